# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Maneuver node: plays a maneuver of ``config/maneuvers`` as driver input, one per state.

For every ``VehicleState`` of the run (states that do not continue the simulator's own
sequence are refused and counted, :class:`fourws_run.ticks.StateGate`) it calls the core
maneuver (:class:`fourws_sim.maneuvers.Maneuver`) with the state's exact simulation time and
outputs and publishes the ``DriverInput`` stamped with the state's stamp -- the answer the
simulator waits for in lockstep mode. It publishes ``ManeuverStatus`` (phase, progress,
events, its published counts) and, once the maneuver is done, a final status with
``done = true`` stamped with that state's stamp (``end``: ``completed``, ``end_condition`` or
``aborted``) instead of an answer, which ends the run; if the simulation ends first (it
diverged), the final status says ``stopped``. Then it waits until every subscriber
has everything it published and exits (``exit_when_done``).

Parameters (ROS)
----------------
maneuver : str
    Maneuver name (``config/maneuvers`` stem) or YAML path; read-only.
maneuver_json : str
    Inline maneuver mapping as JSON (overrides ``maneuver`` when not empty); read-only.
vehicle : str
    Simulated vehicle (name or YAML path); read-only.
integration_step_s, state_period_s : float
    The run's integration step and the period of the states it answers (lockstep: the
    control period); the state gate checks the states against them.
clock_mode : str
    ``lockstep`` (every state answered, none skipped) or ``realtime``.
exit_when_done : bool
    Exit once the maneuver is done and delivered.
simulator_node : str
    The run's simulator node; states of any other publisher are refused and counted (a
    foreign state on the run's clock could otherwise take the place of the simulator's and
    stall a lockstep run); read-only.
"""

from __future__ import annotations

import json
import sys
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor

from fourws_ros import conversions, peers, reporting, topics
from fourws_ros.identity import run_node_filter, subscribe_from
from fourws_ros.node_base import FourwsNode
from fourws_ros.runtime import EXIT_PEERS, run_node
from fourws_run import codecs
from fourws_run.ticks import StateGate
from fourws_sim.errors import FourwsError, ParameterError
from fourws_sim.maneuvers import make_maneuver

#: Progress status every this many integration steps (0.1 s at 1 kHz), besides phase events.
STATUS_EVERY_STEPS = 100
CLOCK_MODES = ("lockstep", "realtime")


class ManeuverNode(FourwsNode):
    """Maneuver player (see module docstring)."""

    #: States are taken from the run's simulator node only, told by the publisher of each
    #: message (rclpy message info: the lean executor, fourws_ros.runtime).
    needs_message_info = True

    def __init__(self) -> None:
        super().__init__("fourws_maneuver")

        ro = dict(read_only=True)
        period = [FloatingPointRange(from_value=1e-5, to_value=1.0)]
        self.declare_parameter("maneuver", "step_steer_85kmh", ParameterDescriptor(
            description="maneuver name (config/maneuvers) or YAML path", **ro))
        self.declare_parameter("maneuver_json", "", ParameterDescriptor(
            description="inline maneuver mapping as JSON (overrides maneuver)", **ro))
        self.declare_parameter("vehicle", "table_8_1", ParameterDescriptor(
            description="simulated vehicle (config/vehicles name or YAML path)", **ro))
        self.declare_parameter("vehicle_json", "", ParameterDescriptor(
            description="the simulated vehicle as a whole vehicle-file mapping in JSON "
                        "(overrides vehicle when not empty)", **ro))
        self.declare_parameter("integration_step_s", 1e-3, ParameterDescriptor(
            description="the run's integration step, s", floating_point_range=period, **ro))
        self.declare_parameter("state_period_s", 0.01, ParameterDescriptor(
            description="period of the answered states, s (lockstep: the control period)",
            floating_point_range=period, **ro))
        self.declare_parameter("clock_mode", "lockstep", ParameterDescriptor(
            description="lockstep | realtime", **ro))
        self.declare_parameter("exit_when_done", True, ParameterDescriptor(
            description="exit once the maneuver is done and delivered"))
        self.declare_parameter("simulator_node", topics.NODE_NAMES[topics.Role.SIMULATOR],
                               ParameterDescriptor(
            description="the run's simulator node: states of any other publisher are refused "
                        "(a foreign state on the run's clock would take the place of the "
                        "simulator's)", **ro))
        self.declare_parameter("startup_timeout_s", peers.STARTUP_TIMEOUT_S, ParameterDescriptor(
            description="wall time to wait for the simulator's states before giving up with "
                        "a line naming what is missing, s (0: wait forever)",
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=86400.0)], **ro))
        vehicle = conversions.vehicle_from_params(self)
        inline = str(self.get_parameter("maneuver_json").value)
        if inline:
            try:
                source: Any = json.loads(inline)
            except json.JSONDecodeError as exc:
                raise ParameterError("maneuver_json", f"not JSON ({exc})") from None
        else:
            source = str(self.get_parameter("maneuver").value)
        self.maneuver = make_maneuver(source, vehicle)
        mode = str(self.get_parameter("clock_mode").value)
        if mode not in CLOCK_MODES:
            raise ParameterError("clock_mode", f"must be one of {', '.join(CLOCK_MODES)}, "
                                 f"got {mode!r}")
        self.gate = StateGate(float(self.get_parameter("integration_step_s").value),
                              float(self.get_parameter("state_period_s").value),
                              lockstep=mode == "lockstep")
        self.counts = reporting.PublishCounts()
        self.driver_pub = self.counts.publisher(self, topics.DRIVER_INPUT)
        self.status_pub = self.counts.publisher(self, topics.MANEUVER_STATUS)
        self._config_pub = reporting.publish_node_config(
            self, self.counts, topics.Role.MANEUVER,
            {"maneuver": self.maneuver.to_dict(), "vehicle": vehicle.name})
        # raw: the fast decoder keeps the lockstep answer chain short (fourws_run.codecs)
        self._run_nodes = run_node_filter(self, self.gate.rejections)
        state_sub = subscribe_from(self, self._run_nodes, topics.STATE, "simulator_node",
                                   self._on_state, topics.STREAM_READ_QOS)
        self.peers = peers.PeerWatch(self, float(self.get_parameter("startup_timeout_s").value))
        self.peers.need_publishers(state_sub, topics.STATE)
        self._peer_timer = self.create_timer(0.1, self._check_peers)
        self._driver_encoder = codecs.DriverInputEncoder(topics.FRAME_BODY)
        self._recorder = reporting.RecorderWatch(self)
        self.matched = reporting.match_wait(self, self.counts)
        # states of the run (admitted by the gate) that came before the publishers matched
        # the run's subscribers (the recorder among them): answered, in order, once they have
        self._held: list[dict[str, Any]] = []
        self._held_timer = self.create_timer(0.02, self._answer_held)
        self.create_subscription(topics.message_class(topics.SIM_STATUS), topics.SIM_STATUS,
                                 self._on_sim_status, topics.STATUS_READ_QOS)
        self._phase = ""
        self.done = False
        self.finished = False  # run_node: stop spinning
        self.stop_reason = ""  # run_node: why it gave up on its peers (exit_code)
        self.get_logger().info(f"maneuver {self.maneuver.name} "
                               f"({self.maneuver.spec.type}, {self.maneuver.duration_s} s)")

    def _status(self, stamp_ns: int, phase: str, progress: float, event: str,
                end: str = "") -> None:
        msg = topics.message_class(topics.MANEUVER_STATUS)()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, conversions.NS_PER_S)
        msg.maneuver = self.maneuver.name
        msg.phase = phase
        msg.progress = float(progress)
        msg.done = bool(end)
        msg.end = end
        msg.event = event
        reporting.publish_counted_status(self.status_pub, msg, self.counts,
                                         self.gate.rejections)

    def _finish(self, stamp_ns: int, t: float, end: str, event: str) -> None:
        self.done = True
        self._status(stamp_ns, "done", self.maneuver.progress(t), event, end)
        text = f"maneuver {end} at t = {t:.3f} s: {event}"
        # one call site per severity (rclpy refuses one whose severity changes: a run reset
        # after a completed maneuver could end aborted)
        if end == "aborted":
            self.get_logger().warning(text)
        else:
            self.get_logger().info(text)
        if bool(self.get_parameter("exit_when_done").value):
            self.finished = True

    def _answer_held(self) -> None:
        if not self.matched.ready():
            return
        self._held_timer.cancel()
        held, self._held = self._held, []
        for outputs in held:
            self._answer(outputs)

    def _on_state(self, raw: bytes) -> None:
        if self.done:
            return
        try:
            outputs = codecs.parse_state(raw)
        except codecs.CodecError as exc:
            self.gate.rejections.add(topics.STATE, "not a VehicleState", str(exc))
            return
        bad = codecs.outputs_finite(outputs)
        if bad:  # the simulator never publishes one: refused before it takes a step's place
            self.gate.rejections.add(topics.STATE, "non-finite state", bad)
            return
        t = outputs["sim_time_s"]
        stamp = outputs["stamp_ns"]
        if not self.gate.admit(outputs["step"], t, stamp):
            self.get_logger().warning(f"refused a state: {self.gate.rejections.last}",
                                      throttle_duration_sec=1.0)
            return
        if not self.matched.ready() or self._held:
            self._held.append(outputs)  # lockstep: the first state (the simulator waits)
            return
        self._answer(outputs)

    def _answer(self, outputs: dict[str, Any]) -> None:
        """Answer an admitted state: the driver input, or the maneuver's end."""
        if self.done:
            return
        t = outputs["sim_time_s"]
        stamp = outputs["stamp_ns"]
        if self.maneuver.done(t, outputs):
            reason = self.maneuver.abort_reason
            self._finish(stamp, t, self.maneuver.end_kind,
                         f"{self.maneuver.end_kind}: {reason}" if reason else "completed")
            return
        try:
            cmd = self.driver_command(t, outputs)
            raw_cmd = self._driver_encoder.encode(cmd, t)
        except FourwsError as exc:
            self._finish(stamp, t, "aborted", f"aborted: {exc}")
            return
        self.driver_pub.publish(raw_cmd)
        phase = self.maneuver.phase(t)
        event = f"phase {phase}" if phase != self._phase else ""
        if event or outputs["step"] % STATUS_EVERY_STEPS == 0:
            self._status(stamp, phase, self.maneuver.progress(t), event)
        self._phase = phase

    def driver_command(self, t: float, outputs: dict[str, Any]) -> Any:
        """The driver input answering the state at ``t``: the maneuver's (the input driver
        nodes of :mod:`fourws_ros.input_driver_node` take theirs from outside)."""
        return self.maneuver.command(t, outputs)

    def _check_peers(self) -> None:
        """Give up on a graph that does not come together, or whose simulator left."""
        self._run_nodes.poll()
        if self.done:
            return
        why = (self.peers.check_startup() if self.gate.last_step is None
               else self.peers.gone())
        if why:
            self.stop_reason = why
            self.exit_code = EXIT_PEERS
            self.get_logger().error(why)
            # the final counts still go out (a recorder closes its bag with them)
            t = (self.gate.last_step or 0) * self.gate.dt_s
            self._finish(conversions.time_to_ns(t), t, "stopped", f"stopped: {why}")
            self.finished = True

    def _on_sim_status(self, msg: Any) -> None:
        """The simulation ended before the maneuver did (it diverged, or stopped for a node
        that stopped answering): report the final counts with ``end`` ``stopped``. A peer's
        announced failure that already arrived comes first (the simulator checks its peers
        ten times as often as this node: its final status, caused by that failure, can
        overtake this node's own check)."""
        if msg.final and not self.done:
            self._check_peers()
        if msg.final and not self.done and self.gate.admits_final(float(msg.sim_time_s)):
            t = float(msg.sim_time_s)
            self._finish(conversions.time_to_ns(t), t, "stopped",
                         f"stopped: the simulation ended first ({msg.end_reason})")

    def on_shutdown(self, executor: Any) -> None:
        """Answer no more states; wait until what this node published is delivered."""
        self.done = True
        reporting.wait_delivered(self.counts, self.get_logger(), executor, self._recorder,
                                 reporting.delivery_timeout(self))


def main(args: list[str] | None = None) -> int:
    """Console entry point ``maneuver``."""
    return run_node(ManeuverNode, args, name="fourws_maneuver")


if __name__ == "__main__":
    sys.exit(main())
