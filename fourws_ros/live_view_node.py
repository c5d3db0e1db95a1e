# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Live view node: serves a running graph over the Foxglove WebSocket protocol.

``fourws run ... --live [PORT]`` starts it beside the run's nodes, ``fourws node live_view``
by hand. It bridges the run's topics as they are (:data:`LIVE_TOPICS`: the car's frames, its
URDF and markers, the state, driver input, rear-steer command, odometry and IMU): each
becomes a Foxglove channel with message encoding ``cdr`` and its ``ros2msg`` definition (the
text the bags carry, from the typestore), so the Foxglove app decodes the messages as it
decodes a fourws bag, and the shipped layout (``config/foxglove/fourws.json``) shows a live run
and a bag alike. Each message is logged at its header stamp (simulation time; a message
without one at the latest stamp seen), so the timeline is the run's clock: in realtime at wall
speed, in lockstep at the run's pace.

Never in the answer chain: a separate process whose stream subscriptions are best effort and
volatile (a reliable reader would make the simulator's writers keep its samples until it
acknowledged them; a best-effort reader matches the reliable transient-local writers and
never holds them back), counted by no publisher (the run's nodes wait only for the run's
subscribers). The latched topics (``/tf_static``, ``/robot_description``) are read transient
local, so a viewer that connects late still gets the car. What the Foxglove server cannot send
to a slow client it drops (the SDK's per-client backlog), never the run's messages.

Listens on ``host`` (default 127.0.0.1, loopback only) and ``port`` (default 8765); a port in
use is one line and exit code 2.
"""

from __future__ import annotations

import sys
from typing import Any, Callable

import foxglove
from rcl_interfaces.msg import IntegerRange, ParameterDescriptor, ParameterType
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from fourws_ros import topics
from fourws_ros.node_base import FourwsNode
from fourws_ros.runtime import EXIT_USER_ERROR, run_node
from fourws_run.bagfile import typestore
from fourws_run.cdr import stamp_ns
from fourws_sim.errors import ParameterError

#: The topics a live view serves by default.
LIVE_TOPICS = (topics.TF, topics.TF_STATIC, topics.ROBOT_DESCRIPTION, topics.MARKERS,
               topics.STATE, topics.DRIVER_INPUT, topics.REAR_STEER_CMD, topics.ODOM,
               topics.IMU)
#: Default port (the Foxglove app's default WebSocket connection).
DEFAULT_PORT = 8765
#: What the live view reads streams with (module docstring: never holds a writer back).
LIVE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                      reliability=ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.VOLATILE)


def schema_of(msgtype: str) -> foxglove.Schema:
    """The ``ros2msg`` schema of ``msgtype``: its definition with its dependencies, as MCAP
    and the Foxglove app read it (rosbags' typestore writes the same text into bags)."""
    text, _ = typestore().generate_msgdef(msgtype, ros_version=2)
    return foxglove.Schema(name=msgtype, encoding="ros2msg", data=text.encode("utf-8"))


class LiveViewNode(FourwsNode):
    """Bridges the run's topics to a Foxglove WebSocket server (module docstring)."""

    def __init__(self) -> None:
        super().__init__("fourws_live_view")
        ro = dict(read_only=True)
        self.declare_parameter("host", "127.0.0.1", ParameterDescriptor(
            description="address to listen on (127.0.0.1: this machine only)", **ro))
        self.declare_parameter("port", DEFAULT_PORT, ParameterDescriptor(
            description="TCP port of the Foxglove WebSocket server",
            integer_range=[IntegerRange(from_value=1, to_value=65535, step=1)], **ro))
        self.declare_parameter("topics", list(LIVE_TOPICS), ParameterDescriptor(
            type=ParameterType.PARAMETER_STRING_ARRAY,
            description="graph topics to serve (fourws_run.interface names)", **ro))
        self.finished = False
        self.stop_reason = ""
        self.server: Any = None
        host = str(self.get_parameter("host").value)
        port = int(self.get_parameter("port").value)
        wanted = list(dict.fromkeys(self.get_parameter("topics").value))
        unknown = [t for t in wanted if t not in topics.TOPIC_TYPES]
        if unknown:
            raise ParameterError("topics", f"unknown topic {unknown[0]!r}; valid: "
                                 f"{', '.join(topics.TOPIC_TYPES)}")
        # every channel exists before the server starts: a client that connects at once is
        # advertised all of them together (one created after a client connected was seen
        # advertised but refused as unknown when the client subscribed to it)
        self._channels = {topic: foxglove.Channel(topic, message_encoding="cdr",
                                                  schema=schema_of(topics.TOPIC_TYPES[topic]))
                          for topic in wanted}
        try:
            self.server = foxglove.start_server(name="fourws", host=host, port=port)
        except RuntimeError as exc:
            # not a failure of the run: no announcement to its nodes, one line and exit 2
            self.stop_reason = (f"cannot serve the live view on {host}:{port}: "
                                f"{str(exc).split(': ', 1)[-1]}")
            self.exit_code = EXIT_USER_ERROR
            self.finished = True
            return
        self._last_ns = 0
        self._subs = []
        for topic, channel in self._channels.items():
            qos = (topics.LATCHED_RECORD_QOS if topic in topics.LATCHED_TOPICS else LIVE_QOS)
            self._subs.append(self.create_subscription(
                topics.message_class(topic), topic,
                self._forward(channel, topics.TOPIC_TYPES[topic]), qos, raw=True))
        self.get_logger().info(f"live view on ws://{host}:{self.server.port} "
                               f"({len(wanted)} topics); open it in Foxglove")

    def _forward(self, channel: Any, msgtype: str) -> Callable[[bytes], None]:
        def forward(data: bytes) -> None:
            t_ns = stamp_ns(data, msgtype)
            if t_ns is None:
                t_ns = self._last_ns
            elif t_ns > self._last_ns:
                self._last_ns = t_ns
            channel.log(data, log_time=t_ns)
        return forward

    def on_shutdown(self, executor: Any) -> None:
        """Close the server."""
        del executor
        if self.server is not None:
            self.server.stop()


def main(args: list[str] | None = None) -> int:
    """Console entry point ``live_view``."""
    return run_node(LiveViewNode, args, name="fourws_live_view")


if __name__ == "__main__":
    sys.exit(main())
