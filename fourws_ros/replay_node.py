# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Replay node: plays a recorded bag back into the graph.

Two modes (parameter ``mode``):

``timed``
    Publishes the chosen topics at their recorded times (the bag's log times, which the
    fourws recorder sets to the simulation time of each message), scaled by ``rate`` (2.0 =
    twice as fast), and ``/clock`` with the bag time when ``publish_clock`` is true so nodes
    running with ``use_sim_time`` follow the bag's clock.
``answer``
    Lockstep replay: for every ``VehicleState`` a running simulator publishes, publishes the
    recorded messages of the chosen topics whose stamp equals the state's stamp. This is how a
    recorded driver input drives a new lockstep run (e.g. with another controller) in place of
    the maneuver node: ``topics: [/fourws/driver_input]`` (``fourws_ros.graph_run.run_graph``
    with ``replay_driver_from``). Like the maneuver node it publishes ``ManeuverStatus``, with
    ``done`` at the first state after the last recorded message, and then stays up.

Messages are published as the recorded CDR bytes (never deserialized). In timed mode the node
finishes (exits) when the bag is exhausted.

Parameters (ROS)
----------------
bag_path : str
    Bag directory (rosbag2, MCAP); read-only.
topics : list of str
    Topics to play ('' / empty = every graph topic in the bag except ``/fourws/run_config``).
rate : float
    Playback rate factor (timed mode).
publish_clock : bool
    Publish ``/clock`` from the bag time (timed mode).
mode : str
    ``timed`` or ``answer``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
from rosbags.rosbag2 import Reader, ReaderError

from fourws_ros import conversions, reporting, topics
from fourws_ros.node_base import FourwsNode
from fourws_ros.runtime import run_node
from fourws_run.cdr import stamp_ns
from fourws_run.ticks import Rejections
from fourws_sim.errors import ParameterError

MODES = ("timed", "answer")
#: Answer mode: a progress status every this many answered states.
STATUS_EVERY_TICKS = 10
#: Longest sleep between checks in timed mode, s (how quickly a signal is noticed).
_MAX_SLEEP_S = 0.05


def read_bag_raw(path: Path, wanted: list[str] | None) -> list[tuple[int, str, bytes]]:
    """``(log time ns, topic, CDR bytes)`` of a bag's messages in time order.

    Raises
    ------
    ParameterError
        If the bag cannot be read (names the path).
    """
    try:
        with Reader(path) as reader:
            conns = [c for c in reader.connections
                     if c.topic in topics.TOPIC_TYPES and c.topic != topics.RUN_CONFIG
                     and (not wanted or c.topic in wanted)]
            return [(t, c.topic, bytes(raw)) for c, t, raw in reader.messages(connections=conns)]
    except (ReaderError, OSError) as exc:
        raise ParameterError("bag_path", f"cannot read bag {str(path)!r}: {exc}") from None


class ReplayNode(FourwsNode):
    """Bag player (see module docstring)."""

    def __init__(self) -> None:
        super().__init__("fourws_replay")
        ro = dict(read_only=True)
        self.declare_parameter("bag_path", "", ParameterDescriptor(
            description="bag directory to play", **ro))
        self.declare_parameter("topics", [""], ParameterDescriptor(
            type=ParameterType.PARAMETER_STRING_ARRAY,
            description="topics to play (empty: all graph topics of the bag)", **ro))
        self.declare_parameter("rate", 1.0, ParameterDescriptor(
            description="playback rate factor, 1", **ro,
            floating_point_range=[FloatingPointRange(from_value=0.01, to_value=1000.0)]))
        self.declare_parameter("publish_clock", True, ParameterDescriptor(
            description="publish /clock from the bag time (timed mode)", **ro))
        self.declare_parameter("mode", "timed", ParameterDescriptor(
            description="timed | answer", **ro))
        path = str(self.get_parameter("bag_path").value)
        if not path:
            raise ParameterError("bag_path", "must name the bag to play")
        self.mode = str(self.get_parameter("mode").value)
        if self.mode not in MODES:
            raise ParameterError("mode", f"must be one of {', '.join(MODES)}, got {self.mode!r}")
        wanted = [t for t in self.get_parameter("topics").value if t]
        unknown = [t for t in wanted if t not in topics.TOPIC_TYPES]
        if unknown:
            raise ParameterError("topics", f"unknown topic {unknown[0]!r}")
        self.rate = float(self.get_parameter("rate").value)
        self.publish_clock = bool(self.get_parameter("publish_clock").value)
        self.messages = read_bag_raw(Path(path), wanted)
        if not self.messages:
            raise ParameterError("bag_path", f"bag {path!r} has no messages on the chosen topics")
        played = sorted({topic for _, topic, _ in self.messages})
        self.counts = reporting.PublishCounts()
        self.pubs = {t: self.counts.publisher(self, t) for t in played}
        if self.publish_clock and self.mode == "timed" and topics.CLOCK not in self.pubs:
            self.clock_pub = self.create_publisher(topics.message_class(topics.CLOCK),
                                                   topics.CLOCK, topics.CLOCK_QOS)
        else:
            self.clock_pub = None
        self.finished = False
        self._recorder = reporting.RecorderWatch(self)
        self.published = 0
        self._index = 0
        if self.mode == "answer":
            self._by_stamp: dict[int, list[tuple[str, bytes]]] = {}
            for _, topic, raw in self.messages:
                key = stamp_ns(raw, topics.TOPIC_TYPES[topic])
                if key is not None:
                    self._by_stamp.setdefault(key, []).append((topic, raw))
            self._left = sum(len(v) for v in self._by_stamp.values())
            self._total = self._left
            self._done_sent = False
            self._ticks = 0
            self._rejections = Rejections()
            self.status_pub = self.counts.publisher(self, topics.MANEUVER_STATUS)
            self.create_subscription(topics.message_class(topics.STATE), topics.STATE,
                                     self._on_state, topics.STREAM_READ_QOS, raw=True)
        else:
            self._t0_wall: float | None = None
            self._clock_msg = topics.message_class(topics.CLOCK)()
            self._timer = self.create_timer(0.001, self._play_due)
        self.get_logger().info(f"replaying {len(self.messages)} messages of "
                               f"{', '.join(played)} from {path} ({self.mode})")

    def _on_state(self, raw: bytes) -> None:
        key = stamp_ns(raw, topics.TOPIC_TYPES[topics.STATE])
        if key is None or self._done_sent:
            return
        due = self._by_stamp.pop(key, [])
        if not due and self._left == 0:
            self._status(key, "done", True, "completed: recorded input exhausted")
            self._done_sent = True
            self.finished = True  # deliver (on_shutdown) and exit
            self.get_logger().info(f"replay done after {self.published} messages")
            return
        for topic, data in due:
            self.pubs[topic].publish(data)
            self.published += 1
            self._left -= 1
        self._ticks += 1
        if self._ticks % STATUS_EVERY_TICKS == 1:
            self._status(key, "replay", False, "phase replay" if self._ticks == 1 else "")

    def _status(self, stamp: int, phase: str, done: bool, event: str) -> None:
        msg = topics.message_class(topics.MANEUVER_STATUS)()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, conversions.NS_PER_S)
        msg.maneuver = "replay"
        msg.phase = phase
        msg.progress = 1.0 - self._left / self._total if self._total else 1.0
        msg.done = done
        msg.end = "completed" if done else ""
        msg.event = event
        reporting.publish_counted_status(self.status_pub, msg, self.counts, self._rejections)

    def _play_due(self) -> None:
        if self._t0_wall is None:
            if any(p.get_subscription_count() == 0 for p in self.pubs.values()) and \
                    time.monotonic() - getattr(self, "_wait_since", time.monotonic()) < 5.0:
                self._wait_since = getattr(self, "_wait_since", time.monotonic())
                return  # give subscribers a moment to match before the first message
            self._t0_wall = time.monotonic()
            self._t0_bag = self.messages[0][0]
        elapsed_bag_ns = (time.monotonic() - self._t0_wall) * self.rate * 1e9
        while self._index < len(self.messages):
            t_ns, topic, raw = self.messages[self._index]
            if t_ns - self._t0_bag > elapsed_bag_ns:
                break
            if self.clock_pub is not None:
                self.clock_pub.publish(conversions.clock_msg(t_ns * 1e-9, self._clock_msg))
            self.pubs[topic].publish(raw)
            self.published += 1
            self._index += 1
        if self._index >= len(self.messages):
            self.finished = True

    def on_shutdown(self, executor: Any) -> None:
        """Give reliable readers the time to take the last messages before the node goes."""
        reporting.wait_delivered(self.counts, self.get_logger(), executor, self._recorder,
                                 reporting.delivery_timeout(self))
        self.get_logger().info(f"published {self.published} messages")


def main(args: list[str] | None = None) -> int:
    """Console entry point ``replay``."""
    return run_node(ReplayNode, args, name="fourws_replay")


if __name__ == "__main__":
    sys.exit(main())
