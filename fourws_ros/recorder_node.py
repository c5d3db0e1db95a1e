"""Recorder node: writes every graph topic to a rosbag2 bag (MCAP storage).

The bag is written with :class:`fourws_analysis.bag.BagWriter` (rosbags), so the message
definitions embedded in the bag come from the same typestore the offline analysis reads with.
Messages arrive as raw CDR bytes (raw subscriptions) and are written untouched — nothing is
deserialized on the recording path.

Bag timestamps
--------------
Each message is logged at its ``header.stamp`` (the clock's stamp for ``/clock``): simulation
time, in both clock modes. A lockstep run is then recorded on its own time axis (the bag of a
run 20x faster than real time still spans the simulated duration, and replays at rate 1 in
real time); messages without a stamp (``/fourws/run_config``) take the latest stamp seen.

Durability
----------
* SIGINT/SIGTERM: the recorder keeps taking messages until none has arrived for
  ``drain_quiet_s`` (the launcher stops the simulator first, so the queues empty), then closes
  the bag (metadata.yaml written, MCAP summary complete).
* SIGKILL (or a power cut): every ``flush_period_s`` the open MCAP chunk is closed and the file
  flushed to the OS, so the ``.mcap`` holds every message up to the last flush as complete
  chunks. :func:`fourws_analysis.bag.load_bag` reads such a bag (no ``metadata.yaml``, no MCAP
  summary) up to its last complete chunk. At most ``flush_period_s`` of messages is lost.
"""

from __future__ import annotations

import struct
import sys
import time
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import (FloatingPointRange, ParameterDescriptor, ParameterType,
                                SetParametersResult)
from rclpy.node import Node

from fourws_ros import topics
from fourws_sim.errors import ParameterError

#: Topics recorded by default: the whole graph (``/clock`` duplicates the state stamps).
DEFAULT_TOPICS = [t for t in topics.TOPIC_TYPES
                  if t not in (topics.CLOCK, topics.RECORDER_PROGRESS)]
#: The recorder reports its progress (for lockstep flow control) every this many states.
PROGRESS_EVERY = 20

_NS_PER_S = 1_000_000_000
#: Upper bound of the shutdown drain, s (a publisher that never stops cannot hold us forever).
MAX_DRAIN_S = 30.0
#: CDR encapsulation header (2 bytes kind + 2 bytes options) before the payload.
_CDR_HEADER_BYTES = 4
#: Encapsulation kinds of plain CDR (big/little endian); byte 1 is 1 for little endian.
_CDR_LITTLE_ENDIAN = 1
_STAMP_LE = struct.Struct("<iI")
_STAMP_BE = struct.Struct(">iI")


def stamp_ns(data: bytes | memoryview) -> int | None:
    """``header.stamp`` (or ``Clock.clock``) of a serialized message in ns, or ``None``.

    Every stamped graph message starts with a ``builtin_interfaces/Time`` (``int32 sec``,
    ``uint32 nanosec``), so the stamp sits right after the 4-byte CDR encapsulation header.

    Parameters
    ----------
    data : bytes
        CDR-serialized message (with encapsulation header).
    """
    if len(data) < _CDR_HEADER_BYTES + _STAMP_LE.size:
        return None
    fmt = _STAMP_LE if data[1] == _CDR_LITTLE_ENDIAN else _STAMP_BE
    sec, nanosec = fmt.unpack_from(data, _CDR_HEADER_BYTES)
    return sec * _NS_PER_S + nanosec


def flush_bag(bag: Any) -> bool:
    """Close the open MCAP chunk of a :class:`~fourws_analysis.bag.BagWriter` and flush the file.

    Relies on the storage object of rosbags' writer (``close_chunk()``, ``chunk``, ``bio``;
    rosbags 0.11). Returns ``False`` (and does nothing) if that layout is not found, so a
    rosbags upgrade degrades SIGKILL durability instead of breaking recording.
    """
    storage = getattr(getattr(bag, "_writer", None), "storage", None)
    chunk = getattr(storage, "chunk", None)
    if storage is None or chunk is None or not hasattr(storage, "close_chunk"):
        return False
    if chunk.bio.tell():
        storage.close_chunk()
    storage.bio.flush()
    return True


class RecorderNode(Node):
    """Records the graph topics to ``bag_path`` (see module docstring).

    Parameters (ROS)
    ----------------
    bag_path : str
        Bag directory to create (must not exist). Read-only.
    topics : list of str
        Topics to record (default: every graph topic but ``/clock``). Read-only.
    flush_period_s : float
        Wall-clock period of chunk flushes (SIGKILL durability), s.
    drain_quiet_s : float
        On shutdown, stop once no message arrived for this long, s.
    """

    def __init__(self) -> None:
        super().__init__("fourws_recorder")
        from fourws_analysis.bag import BagWriter

        ro = dict(read_only=True)
        self.declare_parameter("bag_path", "", ParameterDescriptor(
            description="bag directory to create (rosbag2, MCAP storage)", **ro))
        self.declare_parameter("topics", DEFAULT_TOPICS, ParameterDescriptor(
            type=ParameterType.PARAMETER_STRING_ARRAY,
            description="topics to record (graph topics of fourws_ros.topics)", **ro))
        self.declare_parameter("flush_period_s", 0.5, ParameterDescriptor(
            description="wall-clock period of MCAP chunk flushes, s (SIGKILL loses at most "
                        "this much)",
            floating_point_range=[FloatingPointRange(from_value=0.05, to_value=60.0)]))
        self.declare_parameter("drain_quiet_s", 0.3, ParameterDescriptor(
            description="on shutdown: stop when no message arrived for this long, s",
            floating_point_range=[FloatingPointRange(from_value=0.01, to_value=10.0)]))
        self.add_on_set_parameters_callback(self._on_set)

        path = str(self.get_parameter("bag_path").value)
        if not path:
            raise ParameterError("bag_path", "must name the bag directory to create")
        wanted = list(self.get_parameter("topics").value)
        unknown = [t for t in wanted if t not in topics.TOPIC_TYPES]
        if unknown:
            raise ParameterError("topics", f"unknown topic {unknown[0]!r}; valid: "
                                 f"{', '.join(topics.TOPIC_TYPES)}")
        self.bag = BagWriter(Path(path))
        self.bag.open()
        self.counts: dict[str, int] = {t: 0 for t in wanted}
        self._last_stamp_ns = 0
        self._last_rx = time.monotonic()
        self._progress_pub = self.create_publisher(
            topics.message_class(topics.RECORDER_PROGRESS), topics.RECORDER_PROGRESS,
            topics.STATUS_QOS)
        self._progress_msg = topics.message_class(topics.RECORDER_PROGRESS)()
        self._subs = [
            self.create_subscription(topics.message_class(t), t, self._make_callback(t),
                                     topics.TOPIC_QOS[t], raw=True)
            for t in wanted]
        self._flush_timer = self.create_timer(
            float(self.get_parameter("flush_period_s").value), self._flush,
            clock=self._wall_clock())
        self.get_logger().info(f"recording {len(wanted)} topics to {path}")

    def _wall_clock(self) -> Any:
        from rclpy.clock import Clock, ClockType
        return Clock(clock_type=ClockType.STEADY_TIME)

    def _on_set(self, params: list[Any]) -> SetParametersResult:
        for p in params:
            if p.name in ("flush_period_s", "drain_quiet_s"):
                value = p.value
                if not isinstance(value, float) or not value > 0.0:
                    return SetParametersResult(successful=False,
                                               reason=f"{p.name}: must be a float > 0 s")
        return SetParametersResult(successful=True)

    def _make_callback(self, topic: str) -> Any:
        msgtype = topics.TOPIC_TYPES[topic]
        write = self.bag.write_raw
        counts = self.counts

        def callback(data: bytes) -> None:
            t_ns = stamp_ns(data) if topic != topics.RUN_CONFIG else None
            if t_ns is None:
                t_ns = self._last_stamp_ns
            elif t_ns > self._last_stamp_ns:
                self._last_stamp_ns = t_ns
            write(topic, data, t_ns, msgtype)
            counts[topic] += 1
            self._last_rx = time.monotonic()
            if topic == topics.STATE and counts[topic] % PROGRESS_EVERY == 0:
                self._progress_msg.data = counts[topic]
                self._progress_pub.publish(self._progress_msg)

        return callback

    def _flush(self) -> None:
        flush_bag(self.bag)

    def on_shutdown(self, executor: Any) -> None:
        """Drain what DDS still holds for us, then close the bag."""
        from fourws_ros.runtime import SPIN_TIMEOUT_S

        quiet = float(self.get_parameter("drain_quiet_s").value)
        start = self._last_rx = time.monotonic()
        while (time.monotonic() - self._last_rx < quiet
               and time.monotonic() - start < MAX_DRAIN_S):
            executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)
        self.bag.close()
        total = sum(self.counts.values())
        summary = ", ".join(f"{t} {n}" for t, n in self.counts.items())
        print(f"[fourws_recorder] closed {self.bag.path}: {total} messages ({summary})",
              file=sys.stderr, flush=True)


def main(args: list[str] | None = None) -> int:
    """Console entry point ``recorder``."""
    from fourws_ros.runtime import run_node
    return run_node(RecorderNode, args, name="fourws_recorder")


if __name__ == "__main__":
    sys.exit(main())
