# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""CDR layouts derived from the message definitions: where each field of a message sits.

Nothing here knows a message by heart. A :class:`Layout` is computed from the typestore's
field definitions (``Typestore.fielddefs``: the ``.msg`` files of ``msg/`` and the ROS 2
standard types, :func:`fourws_run.bagfile.typestore`), so a ``.msg`` edit changes every
offset, encoder and decoder built on it, and nothing else needs editing.

Wire format (plain CDR, XCDR1, what rmw_fastrtps and rmw_cyclonedds send for these types): a
4-byte encapsulation header (byte 1 is 1 for little endian, 0 for big endian), then the fields
depth first in definition order, each primitive aligned to its own size (at most 8) relative to
the end of the header; a fixed array ``T[n]`` is ``n`` such values; a string is a ``uint32``
byte count including the terminating NUL, then the bytes and the NUL. Strings are the only
variable-size part of the messages decoded here: once their lengths are known every offset is.
A sequence (``T[]``: a ``uint32`` element count, then the elements) has a layout only once its
count is given too, as encoders give it (:func:`layout` with ``sequences``: a TFMessage of
nine transforms, a MarkerArray of fixed markers); the decoders refuse sequences
(:class:`CodecError`).

* :func:`layout` -- the layout of a message whose strings are given (an encoder's frame id,
  model or law name), with :meth:`Layout.template` (the serialized bytes with every string
  written and every number zero) and :meth:`Layout.runs` (``struct`` formats that write
  consecutive fields in place).
* :class:`Decoder` -- decodes messages of one type into Python values with one
  ``struct.unpack_from``; the layout for each combination of string lengths is derived once
  and kept.
* :func:`decode_many` -- many messages of one layout as numpy arrays (bag loading).
* :func:`stamp_ns` -- a message's time stamp without decoding it (recorder, replay).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from functools import lru_cache
from operator import itemgetter
from typing import Any, Callable, Mapping, Sequence

import numpy as np
from rosbags.interfaces import Nodetype

from fourws_run.bagfile import typestore
from fourws_run.interface import NS_PER_S
from fourws_sim.errors import FourwsError

#: Bytes of the encapsulation header before the CDR payload.
ENCAPSULATION_BYTES = 4
#: Encapsulation header of plain little-endian CDR (what fourws encoders write).
LITTLE_ENDIAN_HEADER = b"\x00\x01\x00\x00"
#: ROS ``builtin_interfaces/Time``: the type of a stamp (:func:`stamp_ns`).
TIME_TYPE = "builtin_interfaces/msg/Time"

#: ``struct`` format character of each primitive ROS type.
PRIMITIVES: dict[str, str] = {
    "bool": "?", "byte": "B", "char": "B", "octet": "B", "uint8": "B", "int8": "b",
    "int16": "h", "uint16": "H", "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q",
    "float32": "f", "float64": "d",
}
_SIZES = {name: struct.calcsize("<" + code) for name, code in PRIMITIVES.items()}
#: :attr:`Slot.type` of a sequence's length field (:func:`layout` with ``sequences``).
SEQUENCE = "sequence"
_STRING_LENGTH = struct.Struct("<I")
_STRING_LENGTH_BE = struct.Struct(">I")
#: Bytes a message may have after its last field (padding to a multiple of 4, which the CDR
#: encapsulation allows); anything longer is not the message.
_MAX_TAIL = 3
#: Distinct string-length combinations a :class:`Decoder` keeps layouts for; a message with
#: yet another combination is still decoded, from a layout derived for it alone.
MAX_LAYOUTS = 256


class CodecError(FourwsError):
    """Bytes that are not a message of the expected type, or a type without a fixed layout."""


@dataclass(frozen=True)
class Slot:
    """One primitive field (or fixed array of primitives, or string) of a serialized message.

    Attributes
    ----------
    name : str
        Dotted path of the field (``"header.stamp.sec"``, ``"pose.covariance"``); elements of
        an array of messages or strings are indexed (``"points[2].x"``).
    type : str
        Primitive ROS type (``"float64"``, ``"uint32"``, ...), ``"string"``, or
        :data:`SEQUENCE` (the ``uint32`` length of a sequence, whose elements follow as
        their own slots: ``"points[0].x"``, a sequence of numbers as one ``"data[]"`` array).
    offset : int
        Byte offset in the serialized message, the encapsulation header included (for a
        string or a sequence: of its ``uint32`` length).
    count : int
        Elements of a fixed array; 0 for a single value.
    length : int
        Strings: bytes after the length field (the text and its NUL); sequences: the element
        count; 0 otherwise.
    """

    name: str
    type: str
    offset: int
    count: int = 0
    length: int = 0

    @property
    def size(self) -> int:
        """Bytes taken (without the alignment padding before it)."""
        if self.type == "string":
            return 4 + self.length
        if self.type == SEQUENCE:
            return 4
        return _SIZES[self.type] * max(self.count, 1)

    @property
    def end(self) -> int:
        """Offset of the first byte after the field."""
        return self.offset + self.size

    @property
    def code(self) -> str:
        """``struct`` format of the field's values (a string: its text without the NUL)."""
        if self.type == "string":
            return f"4x{max(self.length - 1, 0)}s" + ("x" if self.length else "")
        if self.type == SEQUENCE:
            return "4x"
        return f"{self.count}{PRIMITIVES[self.type]}" if self.count else PRIMITIVES[self.type]


class _Stop(Exception):
    """A string whose length is not known yet, at ``offset``."""

    def __init__(self, offset: int) -> None:
        super().__init__(offset)
        self.offset = offset


class _SequenceError(CodecError):
    """A sequence field: the message has no fixed layout from there on."""


def _align(pos: int, size: int) -> int:
    return pos + (-(pos - ENCAPSULATION_BYTES)) % size


def _walk(store: Any, msgtype: str, pos: int, prefix: str,
          string_length: Callable[[str, int], int], slots: list[Slot],
          times: list[str],
          sequence_length: Callable[[str, int], int] | None = None) -> int:
    """Append the slots of ``msgtype`` serialized from ``pos``; return the end position.

    ``string_length(name, offset)`` gives the byte count of a string (with its NUL) whose
    length field is at ``offset``; ``sequence_length(name, offset)`` the element count of a
    sequence whose length field is at ``offset`` (without it a sequence has no layout:
    :class:`_SequenceError`); ``times`` collects the paths of ``builtin_interfaces/Time``
    fields in order.
    """
    try:
        _, fields = store.fielddefs[msgtype]
    except KeyError:
        raise CodecError(f"unknown message type {msgtype!r}") from None
    for name, (kind, detail) in fields:
        full = f"{prefix}{name}"
        if kind == Nodetype.NAME:
            if detail == TIME_TYPE:
                times.append(full)
            pos = _walk(store, detail, pos, f"{full}.", string_length, slots, times,
                        sequence_length)
        elif kind == Nodetype.BASE:
            pos = _primitive(full, detail[0], 0, pos, string_length, slots)
        elif kind == Nodetype.ARRAY:
            (sub_kind, sub_detail), count = detail
            if sub_kind == Nodetype.NAME:
                for i in range(count):
                    if sub_detail == TIME_TYPE:
                        times.append(f"{full}[{i}]")
                    pos = _walk(store, sub_detail, pos, f"{full}[{i}].", string_length, slots,
                                times, sequence_length)
            elif sub_detail[0] == "string":
                for i in range(count):
                    pos = _primitive(f"{full}[{i}]", "string", 0, pos, string_length, slots)
            else:
                pos = _primitive(full, sub_detail[0], int(count), pos, string_length, slots)
        elif kind == Nodetype.SEQUENCE and sequence_length is not None:
            pos = _sequence(store, full, detail[0], pos, string_length, slots, times,
                            sequence_length)
        else:
            raise _SequenceError(f"{msgtype} field {name!r} is a sequence: the message has no "
                                 "fixed layout")
    return pos


def _sequence(store: Any, full: str, element: tuple[Any, Any], pos: int,
              string_length: Callable[[str, int], int], slots: list[Slot], times: list[str],
              sequence_length: Callable[[str, int], int]) -> int:
    """The slots of sequence ``full`` (its ``uint32`` length, then its elements as a fixed
    array of the length ``sequence_length`` gives); returns the end position."""
    pos = _align(pos, 4)
    n = int(sequence_length(full, pos))
    slots.append(Slot(full, SEQUENCE, pos, 0, n))
    pos += 4
    sub_kind, sub_detail = element
    if sub_kind == Nodetype.NAME:
        for i in range(n):
            if sub_detail == TIME_TYPE:
                times.append(f"{full}[{i}]")
            pos = _walk(store, sub_detail, pos, f"{full}[{i}].", string_length, slots, times,
                        sequence_length)
    elif sub_detail[0] == "string":
        for i in range(n):
            pos = _primitive(f"{full}[{i}]", "string", 0, pos, string_length, slots)
    elif n:
        pos = _primitive(full + "[]", sub_detail[0], n, pos, string_length, slots)
    return pos


def _primitive(name: str, type_: str, count: int, pos: int,
               string_length: Callable[[str, int], int], slots: list[Slot]) -> int:
    if type_ == "string":
        pos = _align(pos, 4)
        slot = Slot(name, "string", pos, 0, string_length(name, pos))
    elif type_ in _SIZES:
        slot = Slot(name, type_, _align(pos, _SIZES[type_]), count)
    else:
        raise CodecError(f"field {name!r} has type {type_}, which fourws does not encode")
    slots.append(slot)
    return slot.end


def _store(store: Any) -> Any:
    return typestore() if store is None else store


@dataclass(frozen=True)
class Layout:
    """Where every field of one message sits, its strings' lengths fixed.

    Attributes
    ----------
    msgtype : str
        ``package/msg/Name``.
    slots : tuple of Slot
        Every field, in wire order.
    size : int
        Bytes of the serialized message, the encapsulation header included.
    strings : dict of str to bytes
        Text of each string field (without the NUL) if the layout was made from it
        (:func:`layout`); empty for a layout read from a message's lengths.
    """

    msgtype: str
    slots: tuple[Slot, ...]
    size: int
    strings: Mapping[str, bytes] = field(default_factory=dict)

    def slot(self, name: str) -> Slot:
        """The slot of field ``name``.

        Raises
        ------
        CodecError
            No such field.
        """
        for s in self.slots:
            if s.name == name:
                return s
        raise CodecError(f"{self.msgtype} has no field {name!r}")

    def template(self) -> bytearray:
        """The message serialized little endian with every string written and every number
        zero (the buffer an encoder writes its numbers into).

        Raises
        ------
        CodecError
            The layout was not made from its strings' text.
        """
        buf = bytearray(self.size)
        buf[:ENCAPSULATION_BYTES] = LITTLE_ENDIAN_HEADER
        for s in self.slots:
            if s.type == SEQUENCE:
                _STRING_LENGTH.pack_into(buf, s.offset, s.length)
                continue
            if s.type != "string":
                continue
            if s.name not in self.strings:
                raise CodecError(f"{self.msgtype}: the text of {s.name!r} is not known")
            _STRING_LENGTH.pack_into(buf, s.offset, s.length)
            text = self.strings[s.name]
            buf[s.offset + 4:s.offset + 4 + len(text)] = text
        return buf

    def runs(self, names: Sequence[str], endian: str = "<") -> list[tuple[int, struct.Struct,
                                                                          int, int]]:
        """``struct`` formats that read or write the fields ``names`` in place.

        Fields adjacent in the message (only alignment padding between them) share one format,
        which writes the padding as zeros.

        Parameters
        ----------
        names : sequence of str
            Numeric fields in wire order.
        endian : str
            ``"<"`` or ``">"``.

        Returns
        -------
        list of (offset, struct.Struct, first, stop)
            Each run's byte offset and format, and the slice ``values[first:stop]`` of the
            flattened values (an array contributes its count of values) it takes.

        Raises
        ------
        CodecError
            A name is not a numeric field, or the names are not in wire order.
        """
        index = {s.name: i for i, s in enumerate(self.slots)}
        runs: list[tuple[int, struct.Struct, int, int]] = []
        start_at = prev_index = prev_end = -1
        fmt = ""
        first = value = 0
        for name in names:
            i = index.get(name)
            if i is None or self.slots[i].type in ("string", SEQUENCE):
                raise CodecError(f"{self.msgtype} has no numeric field {name!r}")
            if i <= prev_index:
                raise CodecError(f"{self.msgtype}: fields {list(names)} are not in wire order")
            s = self.slots[i]
            if i != prev_index + 1 and fmt:
                runs.append((start_at, struct.Struct(endian + fmt), first, value))
                fmt = ""
            if not fmt:
                start_at, prev_end, first = s.offset, s.offset, value
            fmt += (f"{s.offset - prev_end}x" if s.offset > prev_end else "") + s.code
            prev_index, prev_end = i, s.end
            value += max(s.count, 1)
        if fmt:
            runs.append((start_at, struct.Struct(endian + fmt), first, value))
        return runs


def layout(msgtype: str, strings: Mapping[str, str] | None = None,
           store: Any = None, *, sequences: Mapping[str, int] | None = None,
           blank_strings: bool = False) -> Layout:
    """The layout of ``msgtype`` with the given text in its string fields and the given
    element counts in its sequences (an encoder's frame ids, a fixed number of transforms or
    markers).

    Parameters
    ----------
    msgtype : str
        ``package/msg/Name`` of a type of ``store``.
    strings : mapping of str to str
        Text of string fields by path (``{"header.frame_id": "base_link"}``,
        ``{"transforms[1].child_frame_id": "FL_steer"}``).
    store : rosbags Typestore, optional
        Default :func:`fourws_run.bagfile.typestore`.
    sequences : mapping of str to int, optional
        Element count of sequence fields by path (``{"transforms": 9}``,
        ``{"markers[0].points": 2}``); a sequence not named is empty. Without it a message
        with a sequence has no layout.
    blank_strings : bool
        String fields not in ``strings`` are empty (else each must be given).

    Raises
    ------
    CodecError
        Unknown type, a sequence field without ``sequences``, a string field without text
        (unless ``blank_strings``), or a text or count given for a field that is not a string
        or a sequence of the message.
    """
    given = {name: text.encode("utf-8") for name, text in (strings or {}).items()}
    counts = dict(sequences or {})
    missing: list[str] = []

    def length(name: str, offset: int) -> int:
        del offset
        if name not in given:
            if blank_strings:
                given[name] = b""
                return 1
            missing.append(name)
            return 1
        return len(given[name]) + 1

    def count(name: str, offset: int) -> int:
        del offset
        n = counts.get(name, 0)
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise CodecError(f"{msgtype}: sequence {name!r} needs a count >= 0, got {n!r}")
        return n

    slots: list[Slot] = []
    times: list[str] = []
    size = _walk(_store(store), msgtype, ENCAPSULATION_BYTES, "", length, slots, times,
                 count if sequences is not None else None)
    if missing:
        raise CodecError(f"{msgtype}: give the text of its string fields {missing}")
    unknown = sorted(set(given) - {s.name for s in slots if s.type == "string"})
    if unknown:
        raise CodecError(f"{msgtype} has no string fields {unknown}")
    unknown = sorted(set(counts) - {s.name for s in slots if s.type == SEQUENCE})
    if unknown:
        raise CodecError(f"{msgtype} has no sequence fields {unknown}")
    return Layout(msgtype, tuple(slots), size, given)


def constants(msgtype: str, store: Any = None) -> dict[str, Any]:
    """The constants a message definition declares (``visualization_msgs/Marker``'s ``ARROW``,
    ``ADD``, ...), by name.

    Raises
    ------
    CodecError
        Unknown type.
    """
    try:
        consts, _ = _store(store).fielddefs[msgtype]
    except KeyError:
        raise CodecError(f"unknown message type {msgtype!r}") from None
    return {name: value for name, _type, value in consts}


def _read_length(data: bytes | memoryview, offset: int, little: bool) -> int:
    if offset + 4 > len(data):
        raise CodecError("the message ends inside a string length")
    fmt = _STRING_LENGTH if little else _STRING_LENGTH_BE
    (n,) = fmt.unpack_from(data, offset)
    if offset + 4 + n > len(data):
        raise CodecError(f"a string of {n} bytes runs past the end of the message")
    return int(n)


def _endian(data: bytes | memoryview) -> bool:
    """True for little endian; raises CodecError if not plain CDR."""
    if len(data) < ENCAPSULATION_BYTES:
        raise CodecError("shorter than the CDR encapsulation header")
    if data[0] != 0 or data[1] > 1:
        raise CodecError(f"not plain CDR (encapsulation {bytes(data[:2]).hex()})")
    return data[1] == 1


@dataclass
class _Block:
    """Adjacent fixed arrays of one numeric type and length: one numpy view of the bytes."""

    offset: int
    dtype: np.dtype
    count: int
    names: list[str]

    @property
    def end(self) -> int:
        return self.offset + self.dtype.itemsize * self.count * len(self.names)


class _Plan:
    """Decoding of one layout: one ``struct`` format over the whole message."""

    __slots__ = ("size", "unpack", "names", "simple", "pick", "array_slices", "strings",
                 "blocks")

    def __init__(self, lay: Layout, little: bool, numpy_arrays: bool) -> None:
        self.size = lay.size
        endian = "<" if little else ">"
        fmt = f"{ENCAPSULATION_BYTES}x"
        pos = ENCAPSULATION_BYTES
        names: list[str] = []
        scalar_at: list[int] = []
        self.array_slices: list[tuple[str, int, int]] = []
        self.strings = [s.name for s in lay.slots if s.type == "string"]
        self.blocks: list[_Block] = []
        n_values = 0
        for s in lay.slots:
            fmt += f"{s.offset - pos}x" if s.offset > pos else ""
            pos = s.end
            if s.count and numpy_arrays:
                fmt += f"{s.size}x"  # read by numpy, not by struct
                dtype = np.dtype(endian + PRIMITIVES[s.type])
                last = self.blocks[-1] if self.blocks else None
                if (last is not None and last.dtype == dtype and last.count == s.count
                        and last.end == s.offset):
                    last.names.append(s.name)
                else:
                    self.blocks.append(_Block(s.offset, dtype, s.count, [s.name]))
                continue
            fmt += s.code
            if s.count:
                self.array_slices.append((s.name, n_values, n_values + s.count))
                n_values += s.count
            else:
                names.append(s.name)
                scalar_at.append(n_values)
                n_values += 1
        self.unpack = struct.Struct(endian + fmt).unpack_from
        self.names = tuple(names)
        self.simple = not self.array_slices
        self.pick: Callable[[tuple[Any, ...]], Any] = (
            (lambda values: ()) if not scalar_at
            else (lambda values, i=scalar_at[0]: (values[i],)) if len(scalar_at) == 1
            else itemgetter(*scalar_at))

    def decode(self, data: bytes | memoryview) -> dict[str, Any]:
        if not 0 <= len(data) - self.size <= _MAX_TAIL:
            raise CodecError(f"{len(data)} bytes, the layout its strings give has {self.size}")
        values = self.unpack(data, 0)
        if self.simple:
            out = dict(zip(self.names, values))
        else:
            out = dict(zip(self.names, self.pick(values)))
            for name, first, stop in self.array_slices:
                out[name] = values[first:stop]
        for name in self.strings:
            out[name] = out[name].decode("utf-8", errors="replace")
        for block in self.blocks:
            rows = np.frombuffer(data, dtype=block.dtype, count=block.count * len(block.names),
                                 offset=block.offset).reshape(len(block.names), block.count)
            for k, name in enumerate(block.names):
                out[name] = rows[k]
        return out


class _Node:
    """Decoder state after some string lengths: the next string's length offset, or the plan."""

    __slots__ = ("lengths", "string_at", "children", "plan")

    def __init__(self, lengths: tuple[int, ...], string_at: int | None,
                 plan: _Plan | None) -> None:
        self.lengths = lengths
        self.string_at = string_at
        self.children: dict[int, _Node] = {}
        self.plan = plan


class Decoder:
    """Decodes serialized messages of one type into a mapping of Python values.

    Keys are the field paths (``"header.stamp.sec"``, ``"fy_n"``); numbers come as Python
    ``int``/``float``/``bool`` (a float64 is copied bit for bit), strings as ``str`` (invalid
    UTF-8 replaced), fixed arrays as tuples or, with ``numpy_arrays``, as read-only numpy
    views of the message bytes (adjacent arrays of one type and length share one buffer).

    The offsets depend only on the lengths of the message's strings (a frame id, a model
    name): the layout for each combination seen is derived once from the definitions and kept
    (up to :data:`MAX_LAYOUTS`).

    Parameters
    ----------
    msgtype : str
        ``package/msg/Name``.
    numpy_arrays : bool
        Fixed arrays of numbers as numpy arrays instead of tuples.
    store : rosbags Typestore, optional
        Default :func:`fourws_run.bagfile.typestore`.

    Raises
    ------
    CodecError
        Unknown type or no fixed layout (a sequence field).
    """

    def __init__(self, msgtype: str, *, numpy_arrays: bool = False, store: Any = None) -> None:
        self.msgtype = msgtype
        self._store = _store(store)
        # a fixed layout for any string lengths, or an error now rather than at a message
        _walk(self._store, msgtype, ENCAPSULATION_BYTES, "", lambda name, offset: 1, [], [])
        self._numpy = numpy_arrays
        self._layouts = 0
        self._roots = (self._node((), False), self._node((), True))

    def _node(self, lengths: tuple[int, ...], little: bool) -> _Node:
        """The decoder state once the first ``len(lengths)`` strings' lengths are known."""
        lay, stop = self._layout(lengths)
        if stop is not None:
            return _Node(lengths, stop, None)
        assert lay is not None
        return _Node(lengths, None, _Plan(lay, little, self._numpy))

    def _layout(self, lengths: tuple[int, ...]) -> tuple[Layout | None, int | None]:
        """(layout, None) if ``lengths`` are all the string lengths, else (None, offset of
        the next string's length)."""
        known = iter(lengths)

        def length(name: str, offset: int) -> int:
            del name
            try:
                return next(known)
            except StopIteration:
                raise _Stop(offset) from None

        slots: list[Slot] = []
        times: list[str] = []
        try:
            size = _walk(self._store, self.msgtype, ENCAPSULATION_BYTES, "", length, slots,
                         times)
        except _Stop as stop:
            return None, stop.offset
        return Layout(self.msgtype, tuple(slots), size), None

    def decode(self, data: bytes | memoryview) -> dict[str, Any]:
        """The fields of one serialized message (see the class description).

        Raises
        ------
        CodecError
            Not plain CDR, or too short for the layout its strings give.
        """
        try:
            if data[0] or data[1] > 1:
                raise CodecError(f"not plain CDR (encapsulation {bytes(data[:2]).hex()})")
            little = data[1] == 1
            node = self._roots[little]
            while node.plan is None:
                (n,) = (_STRING_LENGTH if little else _STRING_LENGTH_BE).unpack_from(
                    data, node.string_at)
                node = node.children.get(n) or self._grow(node, data, little)
            return node.plan.decode(data)
        except CodecError as exc:
            raise CodecError(f"not a {self.msgtype}: {exc}") from None
        except (struct.error, IndexError, ValueError) as exc:
            raise CodecError(f"not a {self.msgtype}: {exc}") from None

    def _grow(self, node: _Node, data: bytes | memoryview, little: bool) -> _Node:
        assert node.string_at is not None
        n = _read_length(data, node.string_at, little)
        child = self._node(node.lengths + (n,), little)
        if self._layouts < MAX_LAYOUTS:
            node.children[n] = child
            self._layouts += 1
        return child

    def layout_of(self, data: bytes | memoryview) -> Layout:
        """The layout of one serialized message (its strings' lengths read from it).

        Raises
        ------
        CodecError
            Not plain CDR, or a string runs past the end.
        """
        little = _endian(data)
        lengths: tuple[int, ...] = ()
        while True:
            lay, stop = self._layout(lengths)
            if lay is not None:
                if lay.size > len(data):
                    raise CodecError(f"not a {self.msgtype}: {len(data)} bytes, the layout "
                                     f"needs {lay.size}")
                return lay
            assert stop is not None
            lengths += (_read_length(data, stop, little),)


def decode_many(msgtype: str, raws: Sequence[bytes], store: Any = None
                ) -> dict[str, np.ndarray] | None:
    """Many serialized messages of one type and one layout as arrays, in one pass.

    Parameters
    ----------
    msgtype : str
        ``package/msg/Name``.
    raws : sequence of bytes
        Serialized messages (at least one).
    store : rosbags Typestore, optional
        Default :func:`fourws_run.bagfile.typestore`.

    Returns
    -------
    dict of str to ndarray or None
        Numeric fields by path (a fixed array of ``n`` as shape ``(N, n)``), strings as
        object arrays; ``None`` if the type has no fixed layout or the messages do not all
        share the first one's encapsulation, size and strings (the caller decodes them one by
        one).
    """
    first = raws[0]
    try:
        lay = Decoder(msgtype, store=store).layout_of(first)
    except CodecError:
        return None
    size = len(first)
    if any(len(r) != size for r in raws):
        return None
    buf = np.frombuffer(b"".join(raws), dtype=np.uint8).reshape(len(raws), size)
    # the header and every string must be the same bytes in every message for the offsets to
    # hold in all of them (each string's length fixes where the next field starts)
    same = [(0, ENCAPSULATION_BYTES)] + [(s.offset, s.end) for s in lay.slots
                                         if s.type == "string"]
    for start, end in same:
        if not np.array_equal(buf[:, start:end], np.broadcast_to(buf[0, start:end],
                                                                 (len(raws), end - start))):
            return None
    endian = "<" if first[1] == 1 else ">"
    numeric = [s for s in lay.slots if s.type != "string"]
    dtype = np.dtype({
        "names": [s.name for s in numeric],
        "formats": [(np.dtype(endian + PRIMITIVES[s.type]), (s.count,)) if s.count
                    else np.dtype(endian + PRIMITIVES[s.type]) for s in numeric],
        "offsets": [s.offset for s in numeric], "itemsize": size})
    rec = buf.view(dtype).reshape(len(raws))
    result: dict[str, np.ndarray] = {s.name: np.array(rec[s.name]) for s in numeric}
    for s in lay.slots:
        if s.type == "string":
            text = bytes(first[s.offset + 4:s.offset + 3 + s.length])
            result[s.name] = np.full(len(raws), text.decode("utf-8", errors="replace"),
                                     dtype=object)
    return result


_STAMP_LE = struct.Struct("<iI")
_STAMP_BE = struct.Struct(">iI")


def stamp_offset(msgtype: str, store: Any = None) -> int | None:
    """Byte offset of the message's stamp: its first ``builtin_interfaces/Time`` field
    (``header.stamp``, ``Clock.clock``) if no string or sequence precedes it (then it is the
    same in every message of the type), or the first element's when the message starts with a
    sequence of messages that start with it (``tf2_msgs/TFMessage``,
    ``visualization_msgs/MarkerArray``: the stamp of their first transform or marker; such a
    message with an empty sequence has none); ``None`` otherwise."""
    location = _stamp_location(msgtype, store)
    return None if location is None else location[0]


def _stamp_location(msgtype: str, store: Any = None) -> tuple[int, int | None] | None:
    """(offset of the stamp, offset of the leading sequence's length or None) -- see
    :func:`stamp_offset`."""
    if store is None:
        return _default_stamp_location(msgtype)

    def length(name: str, offset: int) -> int:
        raise _Stop(offset)

    leading: list[int] = []

    def first_element(name: str, offset: int) -> int:
        # the first sequence, before any other field: its first element's stamp
        if slots or leading:
            raise _Stop(offset)
        leading.append(offset)
        return 1

    slots: list[Slot] = []
    times: list[str] = []
    try:
        _walk(store, msgtype, ENCAPSULATION_BYTES, "", length, slots, times, first_element)
    except (_Stop, _SequenceError):
        pass  # every slot found before the first variable-size field has a fixed offset
    except CodecError:
        return None
    fixed = {s.name: s.offset for s in slots}
    if not times or f"{times[0]}.nanosec" not in fixed:
        return None
    return fixed[f"{times[0]}.sec"], (leading[0] if leading else None)


@lru_cache(maxsize=None)
def _default_stamp_location(msgtype: str) -> tuple[int, int | None] | None:
    return _stamp_location(msgtype, _store(None))


def stamp_ns(data: bytes | memoryview, msgtype: str, store: Any = None) -> int | None:
    """The stamp (:func:`stamp_offset`) of a serialized message in ns, or ``None`` if the type
    has none at a fixed offset or the bytes are too short or not plain CDR.

    Parameters
    ----------
    data : bytes
        The serialized message, encapsulation header included.
    msgtype : str
        Its type, ``package/msg/Name``.
    """
    location = _stamp_location(msgtype, store)
    if location is None:
        return None
    offset, sequence_at = location
    if len(data) < offset + 8 or data[0] != 0 or data[1] > 1:
        return None
    little = data[1] == 1
    if sequence_at is not None and (_STRING_LENGTH if little else _STRING_LENGTH_BE
                                    ).unpack_from(data, sequence_at)[0] == 0:
        return None  # an empty leading sequence: no first element, no stamp
    sec, nanosec = (_STAMP_LE if little else _STAMP_BE).unpack_from(data, offset)
    return int(sec) * NS_PER_S + int(nanosec)


__all__ = ["CodecError", "Decoder", "ENCAPSULATION_BYTES", "LITTLE_ENDIAN_HEADER", "Layout",
           "MAX_LAYOUTS", "PRIMITIVES", "SEQUENCE", "Slot", "TIME_TYPE", "constants",
           "decode_many", "layout", "stamp_ns", "stamp_offset"]
