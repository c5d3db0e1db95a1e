"""Maneuver node: plays a maneuver of ``config/maneuvers`` as driver input, one per state.

For every ``VehicleState`` it receives (at the control rate) it calls the core maneuver
(:class:`fourws_sim.maneuvers.Maneuver`) with the state's exact simulation time and outputs and
publishes the ``DriverInput`` stamped with the state's stamp — the answer the simulator waits
for in lockstep mode. It publishes ``ManeuverStatus`` (phase, progress, events) and, once the
maneuver is done, a status with ``done = true`` and stops answering, which ends the run.

Parameters (ROS)
----------------
maneuver : str
    Maneuver name (``config/maneuvers`` stem) or YAML path; read-only.
maneuver_json : str
    Inline maneuver mapping as JSON (overrides ``maneuver`` when not empty); read-only.
vehicle : str
    Simulated vehicle (name or YAML path); read-only.
"""

from __future__ import annotations

import json
import sys
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node

from fourws_ros import cdr, conversions, topics
from fourws_sim.errors import FourwsError, ParameterError


#: Progress status every this many integration steps (0.1 s at 1 kHz), besides phase events.
STATUS_EVERY_STEPS = 100


class ManeuverNode(Node):
    """Maneuver player (see module docstring)."""

    def __init__(self) -> None:
        super().__init__("fourws_maneuver")
        from fourws_sim.maneuvers import make_maneuver
        from fourws_sim.params import load_vehicle

        ro = dict(read_only=True)
        self.declare_parameter("maneuver", "step_steer_85kmh", ParameterDescriptor(
            description="maneuver name (config/maneuvers) or YAML path", **ro))
        self.declare_parameter("maneuver_json", "", ParameterDescriptor(
            description="inline maneuver mapping as JSON (overrides maneuver)", **ro))
        self.declare_parameter("vehicle", "table_8_1", ParameterDescriptor(
            description="simulated vehicle (config/vehicles name or YAML path)", **ro))
        vehicle = load_vehicle(str(self.get_parameter("vehicle").value))
        inline = str(self.get_parameter("maneuver_json").value)
        if inline:
            try:
                source: Any = json.loads(inline)
            except json.JSONDecodeError as exc:
                raise ParameterError("maneuver_json", f"not JSON ({exc})") from None
        else:
            source = str(self.get_parameter("maneuver").value)
        self.maneuver = make_maneuver(source, vehicle)
        self.driver_pub = self.create_publisher(topics.message_class(topics.DRIVER_INPUT),
                                                topics.DRIVER_INPUT, topics.STREAM_QOS)
        self.status_pub = self.create_publisher(topics.message_class(topics.MANEUVER_STATUS),
                                                topics.MANEUVER_STATUS, topics.STATUS_QOS)
        # raw: the fast decoder keeps the lockstep answer chain short (fourws_ros.cdr)
        self.create_subscription(topics.message_class(topics.STATE), topics.STATE,
                                 self._on_state, topics.STREAM_QOS, raw=True)
        self._driver_encoder = cdr.DriverInputEncoder(topics.FRAME_BODY)
        self._phase = ""
        self._done = False
        self.get_logger().info(f"maneuver {self.maneuver.name} "
                               f"({self.maneuver.spec.type}, {self.maneuver.duration_s} s)")

    def _status(self, stamp_ns: int, phase: str, progress: float, done: bool,
                event: str) -> None:
        msg = topics.message_class(topics.MANEUVER_STATUS)()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, conversions.NS_PER_S)
        msg.maneuver = self.maneuver.name
        msg.phase = phase
        msg.progress = float(progress)
        msg.done = done
        msg.event = event
        self.status_pub.publish(msg)

    def _on_state(self, raw: bytes) -> None:
        if self._done:
            return
        try:
            outputs = cdr.parse_state(raw)
        except cdr.CdrError as exc:
            self.get_logger().error(f"ignored state: {exc}", throttle_duration_sec=1.0)
            return
        t = outputs["sim_time_s"]
        stamp = outputs["stamp_ns"]
        if self.maneuver.done(t, outputs):
            self._done = True
            reason = self.maneuver.abort_reason
            self._status(stamp, "done", self.maneuver.progress(t), True,
                         f"done: {reason}" if reason else "done")
            self.get_logger().info(f"maneuver done at t = {t:.3f} s {reason}")
            return
        try:
            cmd = self.maneuver.command(t, outputs)
            self.driver_pub.publish(self._driver_encoder.encode(cmd, t))
        except FourwsError as exc:
            self._done = True
            self._status(stamp, "done", self.maneuver.progress(t), True, f"abort: {exc}")
            self.get_logger().error(f"maneuver aborted: {exc}")
            return
        phase = self.maneuver.phase(t)
        event = f"phase {phase}" if phase != self._phase else ""
        if event or outputs["step"] % STATUS_EVERY_STEPS == 0:
            self._status(stamp, phase, self.maneuver.progress(t), False, event)
        self._phase = phase


def main(args: list[str] | None = None) -> int:
    """Console entry point ``maneuver``."""
    from fourws_ros.runtime import run_node
    return run_node(ManeuverNode, args, name="fourws_maneuver")


if __name__ == "__main__":
    sys.exit(main())
