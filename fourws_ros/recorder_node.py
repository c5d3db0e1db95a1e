# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Recorder node: writes the run's topics to a rosbag2 bag (MCAP) and accounts for every message.

What it stores
--------------
Only messages of the run's own publishers: for each topic the roles that may publish it are
:data:`fourws_run.interface.WRITER_ROLES`, and the node name of each role is a parameter
(``simulator_node``, ``maneuver_node``, ``controller_node``, ``launcher_node``). Every message
arrives with its publisher's identity and publication sequence number (rclpy message info);
the publisher is looked up in the ROS graph. A message from anyone else is not stored but
counted as foreign (with the publishing node's name), so a rogue node on the run's domain
cannot put data into the bag. Messages are written as the raw CDR bytes received, never
deserialized; the publisher's sequence number is kept in each MCAP message record.

Accounting and completeness
---------------------------
:class:`fourws_run.accounting.Ledger` keeps, per topic and publisher, what was stored and which
sequence numbers never arrived; the simulator's and the maneuver's status messages bring their
own published counts, the final ones when the run ends. The recorder publishes its progress
and accounting on ``/fourws/recorder_status`` (the simulator's lockstep flow control reads the
stored counts) when it stored something, and at least every ``STATUS_HEARTBEAT_S`` until the
bag is closed. Once the simulator's final status is in and every expected message is stored
(``complete``), it writes the accounting into the bag (``metadata.yaml`` ``custom_data``
``fourws.complete`` / ``fourws.accounting`` and an MCAP metadata record), closes the bag and
exits (``close_when_complete``). On SIGINT/SIGTERM before that it drains what DDS still holds
for ``drain_quiet_s``, closes the bag with the accounting it has (``fourws.complete: false``
and what is missing) and exits with code 4.

Bag timestamps
--------------
Each message is logged at its ``header.stamp`` (the clock's stamp for ``/clock``): simulation
time, in both clock modes; messages without a stamp (configurations) take the latest stamp
seen.

Durability
----------
The open MCAP chunk is closed and handed to the OS every ``flush_period_s`` of simulation time
or of wall time, whichever comes first, and whenever it exceeds
:data:`fourws_run.bagfile.CHUNK_BYTES`; a recorder killed later leaves every message up to the
last flush in complete, CRC-checked chunks (``fourws bag repair`` rebuilds the bag). In
lockstep the simulator cannot run further than the flow-control window ahead, so a killed
recorder loses at most that window plus one flush period of data. A tick held for a recorder
that stays behind (stopped, starved, a slow disk) fails the run after the simulator's
``recorder_timeout_s`` of wall time, naming the recorder.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any, Callable

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
from rclpy.clock import Clock, ClockType
from rclpy.serialization import deserialize_message

from fourws_ros import peers, topics
from fourws_ros.identity import (MAX_HELD, UNIDENTIFIED_AFTER_S, PublisherNames, drain,
                                 publisher_gid)
from fourws_ros.node_base import FourwsNode
from fourws_ros.runtime import EXIT_INCOMPLETE, EXIT_PEERS, SPIN_TIMEOUT_S, run_node
from fourws_run.accounting import REPORTING_ROLES, Ledger
from fourws_run.bagfile import BagError, BagWriter
from fourws_run.cdr import stamp_ns
from fourws_sim.errors import ParameterError

#: The recorder reports its progress at least every this many messages taken (and after a
#: batch, and on a timer).
STATUS_EVERY = 20
#: Wall period of the recorder status and the pending-publisher lookups, s.
STATUS_PERIOD_S = 0.1
#: Until the bag is closed a status goes out at least this often (wall), even with nothing new
#: stored: the status topic is volatile, and a reader that matched after the last status
#: (the simulator, whose start waits for a first one) would otherwise wait for the next
#: message stored, which before the start never comes (a run stalled at t = 0), s.
STATUS_HEARTBEAT_S = 0.5
# A publisher the ROS graph cannot name within UNIDENTIFIED_AFTER_S (wall time) is foreign;
# MAX_HELD messages are kept per publisher meanwhile (fourws_ros.identity: one rule for the
# nodes that take messages by publisher).
#: Once every writer has reported its final counts, a bag still incomplete with nothing held
#: for identification and nothing received for this long (wall time) never completes: what
#: is missing was lost (a reliable writer delivers what it has within a fraction of that), so
#: the recorder closes it incomplete and says what is missing instead of waiting, s.
INCOMPLETE_AFTER_END_S = 10.0

_NS_PER_S = 1_000_000_000
#: Topics whose status messages carry a publisher's counts.
_REPORT_TOPICS = (topics.SIM_STATUS, topics.MANEUVER_STATUS)


class RecorderNode(FourwsNode):
    """Records and accounts for the run's topics (see module docstring).

    Parameters (ROS)
    ----------------
    bag_path : str
        Bag directory to create (must not exist). Read-only.
    topics : list of str
        Topics to record (default: every graph topic but ``/clock``). Read-only.
    simulator_node, maneuver_node, controller_node, launcher_node : str
        ROS node name of each role (who may publish what).
    flush_period_s : float
        Simulation- and wall-time period of chunk flushes (SIGKILL loses at most this), s.
    drain_quiet_s : float
        On SIGINT/SIGTERM: stop draining once no message arrived for this long, s.
    close_when_complete : bool
        Close the bag and exit once the run ended and every message is stored.
    """

    #: run_node: this node needs message info (publisher identity), so it spins the lean
    #: executor (fourws_ros.lean_executor; the events executor does not deliver it).
    needs_message_info = True

    def __init__(self) -> None:
        super().__init__("fourws_recorder")
        ro = dict(read_only=True)
        self.declare_parameter("bag_path", "", ParameterDescriptor(
            description="bag directory to create (rosbag2, MCAP storage)", **ro))
        self.declare_parameter("topics", list(topics.RECORDED_TOPICS), ParameterDescriptor(
            type=ParameterType.PARAMETER_STRING_ARRAY,
            description="topics to record (graph topics of fourws_run.interface)", **ro))
        for role in (topics.Role.SIMULATOR, topics.Role.MANEUVER, topics.Role.CONTROLLER,
                     topics.Role.LAUNCHER):
            self.declare_parameter(f"{role.value}_node", topics.NODE_NAMES[role],
                                   ParameterDescriptor(
                                       description=f"ROS node name of the run's {role.value}",
                                       **ro))
        self.declare_parameter("flush_period_s", 0.5, ParameterDescriptor(
            description="simulation- and wall-time period of MCAP chunk flushes, s (a killed "
                        "recorder loses at most this)",
            floating_point_range=[FloatingPointRange(from_value=0.01, to_value=60.0)], **ro))
        self.declare_parameter("drain_quiet_s", 0.3, ParameterDescriptor(
            description="on SIGINT/SIGTERM: stop draining once no message arrived for this "
                        "long, s",
            floating_point_range=[FloatingPointRange(from_value=0.01, to_value=10.0)]))
        self.declare_parameter("close_when_complete", True, ParameterDescriptor(
            description="close the bag and exit once the run ended and every message is "
                        "stored"))
        self.declare_parameter("maneuver_reports", True, ParameterDescriptor(
            description="the maneuver role's node reports its counts in ManeuverStatus (false: "
                        "a user's driver, counted by sequence numbers)", **ro))
        self.declare_parameter("startup_timeout_s", peers.STARTUP_TIMEOUT_S, ParameterDescriptor(
            description="wall time to wait for the simulator's states before giving up (the "
                        "bag is closed empty, naming what is missing), s (0: wait forever)",
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=86400.0)], **ro))

        path = str(self.get_parameter("bag_path").value)
        if not path:
            raise ParameterError("bag_path", "must name the bag directory to create")
        wanted = list(dict.fromkeys(self.get_parameter("topics").value))
        unknown = [t for t in wanted if t not in topics.TOPIC_TYPES]
        if unknown:
            raise ParameterError("topics", f"unknown topic {unknown[0]!r}; valid: "
                                 f"{', '.join(topics.RECORDED_TOPICS)}")
        if topics.RECORDER_STATUS in wanted:
            raise ParameterError("topics", f"{topics.RECORDER_STATUS} is the recorder's own")
        writers = {role: str(self.get_parameter(f"{role.value}_node").value)
                   for role in (topics.Role.SIMULATOR, topics.Role.MANEUVER,
                                topics.Role.CONTROLLER, topics.Role.LAUNCHER)}
        try:
            self.bag = BagWriter(Path(path)).open()
        except BagError as exc:
            raise ParameterError("bag_path", str(exc)) from None
        self.recorded = wanted
        reporting = dict(REPORTING_ROLES)
        if not bool(self.get_parameter("maneuver_reports").value):
            reporting.pop(topics.Role.MANEUVER)
        self.ledger = Ledger(wanted, writers, reporting)
        self.closed = False
        self._gave_up = ""
        self._failed = False
        self.finished = False  # run_node: stop spinning
        self.stop_reason = ""
        self._flush_ns = int(float(self.get_parameter("flush_period_s").value) * _NS_PER_S)
        self._flush_wall_s = float(self.get_parameter("flush_period_s").value)
        self._flushed_ns = 0
        self._flushed_wall = time.monotonic()
        self._last_stamp_ns = 0
        self._last_rx = time.monotonic()
        self._names = PublisherNames(self)
        self._pending: dict[bytes, tuple[float, list[tuple[str, bytes, int]]]] = {}
        self._status_due = False
        self._status_at = 0.0
        self._unreported = 0
        self._status_pub = self.create_publisher(
            topics.message_class(topics.RECORDER_STATUS), topics.RECORDER_STATUS,
            topics.STATUS_QOS)
        self._status_msg = topics.message_class(topics.RECORDER_STATUS)()
        self._status_msg.bag_path = str(self.bag.path)
        self._status_msg.topics = list(wanted)
        subscribed = list(wanted) + [t for t in _REPORT_TOPICS if t not in wanted]
        self._subs: dict[str, Any] = {}
        for t in subscribed:
            self._subs[t] = self.create_subscription(
                topics.message_class(t), t, self._make_callback(t),
                topics.READ_QOS[t],
                raw=True)
        self.peers = peers.PeerWatch(self, float(self.get_parameter("startup_timeout_s").value))
        if topics.STATE in self._subs:
            self.peers.need_publishers(self._subs[topics.STATE], topics.STATE)
        self._timer = self.create_timer(STATUS_PERIOD_S, self._tick, clock=_steady_clock())
        self._names.refresh_changed(self._subs)
        self.get_logger().info(f"recording {len(wanted)} topics to {path}")
        self._publish_status()

    # ------------------------------------------------------------------ messages
    def _make_callback(self, topic: str) -> Callable[[bytes, Any], None]:
        msgtype = topics.message_class(topic)

        def receive(data: bytes, info: Any) -> None:
            gid = publisher_gid(info)
            seq = info.get("publication_sequence_number") or 0
            # a publisher with messages waiting to be identified keeps its order: behind them
            node = None if gid in self._pending else self._names.name(topic, gid)
            if node is None:
                self._hold(gid, topic, data, seq)
            else:
                self._take(topic, node, data, seq)

        def callback(data: bytes, info: Any) -> None:
            # the rest of this topic's queue is taken here: a recorder that fell behind
            # catches up at the speed of writing, not of the executor
            self._last_rx = time.monotonic()
            receive(data, info)
            more = drain(self._subs[topic], msgtype, True, receive, topics.STREAM_DEPTH)
            # report often enough that the simulator's flow window never waits on a report:
            # after a batch (the recorder was behind) or every STATUS_EVERY messages
            self._unreported += 1 + more
            if more or self._unreported >= STATUS_EVERY:
                self._publish_status()

        return callback

    def _take(self, topic: str, node: str, data: bytes, seq: int) -> None:
        if topic in _REPORT_TOPICS and self.ledger.is_legit(topic, node):
            self._read_report(topic, node, data)
        if topic not in self.ledger.topics:
            return  # subscribed for the accounting only
        if not self.ledger.on_message(topic, node, seq):
            return
        t_ns = (stamp_ns(data, topics.TOPIC_TYPES[topic]) if topic not in topics.LATCHED_TOPICS
                else None)
        if t_ns is None:
            t_ns = self._last_stamp_ns
        elif t_ns > self._last_stamp_ns:
            self._last_stamp_ns = t_ns
        if self._failed:
            return
        try:
            self.bag.write_raw(topic, data, t_ns, topics.TOPIC_TYPES[topic], seq)
            if (self._last_stamp_ns - self._flushed_ns >= self._flush_ns
                    or self._last_rx - self._flushed_wall >= self._flush_wall_s):
                self._flush()
        except OSError as exc:
            self._fail(exc)
            return
        self._status_due = True
        if topic in _REPORT_TOPICS and self.ledger.ended:
            # a writer's final report is itself recorded: the bag is complete only once it is
            # stored, here, not at its reading above (the next tick would close it, up to
            # STATUS_PERIOD_S later, and every node waits for that close to leave)
            self._check_complete()

    def _fail(self, exc: OSError) -> None:
        """The bag cannot be written (disk full, file system gone read-only): stop with the
        reason; what the last flush put on disk stays readable (`fourws bag repair`)."""
        self._failed = True
        self.closed = True
        self.stop_reason = f"cannot write the bag {self.bag.path}: {exc.strerror or exc}"
        self.exit_code = EXIT_INCOMPLETE
        self.finished = True
        self.get_logger().error(self.stop_reason)
        try:
            self.bag.abort()
        except OSError:
            pass

    def _read_report(self, topic: str, node: str, data: bytes) -> None:
        try:
            msg = deserialize_message(data, topics.message_class(topic))
        except Exception as exc:  # noqa: BLE001 - rclpy raises several types on bad bytes
            self.get_logger().error(f"unreadable {topic} from {node}: {exc}")
            return
        counts = dict(zip(msg.published_topics, (int(c) for c in msg.published_counts)))
        if topic == topics.SIM_STATUS:
            self.ledger.on_report(node, counts, bool(msg.final), int(msg.commands_accepted))
        else:
            self.ledger.on_report(node, counts, bool(msg.done))
        self._check_complete()

    # ------------------------------------------------------------------ publisher identity
    def _hold(self, gid: bytes, topic: str, data: bytes, seq: int) -> None:
        since, held = self._pending.setdefault(gid, (time.monotonic(), []))
        if len(held) < MAX_HELD:
            held.append((topic, data, seq))
        else:
            self.ledger.on_message(topic, "", seq)  # counted foreign: unidentifiable

    def _resolve_pending(self, final: bool = False) -> None:
        """Store or count the messages of publishers identified meanwhile; those still
        unknown after :data:`UNIDENTIFIED_AFTER_S` (or at ``final``, the bag closing) are
        foreign."""
        for gid, (since, held) in list(self._pending.items()):
            node = None
            for topic in {t for t, _, _ in held}:
                node = self._names.name(topic, gid) or node
            if node is None and not final and time.monotonic() - since < UNIDENTIFIED_AFTER_S:
                continue
            del self._pending[gid]
            for topic, data, seq in held:
                self._take(topic, node or "", data, seq)

    # ------------------------------------------------------------------ progress
    def _tick(self) -> None:
        self._check_peers()
        self._names.refresh_changed(self._subs)
        if self._pending:
            self._resolve_pending()
        if not self.closed and (self._status_due or time.monotonic() - self._status_at
                                >= STATUS_HEARTBEAT_S):
            self._publish_status()
        if not self.closed and time.monotonic() - self._flushed_wall >= self._flush_wall_s:
            self._flush()
        self._check_complete()

    def _check_peers(self) -> None:
        """A graph that did not come together, or whose simulator left before its final
        status: close the bag with what it holds (incomplete) and stop, saying why."""
        if self.closed or self.ledger.ended or self._gave_up:
            return
        why = (self.peers.check_startup() if not self.peers.ready()
               else self.peers.gone())
        if not why:
            return
        # on_shutdown drains what is still queued, then closes the bag (exit code 4 when it
        # is incomplete, as it is: the run did not end)
        self.get_logger().error(why)
        self._gave_up = why
        self.exit_code = EXIT_PEERS
        self.finished = True

    def _flush(self) -> None:
        if self._failed:
            return
        try:
            self.bag.flush()
        except OSError as exc:
            self._fail(exc)
            return
        self._flushed_ns = self._last_stamp_ns
        self._flushed_wall = time.monotonic()

    def _publish_status(self) -> None:
        self._status_due = False
        self._status_at = time.monotonic()
        self._unreported = 0
        account = self.ledger.account()
        msg = self._status_msg
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(self._last_stamp_ns, _NS_PER_S)
        entries = [account.topics[t] for t in self.recorded]
        msg.stored = [e.stored for e in entries]
        msg.expected = [e.expected or 0 for e in entries]
        msg.expected_known = [e.expected is not None for e in entries]
        msg.foreign = [e.foreign for e in entries]
        msg.gaps = [e.gaps for e in entries]
        problems = account.problems()
        msg.complete = not problems
        msg.closed = self.closed
        msg.detail = "complete" if not problems else problems[0]
        self._status_pub.publish(msg)

    def _check_complete(self) -> None:
        if self.closed or not self.ledger.ended:
            return
        account = self.ledger.account()
        if account.complete and bool(self.get_parameter("close_when_complete").value):
            self._close()
            self.finished = True
        elif (not account.complete and not self._pending
              and time.monotonic() - self._last_rx > INCOMPLETE_AFTER_END_S):
            why = (f"every writer reported its final counts, and {account.summary()} after "
                   f"{INCOMPLETE_AFTER_END_S:g} s without a message")
            self.get_logger().error(why)
            self._gave_up = why
            self._close()
            self.finished = True

    def _close(self) -> None:
        """Write the accounting, close the bag, report."""
        if self.closed:
            return
        account = self.ledger.account()
        self.bag.set_accounting(account.to_dict(), account.complete)
        try:
            self.bag.close()
        except OSError as exc:
            self._fail(exc)
            return
        self.closed = True
        if not account.complete:
            self.stop_reason = f"bag closed incomplete: {account.summary()}"
            self.exit_code = EXIT_INCOMPLETE
        if self._gave_up:
            self.stop_reason = f"{self._gave_up}; {self.stop_reason}".rstrip("; ")
        self._publish_status()
        total = sum(self.bag.counts.values())
        summary = ", ".join(f"{t} {n}" for t, n in self.bag.counts.items())
        foreign = sum(account.foreign_publishers.values())
        print(f"[fourws_recorder] closed {self.bag.path}: {total} messages ({summary}); "
              f"{account.summary()}"
              + (f"; {foreign} foreign messages not stored" if foreign else ""),
              file=sys.stderr, flush=True)

    def on_shutdown(self, executor: Any) -> None:
        """Drain what DDS still holds for us, then close the bag with the accounting."""
        if not self.closed:
            quiet = float(self.get_parameter("drain_quiet_s").value)
            start = self._last_rx = time.monotonic()
            while (not self.closed and time.monotonic() - self._last_rx < quiet
                   and time.monotonic() - start < 30.0):
                executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)
            if self._pending:
                self._resolve_pending(final=True)
        self._close()


def _steady_clock() -> Any:
    return Clock(clock_type=ClockType.STEADY_TIME)


def main(args: list[str] | None = None) -> int:
    """Console entry point ``recorder``."""
    return run_node(RecorderNode, args, name="fourws_recorder")


if __name__ == "__main__":
    sys.exit(main())
