# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""rosbag2 bags as fourws writes, checks and repairs them (MCAP storage, no rclpy).

A fourws bag is a rosbag2 directory (format version 9): ``metadata.yaml`` and one ``.mcap``
file. rosbags writes ``metadata.yaml`` and the connections (message definitions and type
hashes from :func:`typestore`); the MCAP file itself is written with the ``mcap`` library
(:class:`_McapStorage`), which gives what a recording must be trusted for:

* **checksums**: every chunk carries the CRC-32 of its records and the data section ends with
  the CRC-32 of the whole section; :func:`verify_bag` and the loader check them, so a changed
  byte is an error, never a plausible wrong number;
* **bounded loss**: :meth:`BagWriter.flush` closes the open chunk and hands the file to the OS,
  so a process killed later leaves every message up to that flush in complete chunks; the
  recorder flushes by simulation time, wall time and size (:mod:`fourws_ros.recorder_node`);
* **accounting**: the recorder's final accounting (what each publisher sent and what was
  stored, :mod:`fourws_run.accounting`) goes into ``metadata.yaml`` ``custom_data`` and into
  an MCAP metadata record ``fourws``;
* **repair**: :func:`repair_bag` rebuilds a bag whose writer was killed (no summary, no
  ``metadata.yaml``) from its complete chunks, so rosbags, Foxglove and fourws open it;
* **one writer**: a :class:`BagWriter` holds an exclusive ``flock(2)`` on the bag's
  :data:`LOCK_FILE` from before its MCAP file exists until the bag is closed (the file is
  removed then); the kernel drops the lock when the writer dies, so only a bag still being
  written is locked. :func:`repair_bag` and :func:`verify_bag` refuse a locked bag (the
  repair would rewrite the file under the recorder), naming the writer's process.
"""

from __future__ import annotations

import fcntl
import json
import os
import struct
import time
import zlib
from dataclasses import dataclass, field
from functools import lru_cache
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any, Mapping

import yaml
from mcap.exceptions import McapError
from mcap.records import Channel, DataEnd, Footer, Message, Metadata, Schema
from mcap.stream_reader import CRCValidationError, StreamReader
from mcap.writer import CompressionType, Writer as McapFileWriter
from rosbags.interfaces import (MessageDefinitionFormat, Qos, QosDurability, QosHistory,
                                QosLiveliness, QosReliability, QosTime)
from rosbags.rosbag2 import StoragePlugin, Writer, WriterError
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from fourws_run import interface
from fourws_run.accounting import RunAccount, account_from_messages
from fourws_sim.errors import FourwsError

#: Folder with the fourws ``.msg`` definitions.
MSG_DIR = interface.MSG_DIR
#: rosbag2 metadata format version written.
BAG_VERSION = 9
#: ``custom_data`` keys of ``metadata.yaml`` written by the recorder.
KEY_COMPLETE = "fourws.complete"
KEY_ACCOUNTING = "fourws.accounting"
#: Name of the MCAP metadata record holding the accounting (JSON under key ``accounting``).
MCAP_METADATA = "fourws"
#: A chunk is closed once its records exceed this many bytes (besides the recorder's time-based
#: flushes), bounding what a killed writer can lose.
CHUNK_BYTES = 256 * 1024
#: The file in a bag folder its writer holds locked (with its process id) while it writes.
LOCK_FILE = ".fourws-recording.lock"


class BagError(FourwsError):
    """A bag is missing, unreadable, truncated, corrupt, incomplete, or cannot be written."""


def _fourws_version() -> str:
    try:
        return version("fourws")
    except PackageNotFoundError:
        return "unknown"


# --------------------------------------------------------------------------------------------
# the writer's lock


class _WriterLock:
    """An exclusive ``flock`` on ``folder/LOCK_FILE`` (module docstring).

    Raises
    ------
    BagError
        Another process holds it.
    """

    def __init__(self, folder: Path) -> None:
        self.path = folder / LOCK_FILE
        handle = open(self.path, "a+")  # appending: the holder's process id stays readable
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.close()
            raise BagError(_being_recorded(folder, recording_process(folder))) from None
        handle.truncate(0)
        handle.write(f"{os.getpid()}\n")
        handle.flush()
        self._handle: Any = handle

    def release(self, remove: bool) -> None:
        """Give the lock up; ``remove`` deletes the file first (a closed bag has none)."""
        if self._handle is None:
            return
        if remove:
            self.path.unlink(missing_ok=True)
        fcntl.flock(self._handle, fcntl.LOCK_UN)
        self._handle.close()
        self._handle = None


def recording_process(path: str | Path) -> int | None:
    """The process id of the writer that holds the bag ``path`` locked (0 if its lock file
    does not say), or None when no process writes it (no lock file, or a stale one of a
    killed writer)."""
    lock = Path(path) / LOCK_FILE
    try:
        handle = open(lock)
    except OSError:
        return None
    with handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            text = handle.read(32).strip()
            return int(text) if text.isdigit() else 0
        fcntl.flock(handle, fcntl.LOCK_UN)
    return None


def _being_recorded(path: str | Path, pid: int | None) -> str:
    who = f"process {pid}" if pid else "another process"
    return (f"bag {str(path)!r} is being recorded ({who} holds {LOCK_FILE}); wait until "
            "its recording has ended")


def _refuse_while_recorded(path: str | Path) -> None:
    pid = recording_process(path)
    if pid is not None:
        raise BagError(_being_recorded(path, pid))


# --------------------------------------------------------------------------------------------
# typestore


@lru_cache(maxsize=1)
def typestore() -> Any:
    """Rosbags typestore: ROS 2 (kilted) standard types plus the fourws messages.

    The fourws types are parsed from the text of ``msg/*.msg`` so the bags carry exactly the
    definitions the ROS nodes were built from.

    Returns
    -------
    rosbags.typesys.store.Typestore
    """
    store = get_typestore(Stores.ROS2_KILTED)
    types: dict[str, Any] = {}
    # the legacy package name too, so bags recorded before the rename still decode
    for package in (interface.MSG_PACKAGE, *interface.LEGACY_MSG_PACKAGES):
        for path in sorted(MSG_DIR.glob("*.msg")):
            types.update(get_types_from_msg(path.read_text(), f"{package}/msg/{path.stem}"))
    store.register(types)
    return store


def bag_typestore(schemas: Mapping[str, tuple[str, bytes]]) -> Any:
    """A typestore for decoding one bag: the ROS 2 standard types plus the fourws message
    definitions *the bag carries* (its MCAP schemas), so a bag recorded before a ``.msg`` file
    changed still decodes as it was written. Types the bag has no schema for come from
    :func:`typestore`.
    """
    key = tuple(sorted((name, bytes(data)) for name, (enc, data) in schemas.items()
                       if enc == "ros2msg" and name.startswith(_OWN_PREFIXES)))
    return _bag_typestore(key) if key else typestore()


#: Type name prefixes of the fourws messages, the current package's and the former one's.
_OWN_PREFIXES = tuple(f"{p}/" for p in (interface.MSG_PACKAGE, *interface.LEGACY_MSG_PACKAGES))


@lru_cache(maxsize=16)
def _bag_typestore(key: tuple[tuple[str, bytes], ...]) -> Any:
    store = get_typestore(Stores.ROS2_KILTED)
    own = dict(key)
    types: dict[str, Any] = {}
    for package in (interface.MSG_PACKAGE, *interface.LEGACY_MSG_PACKAGES):
        for path in sorted(MSG_DIR.glob("*.msg")):
            name = f"{package}/msg/{path.stem}"
            if name not in own:
                types.update(get_types_from_msg(path.read_text(), name))
    for name, data in own.items():
        types.update({k: v for k, v in get_types_from_msg(data.decode(), name).items()
                      if k.startswith(_OWN_PREFIXES)})
    store.register(types)
    return store


# --------------------------------------------------------------------------------------------
# writer


class _McapStorage:
    """rosbags storage plugin (its ``StorageWriter`` protocol) on the ``mcap`` library:
    chunk and data-section CRCs, explicit chunk flushes, publisher sequence numbers."""

    def __init__(self, path: Path, compression: Any) -> None:
        del compression  # fourws bags are not compressed (the CRCs cover the raw records)
        self.path = path / f"{path.name}.mcap"
        # held from before the MCAP file exists (rosbags has just made the folder)
        self.lock = _WriterLock(path)
        try:
            self._file = self.path.open("xb")
        except OSError:
            self.lock.release(remove=True)
            raise
        self._mcap = McapFileWriter(self._file, chunk_size=CHUNK_BYTES,
                                    compression=CompressionType.NONE, enable_crcs=True,
                                    enable_data_crcs=True)
        self._mcap.start(profile="ros2", library=f"fourws-{_fourws_version()}")
        self._schemas: dict[str, int] = {}
        self._channels: dict[int, int] = {}
        self.metadata: dict[str, str] = {}

    def add_msgtype(self, connection: Any) -> None:
        encoding = ("ros2msg" if connection.msgdef.format == MessageDefinitionFormat.MSG
                    else "ros2idl")
        self._schemas[connection.msgtype] = self._mcap.register_schema(
            connection.msgtype, encoding, connection.msgdef.data.encode())

    def add_connection(self, connection: Any, offered_qos_profiles: str) -> None:
        self._channels[connection.id] = self._mcap.register_channel(
            connection.topic, connection.ext.serialization_format,
            self._schemas[connection.msgtype],
            {"offered_qos_profiles": offered_qos_profiles,
             "topic_type_hash": connection.digest})

    def write(self, connection: Any, timestamp: int, data: bytes | memoryview,
              sequence: int = 0) -> None:
        self._mcap.add_message(self._channels[connection.id], timestamp, bytes(data),
                               timestamp, sequence)

    def flush(self) -> None:
        self._mcap.flush()

    def close(self, version_: int, metadata: str) -> None:
        del version_
        self._mcap.add_metadata("rosbag2", {"serialized_metadata": metadata})
        if self.metadata:
            self._mcap.add_metadata(MCAP_METADATA, dict(self.metadata))
        self._mcap.finish()
        self._file.flush()
        os.fsync(self._file.fileno())
        self._file.close()

    def abort(self) -> None:
        self._file.close()


class _Writer(Writer):  # type: ignore[misc]
    """rosbags' rosbag2 writer with the MCAP storage of :class:`_McapStorage` (its
    documented ``STORAGE_PLUGINS`` table)."""

    STORAGE_PLUGINS = {StoragePlugin.MCAP: _McapStorage}


class BagWriter:
    """Write a fourws run as a rosbag2 bag (format version 9, MCAP storage, CRCs).

    Use as a context manager::

        with BagWriter("runs/step") as bag:
            bag.write_run_config(config)
            bag.write(interface.STATE, make_message(...), t_ns)

    Connections are added on first use of a topic with its type from
    :data:`fourws_run.interface.TOPIC_TYPES` (other topics need :meth:`add_topic`).
    :meth:`write_raw` takes already serialized CDR bytes so a recorder never deserializes.

    Parameters
    ----------
    path : str or Path
        Bag directory to create; it must not exist.

    Raises
    ------
    BagError
        If ``path`` exists or the bag cannot be created (the message names the cause).
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        try:
            self._writer = _Writer(self.path, version=BAG_VERSION,
                                   storage_plugin=StoragePlugin.MCAP)
        except WriterError as exc:
            raise BagError(f"cannot create bag {str(self.path)!r}: {exc}") from None
        self._connections: dict[str, Any] = {}
        self._open = False
        #: Messages written per topic.
        self.counts: dict[str, int] = {}

    def open(self) -> "BagWriter":
        """Create the bag on disk.

        Raises
        ------
        BagError
            The directory cannot be created (exists, read-only file system, no permission).
        """
        try:
            self._writer.open()
        except (OSError, ValueError) as exc:
            raise BagError(f"cannot create bag {str(self.path)!r}: {_os_reason(exc)}") from None
        self._open = True
        return self

    def set_custom_data(self, key: str, value: str) -> None:
        """A ``custom_data`` entry of ``metadata.yaml`` (written at :meth:`close`)."""
        self._writer.set_custom_data(key, value)

    def set_accounting(self, accounting: Mapping[str, Any], complete: bool) -> None:
        """Record the recorder's accounting in ``metadata.yaml`` and the MCAP file."""
        text = json.dumps(accounting, sort_keys=True)
        self.set_custom_data(KEY_COMPLETE, "true" if complete else "false")
        self.set_custom_data(KEY_ACCOUNTING, text)
        storage = self._writer.storage
        if storage is not None:
            storage.metadata.update({"complete": "true" if complete else "false",
                                     "accounting": text})

    def flush(self) -> None:
        """Close the open chunk and hand everything to the OS (a later kill loses nothing
        written before)."""
        storage = self._writer.storage
        if storage is not None:
            storage.flush()

    def close(self) -> None:
        """Write the summary, the metadata and close the bag (then release its lock)."""
        if self._open:
            self._open = False
            storage = self._writer.storage
            try:
                self._writer.close()
            finally:
                storage.lock.release(remove=True)

    def abort(self) -> None:
        """Close the file without summary or metadata (as a killed writer would leave it:
        the lock file stays, unlocked)."""
        if self._open:
            self._open = False
            storage = self._writer.storage
            self._writer.abort()
            storage.lock.release(remove=False)

    def __enter__(self) -> "BagWriter":
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def add_topic(self, topic: str, msgtype: str | None = None) -> Any:
        """Register ``topic`` (type from :data:`~fourws_run.interface.TOPIC_TYPES` unless
        given); returns the connection. Latched topics record transient-local durability."""
        if topic in self._connections:
            return self._connections[topic]
        if msgtype is None:
            if topic not in interface.TOPIC_TYPES:
                raise BagError(f"topic {topic!r}: unknown type; pass msgtype")
            msgtype = interface.TOPIC_TYPES[topic]
        latched = topic in interface.LATCHED_TOPICS
        durability = QosDurability.TRANSIENT_LOCAL if latched else QosDurability.VOLATILE
        qos = Qos(QosHistory.KEEP_LAST, 1 if latched else 10, QosReliability.RELIABLE,
                  durability, QosTime(0, 0), QosTime(0, 0), QosLiveliness.AUTOMATIC,
                  QosTime(0, 0), False)
        conn = self._writer.add_connection(topic, msgtype, typestore=typestore(),
                                           offered_qos_profiles=[qos])
        self._connections[topic] = conn
        self.counts[topic] = 0
        return conn

    def write(self, topic: str, message: Any, time_ns: int) -> None:
        """Serialize a rosbags message object and write it at log time ``time_ns`` (ns)."""
        conn = self.add_topic(topic)
        data = typestore().serialize_cdr(message, conn.msgtype)
        self.write_raw(topic, data, time_ns)

    def write_raw(self, topic: str, data: bytes | memoryview, time_ns: int,
                  msgtype: str | None = None, sequence: int = 0) -> None:
        """Write serialized CDR bytes of ``topic`` at log time ``time_ns`` (ns); ``sequence``
        is the publisher's sequence number (kept in the MCAP message record)."""
        conn = self._connections.get(topic) or self.add_topic(topic, msgtype)
        writer = self._writer
        writer.storage.write(conn, int(time_ns), data, sequence)
        # rosbags' own bookkeeping for metadata.yaml (what Writer.write does after storage)
        writer.counts[conn.id] += 1
        writer.min_timestamp = min(int(time_ns), writer.min_timestamp)
        writer.max_timestamp = max(int(time_ns), writer.max_timestamp)
        self.counts[topic] += 1

    def write_run_config(self, config: Mapping[str, Any], time_ns: int = 0) -> None:
        """Write the run configuration as JSON on ``/fourws/run_config`` (transient local)."""
        store = typestore()
        msg = store.types["std_msgs/msg/String"](data=json.dumps(config, sort_keys=True))
        self.write(interface.RUN_CONFIG, msg, time_ns)


def _os_reason(exc: BaseException) -> str:
    """A short reason for an OS error (``no space left on device``, ``read-only file
    system``, ...)."""
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror.lower()
    return str(exc) or type(exc).__name__


# --------------------------------------------------------------------------------------------
# reading records (with CRCs), metadata


@dataclass
class RawMessage:
    """One stored message: topic, type, log time (ns), publisher sequence number, CDR bytes."""

    topic: str
    msgtype: str
    log_time_ns: int
    sequence: int
    data: bytes


@dataclass
class McapScan:
    """What a record-by-record pass over an MCAP file found.

    Attributes
    ----------
    messages : list of RawMessage
        Every message of the complete, CRC-checked chunks, in file order.
    schemas : dict of str to (str, bytes)
        Message type -> (encoding, definition).
    channels : dict of str to (str, str, dict)
        Topic -> (message type, serialization format, channel metadata).
    metadata : dict of str to dict
        MCAP metadata records by name.
    complete_file : bool
        The file ended with a summary and footer (its writer closed it).
    damage : str
        Why the pass stopped early ('' if it read to the end): a failed CRC, a truncated
        record, ...
    """

    messages: list[RawMessage] = field(default_factory=list)
    schemas: dict[str, tuple[str, bytes]] = field(default_factory=dict)
    channels: dict[str, tuple[str, str, dict[str, str]]] = field(default_factory=dict)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    complete_file: bool = False
    damage: str = ""

    def counts(self) -> dict[str, int]:
        """Messages per topic."""
        out: dict[str, int] = {}
        for m in self.messages:
            out[m.topic] = out.get(m.topic, 0) + 1
        return out


def mcap_files(path: str | Path) -> list[Path]:
    """The ``.mcap`` file(s) of a bag directory, or ``[path]`` for a file.

    Raises
    ------
    BagError
        The path does not exist or holds no MCAP file.
    """
    path = Path(path)
    if not path.exists():
        raise BagError(f"bag {str(path)!r} does not exist")
    if path.is_dir():
        files = sorted(path.glob("*.mcap"))
        if not files:
            raise BagError(f"bag {str(path)!r} holds no .mcap file")
        return files
    return [path]


def scan_mcap(file: Path) -> McapScan:
    """Read an MCAP file record by record with CRC validation, up to its end or its first
    damage (a killed writer's unfinished chunk, a changed byte); messages of a damaged chunk
    are never returned."""
    scan = McapScan()
    schema_names: dict[int, str] = {}
    channels: dict[int, tuple[str, str]] = {}
    try:
        with open(file, "rb") as stream:
            for record in StreamReader(stream, validate_crcs=True).records:
                if isinstance(record, Schema):
                    schema_names[record.id] = record.name
                    scan.schemas[record.name] = (record.encoding, bytes(record.data))
                elif isinstance(record, Channel):
                    msgtype = schema_names.get(record.schema_id, "")
                    channels[record.id] = (record.topic, msgtype)
                    scan.channels[record.topic] = (msgtype, record.message_encoding,
                                                   dict(record.metadata))
                elif isinstance(record, Message) and record.channel_id in channels:
                    topic, msgtype = channels[record.channel_id]
                    scan.messages.append(RawMessage(topic, msgtype, record.log_time,
                                                    record.sequence, bytes(record.data)))
                elif isinstance(record, Metadata):
                    scan.metadata[record.name] = dict(record.metadata)
                elif isinstance(record, Footer):
                    scan.complete_file = True
                elif isinstance(record, DataEnd):
                    pass
    except (McapError, OSError, EOFError, ValueError, KeyError, IndexError, OverflowError,
            UnicodeDecodeError, MemoryError, struct.error, zlib.error, AssertionError,
            TypeError) as exc:  # what the MCAP reader raises on a damaged file
        if isinstance(exc, CRCValidationError):
            scan.damage = f"checksum (CRC) mismatch, the data changed after writing: {exc}"
        else:
            scan.damage = f"truncated or corrupt ({type(exc).__name__}: {exc})"
    return scan


def read_metadata(path: str | Path) -> dict[str, Any] | None:
    """``rosbag2_bagfile_information`` of a bag directory's ``metadata.yaml`` (None if the bag
    has none, e.g. its recorder was killed).

    Raises
    ------
    BagError
        ``metadata.yaml`` exists but is not a rosbag2 metadata file.
    """
    meta = Path(path) / "metadata.yaml"
    if not Path(path).is_dir() or not meta.is_file():
        return None
    try:
        info = yaml.safe_load(meta.read_text())["rosbag2_bagfile_information"]
    except (yaml.YAMLError, KeyError, TypeError, UnicodeDecodeError, OSError) as exc:
        raise BagError(f"bag {str(path)!r}: unreadable metadata.yaml ({exc})") from None
    if not isinstance(info, dict):
        raise BagError(f"bag {str(path)!r}: metadata.yaml is not a rosbag2 metadata file")
    return info


def metadata_counts(info: Mapping[str, Any]) -> dict[str, int]:
    """Messages per topic as ``metadata.yaml`` states them."""
    return {t["topic_metadata"]["name"]: int(t["message_count"])
            for t in info.get("topics_with_message_count", []) or []}


# --------------------------------------------------------------------------------------------
# verification


@dataclass
class BagCheck:
    """The verdict on a bag: readable, checksums, and whether it holds the whole run.

    Attributes
    ----------
    path : str
    counts : dict of str to int
        Messages per topic found in the CRC-checked chunks.
    complete : bool or None
        True: the recorder verified every published message stored (its accounting, cross
        checked here); False: something is missing or damaged (``problems`` says what);
        None: the bag carries no accounting (written by an older fourws or another tool).
    problems : list of str
        One line per problem (damage, CRC failure, missing messages per topic).
    accounting : dict
        The recorder's accounting (``fourws_run.accounting.RunAccount.to_dict``), if any.
    """

    path: str
    counts: dict[str, int]
    complete: bool | None
    problems: list[str] = field(default_factory=list)
    accounting: dict[str, Any] = field(default_factory=dict)
    #: The message definitions the bag carries: type -> (encoding, definition).
    schemas: dict[str, tuple[str, bytes]] = field(default_factory=dict)

    def summary(self) -> str:
        """One line: complete, unverified, or the problems."""
        if self.complete:
            return f"{self.path}: complete ({sum(self.counts.values())} messages, checksums ok)"
        if self.complete is None and not self.problems:
            return (f"{self.path}: readable, checksums ok, completeness unknown (the bag "
                    "carries no recording accounting)")
        return f"{self.path}: INCOMPLETE: " + "; ".join(self.problems)


def verify_bag(path: str | Path) -> BagCheck:
    """Check a bag: CRCs of every chunk and of the data section, the file's summary, the
    metadata's counts, and the recorder's accounting against what is really in the file.

    Raises
    ------
    BagError
        The bag does not exist, is not a bag, or is being recorded (:data:`LOCK_FILE`).
    """
    _refuse_while_recorded(path)
    return read_bag(path)[1]


def read_bag(path: str | Path) -> tuple[list[RawMessage], BagCheck]:
    """Every message of a bag's complete, CRC-checked chunks and the verdict on the bag
    (:func:`verify_bag`), in one pass over the file.

    Raises
    ------
    BagError
        The bag does not exist or is not a bag.
    """
    files = mcap_files(path)
    problems: list[str] = []
    messages: list[RawMessage] = []
    mcap_meta: dict[str, dict[str, str]] = {}
    schemas: dict[str, tuple[str, bytes]] = {}
    for file in files:
        scan = scan_mcap(file)
        messages.extend(scan.messages)
        mcap_meta.update(scan.metadata)
        schemas.update(scan.schemas)
        if scan.damage:
            problems.append(f"{file.name} damaged after {len(scan.messages)} messages "
                            f"({scan.damage})")
        elif not scan.complete_file and recording_process(path) is not None:
            problems.append(f"{file.name} is being recorded: not closed yet")
        elif not scan.complete_file:
            problems.append(f"{file.name} was not closed (no summary): its writer stopped "
                            "early; `fourws bag repair` rebuilds it")
    counts: dict[str, int] = {}
    for m in messages:
        counts[m.topic] = counts.get(m.topic, 0) + 1
    info = read_metadata(path) if Path(path).is_dir() else None
    if Path(path).is_dir() and info is None:
        problems.append("no metadata.yaml (the recorder did not close the bag); "
                        "`fourws bag repair` writes it")
    if info is not None:
        try:
            stated = metadata_counts(info)
        except (KeyError, TypeError, ValueError, OverflowError, AttributeError) as exc:
            # a damaged metadata.yaml is a damaged bag, not a crash of the reader
            problems.append(f"metadata.yaml does not list its topics as rosbag2 does "
                            f"({type(exc).__name__}: {exc})")
            stated = {}
        for topic, n in stated.items():
            if counts.get(topic, 0) != n:
                problems.append(f"{topic}: metadata.yaml says {n} messages, the file holds "
                                f"{counts.get(topic, 0)}")
    custom = (info or {}).get("custom_data") or {}
    if not isinstance(custom, Mapping):
        problems.append("metadata.yaml: custom_data is not a mapping")
        custom = {}
    text = custom.get(KEY_ACCOUNTING) or mcap_meta.get(MCAP_METADATA, {}).get("accounting")
    complete: bool | None = None
    accounting: dict[str, Any] = {}
    if text:
        try:
            accounting = json.loads(text)
            account = RunAccount.from_dict(accounting)
        except (ValueError, TypeError, KeyError) as exc:
            problems.append(f"unreadable recording accounting ({exc})")
        else:
            problems.extend(account.problems())
            for topic, entry in account.topics.items():
                if counts.get(topic, 0) != entry.stored:
                    problems.append(f"{topic}: the recorder stored {entry.stored} messages, "
                                    f"the file holds {counts.get(topic, 0)}")
            complete = not problems
    if problems:
        complete = False
    return messages, BagCheck(str(path), counts, complete, problems, accounting, schemas)


# --------------------------------------------------------------------------------------------
# repair


@dataclass
class RepairResult:
    """What :func:`repair_bag` did."""

    path: str
    recovered: dict[str, int]
    damage: str
    backup: str
    check: BagCheck


def repair_bag(path: str | Path) -> RepairResult:
    """Rebuild a bag whose writer was killed: keep every message of the complete, CRC-checked
    chunks, write a new MCAP file with summary and CRCs and a ``metadata.yaml``.

    The original file is kept beside as ``<name>.mcap.damaged``. The accounting of the
    recovered bag is recomputed from the final status messages it holds
    (:func:`fourws_run.accounting.account_from_messages`), so a bag is called complete only if
    its publishers' final counts are inside it and match.

    Raises
    ------
    BagError
        Not a bag directory, being recorded (:data:`LOCK_FILE`), nothing recoverable, or the
        new files cannot be written.
    """
    path = Path(path)
    files = mcap_files(path)
    if not path.is_dir() or len(files) != 1:
        raise BagError(f"bag {str(path)!r}: repair needs a bag directory with one .mcap file")
    # held for the whole repair: no writer and no second repair meanwhile
    try:
        lock = _WriterLock(path)
    except OSError as exc:
        raise BagError(f"bag {str(path)!r}: cannot lock it for the repair "
                       f"({_os_reason(exc)})") from None
    try:
        return _repair_locked(path, files[0])
    finally:
        lock.release(remove=True)  # a killed writer's stale lock file goes too


def _repair_locked(path: Path, source: Path) -> RepairResult:
    scan = scan_mcap(source)
    if not scan.messages:
        raise BagError(f"bag {str(path)!r}: nothing recoverable "
                       f"({scan.damage or 'no complete chunk'})")
    store = typestore()
    unknown = sorted({m.msgtype for m in scan.messages if m.msgtype not in store.types})
    if unknown:
        raise BagError(f"bag {str(path)!r}: unknown message types {', '.join(unknown)}")
    account = account_from_messages(scan.messages, bag_typestore(scan.schemas))
    tmp_dir = path.parent / f".{path.name}.repair-{os.getpid()}-{int(time.time())}"
    try:
        writer = BagWriter(tmp_dir).open()
        for m in sorted(scan.messages, key=lambda m: m.log_time_ns):
            writer.write_raw(m.topic, m.data, m.log_time_ns, m.msgtype, m.sequence)
        writer.set_accounting(account.to_dict(), account.complete)
        writer.set_custom_data("fourws.repaired_from", source.name)
        writer.close()
        backup = source.with_name(source.name + ".damaged")
        os.replace(source, backup)
        new_file = next(tmp_dir.glob("*.mcap"))
        os.replace(new_file, path / source.name)
        meta = (tmp_dir / "metadata.yaml").read_text()
        # the new MCAP file took the bag's own file name
        meta = meta.replace(new_file.name, source.name)
        (path / "metadata.yaml.tmp").write_text(meta)
        os.replace(path / "metadata.yaml.tmp", path / "metadata.yaml")
    except OSError as exc:
        raise BagError(f"bag {str(path)!r}: cannot write the repaired bag "
                       f"({_os_reason(exc)})") from None
    finally:
        for leftover in tmp_dir.glob("*") if tmp_dir.exists() else ():
            leftover.unlink()
        if tmp_dir.exists():
            tmp_dir.rmdir()
    # read_bag, not verify_bag: this process holds the lock
    return RepairResult(str(path), scan.counts(), scan.damage, str(backup), read_bag(path)[1])


__all__ = ["BAG_VERSION", "BagCheck", "BagError", "BagWriter", "CHUNK_BYTES", "KEY_ACCOUNTING",
           "KEY_COMPLETE", "LOCK_FILE", "MSG_DIR", "McapScan", "RawMessage", "RepairResult",
           "bag_typestore", "mcap_files", "metadata_counts", "read_bag", "read_metadata",
           "recording_process", "repair_bag", "scan_mcap", "typestore", "verify_bag"]
