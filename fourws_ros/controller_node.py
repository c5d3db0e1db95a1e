# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Controller node: any rear-steer law of :mod:`fourws_control`, answering each vehicle state.

For every ``VehicleState`` it publishes one ``RearSteerCommand`` (``state_step`` = the state's
step): the law's rear angle for the state and the driver's front road-wheel angle of the same
tick, passed through the rear-steer actuator (angle and rate limits over one control period).

Handshake (both clock modes): the command for state ``k`` is sent once both the state ``k``
and the ``DriverInput`` stamped with the state's stamp have arrived — the law's feed-forward
term uses the front angle the driver applies in this tick, as the offline runner
(:func:`fourws_run.closed_loop.run_closed_loop`) does. If no driver input of that tick arrives
within ``driver_wait_s`` (wall clock), the latest driver input is used (realtime runs with a
slow maneuver node) and the fallback is counted in the log.

Parameters (ROS, all validated; a rejected set leaves the running value)
-------------------------------------------------------------------------
law : str
    Law name (``fourws_control.available_laws()``); live switchable. The actuator keeps its
    current angle across a switch, so the rear wheels never jump.
law_options_json : str
    JSON mapping of the law's options (e.g. ``{"min_speed_mps": 2.0}``).
vehicle : str
    Simulated vehicle (name or YAML path); read-only.
belief_vehicle : str
    The controller's belief of the vehicle ('' = ``vehicle``); the gains come from it. Not
    used (a live change is refused, saying so) while ``belief_vehicle_json`` is set.
belief_vehicle_json : str
    The belief as a whole vehicle mapping (``fourws run`` sets it to the scenario's belief).
belief_scale_front, belief_scale_rear : float
    Scales of the belief's axle cornering stiffnesses (e.g. 0.6 for a -40 % belief), applied
    to whichever belief is given; live changes take effect at the next state.
angle_limit_rad, rate_limit_radps : float
    Actuator limits (0 = the vehicle file's ``actuators``).
control_period_s : float
    Period over which the rate limit acts and the law is built for, s (the interval between
    the controller's answers).
integration_step_s, state_period_s, clock_mode
    The run's step, the period of the states answered and the clock mode: states that do not
    continue the simulator's sequence are refused (:class:`fourws_run.ticks.StateGate`).
exit_when_done : bool
    Exit once the simulator's final status arrived and everything published is delivered.
simulator_node, maneuver_node : str
    The run's simulator and driver nodes: states and driver inputs of any other publisher
    are refused and counted (a foreign state on the run's clock would steer the law, a
    foreign driver input on a state's stamp would be its feed-forward); read-only.

The node publishes what it runs with on ``/fourws/node_config`` (law, options, belief,
actuator limits), again after every accepted law change.
"""

from __future__ import annotations

import collections
import json
import math
import sys
import time
from typing import Any

from rcl_interfaces.msg import (FloatingPointRange, ParameterDescriptor, SetParametersResult)

from fourws_control import RearSteerActuator, available_laws, make_loop_law
from fourws_ros import conversions, peers, reporting, topics
from fourws_ros.identity import run_node_filter, subscribe_from
from fourws_ros.node_base import FourwsNode
from fourws_ros.runtime import EXIT_PEERS, run_node
from fourws_run import codecs
from fourws_run.ticks import StateGate, law_input
from fourws_sim.errors import FourwsError, ParameterError
from fourws_sim.params import load_vehicle, vehicle_from_mapping

#: Longest rear-angle limit a parameter may set, rad (45 deg: beyond any rear-steer hardware).
MAX_ANGLE_LIMIT_RAD = math.pi / 4
#: Longest rate limit a parameter may set, rad/s.
MAX_RATE_LIMIT_RADPS = 10.0
#: A state waiting this long (wall) for its driver input is reported, naming what it waits
#: for, s.
WAIT_REPORT_S = 1.0


def _float_range(lo: float, hi: float) -> list[FloatingPointRange]:
    return [FloatingPointRange(from_value=lo, to_value=hi)]


class ControllerNode(FourwsNode):
    """Rear-steer controller (see module docstring)."""

    #: States are taken from the run's simulator node only and driver inputs from its
    #: maneuver node only, told by the publisher of each message (rclpy message info: the
    #: lean executor, fourws_ros.runtime).
    needs_message_info = True

    def __init__(self, node_name: str = "fourws_controller") -> None:
        super().__init__(node_name)

        self.declare_parameter("law", "fws", ParameterDescriptor(
            description=f"rear-steer law, one of: {', '.join(available_laws())}"))
        self.declare_parameter("law_options_json", "{}", ParameterDescriptor(
            description="JSON mapping of law options"))
        self.declare_parameter("vehicle", "table_8_1", ParameterDescriptor(
            description="simulated vehicle (config/vehicles name or YAML path)", read_only=True))
        self.declare_parameter("vehicle_json", "", ParameterDescriptor(
            description="the simulated vehicle as a whole vehicle-file mapping in JSON "
                        "(overrides vehicle when not empty)", read_only=True))
        self.declare_parameter("belief_vehicle", "", ParameterDescriptor(
            description="controller belief vehicle ('' = vehicle)"))
        self.declare_parameter("belief_vehicle_json", "", ParameterDescriptor(
            description="the belief as a whole vehicle-file mapping in JSON (replaces "
                        "belief_vehicle when not empty; the scales apply to it)"))
        self.declare_parameter("belief_scale_front", 1.0, ParameterDescriptor(
            description="belief front cornering stiffness scale, 1",
            floating_point_range=_float_range(0.05, 20.0)))
        self.declare_parameter("belief_scale_rear", 1.0, ParameterDescriptor(
            description="belief rear cornering stiffness scale, 1",
            floating_point_range=_float_range(0.05, 20.0)))
        self.declare_parameter("angle_limit_rad", 0.0, ParameterDescriptor(
            description="rear angle limit, rad (0 = vehicle actuators)",
            floating_point_range=_float_range(0.0, MAX_ANGLE_LIMIT_RAD)))
        self.declare_parameter("rate_limit_radps", 0.0, ParameterDescriptor(
            description="rear angle rate limit, rad/s (0 = vehicle actuators)",
            floating_point_range=_float_range(0.0, MAX_RATE_LIMIT_RADPS)))
        self.declare_parameter("control_period_s", 0.01, ParameterDescriptor(
            description="control period (rate-limit interval, the law's period), s",
            read_only=True,
            floating_point_range=_float_range(1e-4, 1.0)))
        self.declare_parameter("driver_wait_s", 0.5, ParameterDescriptor(
            description="wall time to wait for the driver input of a tick before using the "
                        "latest, s (0 = wait forever: lockstep)",
            floating_point_range=_float_range(0.0, 10.0)))
        self.declare_parameter("integration_step_s", 1e-3, ParameterDescriptor(
            description="the run's integration step, s", read_only=True,
            floating_point_range=_float_range(1e-5, 1.0)))
        self.declare_parameter("state_period_s", 0.01, ParameterDescriptor(
            description="period of the answered states, s (lockstep: the control period)",
            read_only=True, floating_point_range=_float_range(1e-5, 1.0)))
        self.declare_parameter("clock_mode", "lockstep", ParameterDescriptor(
            description="lockstep | realtime", read_only=True))
        self.declare_parameter("exit_when_done", True, ParameterDescriptor(
            description="exit once the simulator's final status arrived and all is delivered"))
        self.declare_parameter("maneuver_node", topics.NODE_NAMES[topics.Role.MANEUVER],
                               ParameterDescriptor(
            description="the run's driver node: driver inputs of any other publisher are "
                        "refused (a foreign one on the state's stamp would be the law's "
                        "feed-forward)", read_only=True))
        self.declare_parameter("simulator_node", topics.NODE_NAMES[topics.Role.SIMULATOR],
                               ParameterDescriptor(
            description="the run's simulator node: states of any other publisher are refused "
                        "(a foreign state on the run's clock would steer the law)",
            read_only=True))
        self.declare_parameter("startup_timeout_s", peers.STARTUP_TIMEOUT_S, ParameterDescriptor(
            description="wall time to wait for the simulator's states before giving up with "
                        "a line naming what is missing, s (0: wait forever)", read_only=True,
            floating_point_range=_float_range(0.0, 86400.0)))

        self.vehicle = conversions.vehicle_from_params(self)
        self.dt_s = float(self.get_parameter("control_period_s").value)
        current = {p: self.get_parameter(p).value for p in self._BUILD_PARAMS}
        self.law, self.actuator = self._build(current, None)
        self.law_name = current["law"]
        self.add_on_set_parameters_callback(self._on_set)

        mode = str(self.get_parameter("clock_mode").value)
        if mode not in ("lockstep", "realtime"):
            raise ParameterError("clock_mode", f"must be lockstep or realtime, got {mode!r}")
        self.gate = StateGate(float(self.get_parameter("integration_step_s").value),
                              float(self.get_parameter("state_period_s").value),
                              lockstep=mode == "lockstep")
        self.counts = reporting.PublishCounts()
        self.pub = self.counts.publisher(self, topics.REAR_STEER_CMD)
        self._config_pub = self.counts.publisher(self, topics.NODE_CONFIG)
        self._publish_config()
        self.matched = reporting.match_wait(self, self.counts)
        self.create_subscription(topics.message_class(topics.SIM_STATUS), topics.SIM_STATUS,
                                 self._on_sim_status, topics.STATUS_READ_QOS)
        self._recorder = reporting.RecorderWatch(self)
        self._closing = False
        self._sim_ended = False
        self.finished = False  # run_node: stop spinning
        self.stop_reason = ""  # run_node: why it gave up on its peers (exit_code)
        # raw subscriptions + fourws_run.codecs: the answer chain of lockstep runs stays short
        self._run_nodes = run_node_filter(self, self.gate.rejections)
        state_sub = subscribe_from(self, self._run_nodes, topics.STATE, "simulator_node",
                                   self._on_state, topics.STREAM_READ_QOS)
        self.peers = peers.PeerWatch(self, float(self.get_parameter("startup_timeout_s").value))
        self.peers.need_publishers(state_sub, topics.STATE)
        subscribe_from(self, self._run_nodes, topics.DRIVER_INPUT, "maneuver_node",
                       self._on_driver, topics.STREAM_READ_QOS)
        self._cmd_encoder = codecs.RearSteerCommandEncoder(topics.FRAME_BODY)
        # admitted states not answered yet, in order: stamp ns -> (state, wall time received)
        self._states: collections.OrderedDict[int, tuple[dict[str, Any], float]] = \
            collections.OrderedDict()
        self._reported = -1
        self._driver: dict[int, float] = {}  # stamp ns -> front road-wheel angle, rad
        self._last_front = 0.0
        self.fallbacks = 0
        self._answered_once = False
        self._timer = self.create_timer(0.05, self._check_wait)
        self.get_logger().info(f"law {self.law_name} on {self.vehicle.name}")

    _BUILD_PARAMS = ("law", "law_options_json", "belief_vehicle", "belief_vehicle_json",
                     "belief_scale_front", "belief_scale_rear", "angle_limit_rad",
                     "rate_limit_radps")

    def _build(self, values: dict[str, Any], keep_angle: float | None) -> tuple[Any, Any]:
        """Law and actuator from parameter values; raises FourwsError on bad values."""
        try:
            options = json.loads(values["law_options_json"] or "{}")
        except json.JSONDecodeError as exc:
            raise ParameterError("law_options_json", f"not JSON ({exc})") from None
        if not isinstance(options, dict):
            raise ParameterError("law_options_json", "must be a JSON object")
        if values["belief_vehicle_json"]:
            try:
                data = json.loads(values["belief_vehicle_json"])
            except json.JSONDecodeError as exc:
                raise ParameterError("belief_vehicle_json", f"not JSON ({exc})") from None
            belief = vehicle_from_mapping(data, "parameter belief_vehicle_json")
        else:
            belief = (load_vehicle(values["belief_vehicle"]) if values["belief_vehicle"]
                      else self.vehicle)
        # the scales act on whichever belief is given (fourws run gives it as JSON, scaled
        # already by the scenario's scales: a live scale change multiplies that)
        sf, sr = float(values["belief_scale_front"]), float(values["belief_scale_rear"])
        if sf != 1.0 or sr != 1.0:
            belief = belief.with_axle_tires(sf, sr)
        law = make_loop_law(str(values["law"]), belief, self.dt_s, options)
        law.gains(max(self.vehicle_speed_hint(), 1.0))  # fail now on a law that cannot design
        limits: dict[str, float] = {}
        if values["angle_limit_rad"] > 0.0:
            limits["angle_limit_rad"] = float(values["angle_limit_rad"])
        if values["rate_limit_radps"] > 0.0:
            limits["rate_limit_rad_per_s"] = float(values["rate_limit_radps"])
        # the actuator model's limits come from the vehicle the controller is given (its
        # belief), as in fourws_run.closed_loop
        actuator = RearSteerActuator(belief, **limits,
                                     initial_angle_rad=keep_angle or 0.0)
        return law, actuator

    def vehicle_speed_hint(self) -> float:
        """Speed used to try a new law's gain design, m/s (the last state's, else 20)."""
        states = getattr(self, "_states", None)
        if states:
            return float(next(reversed(states.values()))[0]["speed_mps"])
        return 20.0

    def _on_set(self, params: list[Any]) -> SetParametersResult:
        changed = {p.name: p.value for p in params if p.name in self._BUILD_PARAMS}
        if not changed:
            return SetParametersResult(successful=True)
        values = {p: self.get_parameter(p).value for p in self._BUILD_PARAMS}
        values.update(changed)
        if "belief_vehicle" in changed and values["belief_vehicle_json"]:
            reason = ("belief_vehicle: not used while belief_vehicle_json is set (fourws run "
                      "sets it to the scenario's belief); set belief_vehicle_json instead, or "
                      "to '' together with belief_vehicle")
            self.get_logger().warning(f"rejected parameter change: {reason}")
            return SetParametersResult(successful=False, reason=reason)
        try:
            law, actuator = self._build(values, self.actuator.angle_rad)
        except (FourwsError, TypeError) as exc:
            self.get_logger().warning(f"rejected parameter change: {exc}")
            return SetParametersResult(successful=False, reason=str(exc))
        self.law, self.actuator, self.law_name = law, actuator, str(values["law"])
        self._values = values
        self.get_logger().info(f"now running law {self.law_name}")
        if hasattr(self, "_config_pub"):
            self._publish_config()
        return SetParametersResult(successful=True)

    def _publish_config(self) -> None:
        """What this controller runs with, on ``/fourws/node_config`` (latched)."""
        values = getattr(self, "_values", None) or {
            p: self.get_parameter(p).value for p in self._BUILD_PARAMS}
        msg = topics.message_class(topics.NODE_CONFIG)()
        msg.data = json.dumps({"node": self.get_name(), "role": topics.Role.CONTROLLER.value,
                               "config": {
                                   "law": self.law_name,
                                   "law_options": json.loads(values["law_options_json"]
                                                             or "{}"),
                                   "vehicle": self.vehicle.name,
                                   "belief_vehicle": self.law.vehicle.to_dict(),
                                   "belief_scale_front": float(values["belief_scale_front"]),
                                   "belief_scale_rear": float(values["belief_scale_rear"]),
                                   "angle_limit_rad": self.actuator.angle_limit_rad,
                                   "rate_limit_radps": self.actuator.rate_limit_rad_per_s,
                                   "control_period_s": self.dt_s}}, sort_keys=True)
        self._config_pub.publish(msg)

    def _on_sim_status(self, msg: Any) -> None:
        if not msg.final or not self.gate.admits_final(float(msg.sim_time_s)):
            return
        if not self._sim_ended and not self._closing and self.gate.last_step is None:
            # a peer's announced failure that already arrived comes first (the maneuver
            # node's docstring of _on_sim_status says why)
            why = self.peers.check_startup()
            if why:
                self._give_up(why)
                return
        self._sim_ended = True  # the simulator may leave now
        if bool(self.get_parameter("exit_when_done").value):
            self.get_logger().info(f"simulation ended ({msg.end_reason}); stopping")
            self.finished = True

    def on_shutdown(self, executor: Any) -> None:
        """Answer no more states; wait until what this node published is delivered."""
        self._closing = True
        reporting.wait_delivered(self.counts, self.get_logger(), executor, self._recorder,
                                 reporting.delivery_timeout(self))

    # ------------------------------------------------------------------ handshake
    def _on_state(self, raw: bytes) -> None:
        if self._closing:
            return
        try:
            state = codecs.parse_state(raw)
        except codecs.CodecError as exc:
            self.get_logger().error(f"ignored state: {exc}", throttle_duration_sec=1.0)
            return
        bad = codecs.outputs_finite(state)
        if bad:  # the simulator never publishes one: refused before it takes a step's place
            self.gate.rejections.add(topics.STATE, "non-finite state", bad)
            return
        if not self.gate.admit(state["step"], state["sim_time_s"], state["stamp_ns"]):
            self.get_logger().warning(f"refused a state: {self.gate.rejections.last}",
                                      throttle_duration_sec=1.0)
            return
        if not self.gate.lockstep:
            self._states.clear()  # realtime: only the latest state is worth an answer
        self._states[state["stamp_ns"]] = (state, time.monotonic())
        self._try_answer(fallback=False)

    def _on_driver(self, raw: bytes) -> None:
        try:
            key, cmd = codecs.parse_driver_input(raw)
        except codecs.CodecError as exc:
            self.get_logger().error(f"ignored driver input: {exc}", throttle_duration_sec=1.0)
            return
        if not math.isfinite(cmd.front_wheel_angle_rad):
            self.get_logger().error("ignored driver input: front_wheel_angle_rad is not finite",
                                    throttle_duration_sec=1.0)
            return
        if key in self._driver:
            self.get_logger().warning("refused a second driver input for one state",
                                      throttle_duration_sec=1.0)
            return
        self._driver[key] = cmd.front_wheel_angle_rad
        self._last_front = cmd.front_wheel_angle_rad
        if len(self._driver) > topics.STREAM_DEPTH:
            self._driver.pop(next(iter(self._driver)))
        self._try_answer(fallback=False)

    def _check_wait(self) -> None:
        self._run_nodes.poll()
        if self._states:
            self._try_answer(fallback=False)  # held until the publishers matched
        if self._sim_ended or self._closing:
            return
        if not self._states:
            why = (self.peers.check_startup() if self.gate.last_step is None
                   else self.peers.gone())
            if why:
                self._give_up(why)
            return
        stamp, (state, since) = next(iter(self._states.items()))
        waited = time.monotonic() - since
        if waited > WAIT_REPORT_S and stamp != self._reported:
            # says so once per state: in the log and on /rosout, where fourws run reads it
            self._reported = stamp
            pubs = sorted(i.node_name for i in
                          self.get_publishers_info_by_topic(topics.DRIVER_INPUT))
            self.get_logger().warning(
                f"state step {state['step']} (t = {state['sim_time_s']:.2f} s) waits "
                f"{waited:.1f} s for its {topics.DRIVER_INPUT} (stamp {stamp} ns); "
                f"publishers of {topics.DRIVER_INPUT}: {', '.join(pubs) or 'none'}")
        wait = float(self.get_parameter("driver_wait_s").value)
        if wait > 0.0 and waited > wait:
            self._try_answer(fallback=True)
        gone = self.peers.gone()
        if gone:
            self._give_up(gone)

    def _give_up(self, why: str) -> None:
        """The graph did not come together, or the simulator left: stop, saying why."""
        self.get_logger().error(why)
        self.stop_reason = why
        self.exit_code = EXIT_PEERS
        self._closing = self.finished = True

    def _try_answer(self, fallback: bool) -> None:
        if not self._answered_once:
            # the first answer waits (states and driver inputs kept) until the command
            # publisher has matched the run's subscribers (the recorder among them)
            if not self._states or not self.matched.ready():
                return
            self._answered_once = True
        while self._states:
            key, (state, _since) = next(iter(self._states.items()))
            front = self._driver.pop(key, None)
            if front is None:
                if not fallback:
                    return  # lockstep: the states are answered in their order
                front = self._last_front
                self.fallbacks += 1
                self.get_logger().warning(
                    f"no driver input for state step {state['step']}; used the latest "
                    f"({self.fallbacks} fallbacks)", throttle_duration_sec=1.0)
            # drop driver inputs older than this tick
            for old in [k for k in self._driver if k < key]:
                del self._driver[old]
            del self._states[key]
            self._answer(state, front)

    def _answer(self, state: dict[str, Any], front: float) -> None:
        try:
            law_cmd = self.law.rear_angle(law_input(state, front))
            angle = self.actuator.apply(law_cmd, self.dt_s)
            self.pub.publish(self._cmd_encoder.encode(angle, 0.0, self.law_name,
                                                      state["stamp_ns"], state["step"]))
        except FourwsError as exc:
            # never publish a non-finite command: the simulator times out to zero rear steer
            self.get_logger().error(f"no command for step {state['step']}: {exc}",
                                    throttle_duration_sec=1.0)


def main(args: list[str] | None = None) -> int:
    """Console entry point ``controller``."""
    return run_node(ControllerNode, args, name="fourws_controller")


if __name__ == "__main__":
    sys.exit(main())
