# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Simulator node: the vehicle model of a run, publishing its state and taking the answers.

The node is an adapter: the tick sequence, the trust rules for incoming messages, realtime
pacing and recorder flow control are :mod:`fourws_run.ticks` (shared with the offline twin
:func:`fourws_run.closed_loop.run_closed_loop`); the node converts messages and owns the ROS
objects.

Clock modes
-----------
``lockstep`` (deterministic, faster than real time)
    Tick ``k``: publish ``VehicleState`` ``y_k`` (and ``/clock``); wait until the maneuver
    answered with the ``DriverInput`` stamped ``y_k``'s stamp and the controller with the
    ``RearSteerCommand`` whose ``state_step`` and ``state_stamp`` are ``y_k``'s; integrate
    one control period with those inputs held; publish ``y_{k+1}``. Bit-identical to the
    offline twin. With ``recorder_window`` > 0 the next tick is published only while the
    recorder has stored all but at most that many messages of every recorded topic
    (:class:`fourws_run.ticks.FlowWindow`): a slow recorder slows the run, it never loses data.
``realtime`` (paced by the wall clock)
    A thread integrates one step every ``integration_step_s`` of wall time, holds the latest
    valid driver input and command (zero-order hold), publishes the state every
    ``state_period_s``. Step lateness and every overrun go into the status messages (and so
    into the bag).

Trust
-----
Inputs that cannot be this run's answers -- another tick's or no tick's stamp, a second
answer, non-finite or impossible values, a command naming a state that was never published --
are refused and counted by reason (``SimulatorStatus.rejected_*``). A command's age is the
simulation time since the state it answers was published, from the node's own record, so no
message can keep a dead controller's last command alive.

Missing answers. Lockstep never runs a tick on anything but its answers, so a loaded machine
cannot change the numbers: it waits (after 1 s a status says for what), and after
``command_timeout_s`` of wall time (default 60 s) it stops the run as failed, naming the node
that stopped answering. Realtime cannot wait: a missing command means zero rear steer (counted,
``command_timed_out``), and ``driver_timeout_s`` of simulation time without a driver input
stops the run, naming the maneuver node.

End of a run
------------
When the maneuver reports ``done`` for the state the simulator is waiting on (or the
simulation diverges), the node stops integrating, publishes a final status (``final``, the
reason, every count), waits until every subscriber acknowledged all it published, and exits
(``exit_when_done``; otherwise it stays paused). A diverged run exits with code 3.

Services: ``/fourws/reset`` (``std_srvs/Trigger``) back to the initial speed at t = 0;
``/fourws/pause`` (``std_srvs/SetBool``, true = pause). With ``autostart`` false the node
starts paused (the launcher un-pauses it once the graph is complete).
"""

from __future__ import annotations

import ctypes
import dataclasses
import gc
import math
import os
import sys
import threading
import time
from typing import Any

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
from rclpy.node import Node
from std_srvs.srv import SetBool, Trigger

from fourws_ros import conversions, reporting, topics
from fourws_ros.runtime import run_node
from fourws_run import codecs
from fourws_run.ticks import (FlowWindow, InputLimits, LockstepAnswers, Pacer, RealtimeAnswers,
                              Tick, TickEngine, whole_multiple)
from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import ParameterError, UnknownNameError
from fourws_sim.params import Tire
from fourws_sim.simulator import Simulator

CLOCK_MODES = ("lockstep", "realtime")
#: Shortest/longest integration step a parameter may set, s.
MIN_STEP_S, MAX_STEP_S = 1e-5, 0.1
#: Period of the housekeeping timer (start, lockstep waits, the final status), s.
HOUSEKEEPING_S = 0.01
#: After the simulation ended: how long (wall) the final status waits for the recorder to
#: hold everything the run sent, s.
FINAL_WAIT_S = 10.0
#: GIL switch interval while the realtime thread runs, s (Python's default 5 ms would let a
#: subscriber callback delay a step by up to 5 ms).
_SWITCH_INTERVAL_S = 1e-4
#: Topics whose counts the simulator knows for flow control (its own and the accepted answers).
_FLOW_TOPICS = (topics.STATE, topics.ODOM, topics.IMU, topics.SIM_STATUS, topics.DRIVER_INPUT,
                topics.REAR_STEER_CMD)


def _frange(lo: float, hi: float) -> list[FloatingPointRange]:
    return [FloatingPointRange(from_value=lo, to_value=hi)]


class SimulatorNode(Node):
    """Vehicle simulator (see module docstring)."""

    def __init__(self) -> None:
        super().__init__("fourws_simulator")
        self._declare_parameters()
        self._cfg: dict[str, Any] = {name: self._param(name) for name in self._LIVE}
        self.add_on_set_parameters_callback(self._on_set)
        self._build_core()
        self._create_ros_interfaces()
        self.finished = False  # run_node: stop spinning
        self.stop_reason = ""  # run_node: exit code 3 (the run stopped for its own reason)
        self.ended = ""  # why the simulation ended ('' while it runs)
        self.paused = not bool(self._param("autostart"))
        self._lock = threading.Lock()
        self._rt_thread: threading.Thread | None = None
        self._reset_state()
        self._timer = self.create_timer(HOUSEKEEPING_S, self._housekeeping)
        self.get_logger().info(
            f"{self.model_name} on {self.vehicle.name}, {self.clock_mode}, dt "
            f"{self.dt_s} s, control {self.control_period_s} s"
            + (" (paused)" if self.paused else ""))

    # ------------------------------------------------------------------ setup
    def _declare_parameters(self) -> None:
        ro = dict(read_only=True)
        declare = self.declare_parameter
        declare("vehicle", "table_8_1", ParameterDescriptor(
            description="vehicle (config/vehicles name or YAML path)", **ro))
        declare("vehicle_json", "", ParameterDescriptor(
            description="the simulated vehicle as a whole vehicle-file mapping in JSON "
                        "(overrides vehicle when not empty)", **ro))
        declare("model", "8dof", ParameterDescriptor(
            description="vehicle model (fourws_sim.models name)", **ro))
        declare("tire", "", ParameterDescriptor(
            description="tire model override ('' = the vehicle file's)", **ro))
        declare("integrator", "rk4", ParameterDescriptor(description="integrator name", **ro))
        declare("integration_step_s", 1e-3, ParameterDescriptor(
            description="integration step, s",
            floating_point_range=_frange(MIN_STEP_S, MAX_STEP_S), **ro))
        declare("control_period_s", 0.01, ParameterDescriptor(
            description="control period (driver/controller tick), s; whole multiple of the "
                        "integration step", floating_point_range=_frange(MIN_STEP_S, 1.0), **ro))
        declare("state_period_s", 0.01, ParameterDescriptor(
            description="realtime: state publish period, s; whole multiple of the step",
            floating_point_range=_frange(MIN_STEP_S, 1.0), **ro))
        declare("viz_period_s", 0.02, ParameterDescriptor(
            description="odometry/IMU publish period (simulation time), s",
            floating_point_range=_frange(MIN_STEP_S, 10.0)))
        declare("status_period_s", 0.1, ParameterDescriptor(
            description="sim_status publish period (simulation time), s",
            floating_point_range=_frange(1e-3, 10.0)))
        declare("clock_mode", "lockstep", ParameterDescriptor(
            description="lockstep | realtime", **ro))
        declare("initial_speed_mps", 23.611111111111111, ParameterDescriptor(
            description="forward speed at reset, m/s", floating_point_range=_frange(0.0, 100.0)))
        declare("command_timeout_s", 60.0, ParameterDescriptor(
            description="realtime: rear-steer command age (simulation time since the state "
                        "it answers) after which rear steer falls back to zero; lockstep: "
                        "wall time to wait for a tick's answers before the run stops as "
                        "failed (lockstep never substitutes an input), s",
            floating_point_range=_frange(1e-3, 3600.0)))
        declare("driver_timeout_s", 1.0, ParameterDescriptor(
            description="realtime: simulation time without a new driver input after which "
                        "the run stops (the maneuver node stopped answering), s",
            floating_point_range=_frange(1e-3, 60.0)))
        declare("autostart", True, ParameterDescriptor(
            description="start running at once (false: paused until /fourws/pause false)"))
        declare("controller_node", topics.NODE_NAMES[topics.Role.CONTROLLER], ParameterDescriptor(
            description="ROS node name of the controller (named when it stops answering)",
            read_only=True))
        declare("exit_when_done", True, ParameterDescriptor(
            description="exit once the run has ended and everything published is delivered "
                        "(false: stay up, paused)"))
        declare("expected_state_subscribers", 0, ParameterDescriptor(
            description="lockstep: wait for this many /fourws/state subscribers before the "
                        "first tick", integer_range=[IntegerRange(from_value=0, to_value=64,
                                                                  step=1)], **ro))
        declare("realtime_priority", 20, ParameterDescriptor(
            description="realtime: SCHED_FIFO priority of the integration thread (1-99; 0 = "
                        "normal scheduling). Needs CAP_SYS_NICE; without it the node warns "
                        "and runs with normal priority", integer_range=[IntegerRange(
                            from_value=0, to_value=99, step=1)], read_only=True))
        declare("recorder_window", 0, ParameterDescriptor(
            description="lockstep: run at most this many messages of any recorded topic "
                        "ahead of what the recorder reports stored (0 = no recorder flow "
                        "control; must stay below the stream history depth)",
            integer_range=[IntegerRange(from_value=0, to_value=topics.STREAM_DEPTH // 2,
                                        step=1)], read_only=True))

    def _param(self, name: str) -> Any:
        return self.get_parameter(name).value

    def _build_core(self) -> None:
        # numba (about 0.5 s) only once the parameters are valid: a bad file fails fast
        from fourws_sim.tires import TIRES

        self.clock_mode = str(self._param("clock_mode"))
        if self.clock_mode not in CLOCK_MODES:
            raise ParameterError("clock_mode", f"must be one of {', '.join(CLOCK_MODES)}, got "
                                 f"{self.clock_mode!r}")
        vehicle = conversions.vehicle_from_params(self)
        tire = str(self._param("tire"))
        if tire:
            if tire not in TIRES:
                raise UnknownNameError("tire", tire, list(TIRES))
            base = vehicle.tire if vehicle.tire is not None else Tire()
            vehicle = dataclasses.replace(vehicle, tire=dataclasses.replace(base, model=tire))
        self.vehicle = vehicle
        self.model_name = str(self._param("model"))
        self.dt_s = float(self._param("integration_step_s"))
        self.control_period_s = float(self._param("control_period_s"))
        self.n_state = whole_multiple(float(self._param("state_period_s")), self.dt_s,
                                      "state_period_s")
        sim = Simulator(vehicle, model=self.model_name,
                        integrator=str(self._param("integrator")), dt_s=self.dt_s)
        self.engine = TickEngine(sim, self.control_period_s)
        self.n_control = self.engine.n_control
        # compile the numba kernels now, not in the first (realtime) step
        self.engine.reset(float(self._cfg["initial_speed_mps"]))
        self.engine.advance(DriverCommand(0.0, 0.0), 0.0, n_steps=1)
        self.limits = InputLimits.for_vehicle(vehicle)

    def _create_ros_interfaces(self) -> None:
        msg = topics.message_class
        self.counts = reporting.PublishCounts()
        self.state_pub = self.counts.publisher(self, topics.STATE)
        self.clock_pub = self.create_publisher(msg(topics.CLOCK), topics.CLOCK, topics.CLOCK_QOS)
        self.odom_pub = self.counts.publisher(self, topics.ODOM)
        self.imu_pub = self.counts.publisher(self, topics.IMU)
        self.status_pub = self.counts.publisher(self, topics.SIM_STATUS)
        self.matched = reporting.match_wait(self, self.counts)
        # raw + fourws_run.codecs: short lockstep answer chain
        self.driver_sub = self.create_subscription(msg(topics.DRIVER_INPUT),
                                                   topics.DRIVER_INPUT, self._on_driver,
                                                   topics.STREAM_QOS, raw=True)
        self.cmd_sub = self.create_subscription(msg(topics.REAR_STEER_CMD),
                                                topics.REAR_STEER_CMD, self._on_cmd,
                                                topics.STREAM_QOS, raw=True)
        self.create_subscription(msg(topics.MANEUVER_STATUS), topics.MANEUVER_STATUS,
                                 self._on_maneuver_status, topics.STATUS_QOS)
        self.create_subscription(msg(topics.RECORDER_STATUS), topics.RECORDER_STATUS,
                                 self._on_recorder_status, topics.STATUS_QOS)
        self.window = FlowWindow(int(self._param("recorder_window")), _FLOW_TOPICS)
        self._recorder = reporting.RecorderWatch(self, subscribe=False)
        # state, odometry, IMU and clock go out as CDR bytes written straight from the outputs
        # (fourws_run.codecs), not through Python messages: a shorter lockstep tick, and less
        # time holding the GIL in the realtime thread
        self._state_encoder = codecs.StateEncoder(self.model_name, topics.FRAME_BODY)
        self._odom_encoder = codecs.OdometryEncoder(topics.FRAME_ODOM, topics.FRAME_BODY)
        self._imu_encoder = codecs.ImuEncoder(topics.FRAME_BODY)
        self.create_service(Trigger, topics.SRV_RESET, self._on_reset)
        self.create_service(SetBool, topics.SRV_PAUSE, self._on_pause)
        config = {
            "vehicle": self.vehicle.to_dict(), "model": self.model_name,
            "tire": self.vehicle.tire.model if self.vehicle.tire is not None else "",
            "integrator": str(self._param("integrator")), "integration_step_s": self.dt_s,
            "control_period_s": self.control_period_s,
            "state_period_s": float(self._param("state_period_s")),
            "clock_mode": self.clock_mode,
            "initial_speed_mps": float(self._cfg["initial_speed_mps"])}
        self._config_pub = reporting.publish_node_config(self, self.counts,
                                                         topics.Role.SIMULATOR, config)

    _LIVE = ("viz_period_s", "status_period_s", "command_timeout_s", "driver_timeout_s",
             "initial_speed_mps")

    def _on_set(self, params: list[Any]) -> SetParametersResult:
        """Validate live changes (ranges are enforced by the descriptors); cache the values."""
        for p in params:
            if p.name in self._LIVE and not (
                    isinstance(p.value, float) and math.isfinite(p.value)):
                return SetParametersResult(successful=False,
                                           reason=f"{p.name}: must be a finite float")
        for p in params:
            if p.name in self._LIVE:
                self._cfg[p.name] = p.value
        return SetParametersResult(successful=True)

    def _reset_state(self) -> None:
        self.engine.reset(float(self._cfg["initial_speed_mps"]))
        self.answers = LockstepAnswers(self.limits)
        self.rt_answers = RealtimeAnswers(self.limits)
        self.pacer = Pacer(self.dt_s)
        self.stale_commands = 0
        self.command_timed_out = False
        self._next_viz_s = 0.0
        self._next_status_s = 0.0
        self._held: Tick | None = None  # lockstep: a tick held back by flow control
        self._held_since = 0.0
        self.held_s = 0.0  # lockstep: wall time spent waiting for the recorder
        self._recorder_seen = self.window.window == 0
        self.answer_wait_s = 0.0  # lockstep: wall time from state sent to both answers in
        self.tick_work_s = 0.0  # lockstep: wall time integrating and publishing
        self.ticks = 0
        self._sent_at = 0.0
        self._await_since = 0.0
        self._reported_wait = False
        self._final_sent = False
        self._final_due = 0.0
        self._started = False

    @property
    def rejections(self) -> Any:
        """The refusals of the current mode's answer book."""
        return self.answers.rejections if self.clock_mode == "lockstep" \
            else self.rt_answers.rejections

    def _book(self) -> LockstepAnswers | RealtimeAnswers:
        return self.answers if self.clock_mode == "lockstep" else self.rt_answers

    # ------------------------------------------------------------------ inputs
    def _on_driver(self, raw: bytes) -> None:
        try:
            stamp, cmd = codecs.parse_driver_input(raw)
        except codecs.CodecError as exc:
            self.rejections.add(topics.DRIVER_INPUT, "not a DriverInput", str(exc))
            return
        if self.clock_mode == "realtime":
            with self._lock:
                self.rt_answers.offer_driver(stamp, cmd)
            return
        if self.answers.offer_driver(stamp, cmd) and self.answers.complete:
            self._lockstep_advance()

    def _on_cmd(self, raw: bytes) -> None:
        try:
            msg = codecs.parse_rear_steer_command(raw)
        except codecs.CodecError as exc:
            self.rejections.add(topics.REAR_STEER_CMD, "not a RearSteerCommand", str(exc))
            return
        if self.clock_mode == "realtime":
            with self._lock:
                self.rt_answers.offer_command(msg["state_step"], msg["state_stamp_ns"],
                                              msg["angle_rad"])
            return
        if self.answers.offer_command(msg["state_step"], msg["state_stamp_ns"],
                                      msg["angle_rad"]) and self.answers.complete:
            self._lockstep_advance()

    def _on_maneuver_status(self, msg: Any) -> None:
        if not msg.done or self.ended:
            return
        stamp = conversions.stamp_to_ns(msg.header.stamp)
        if self.clock_mode == "lockstep":
            # the maneuver ends the run instead of answering the state the simulator waits on
            tick = self.answers.awaited
            if tick is None or stamp != tick.stamp_ns:
                self.rejections.add(topics.MANEUVER_STATUS, "done for no awaited state",
                                    f"stamp {stamp} ns")
                return
        elif not self.rt_answers.was_published(stamp):
            self.rejections.add(topics.MANEUVER_STATUS, "done for no published state",
                                f"stamp {stamp} ns")
            return
        end = msg.event or "done"
        self._end(f"maneuver {msg.maneuver!r} {end}")

    def _on_recorder_status(self, msg: Any) -> None:
        self._recorder.update(msg)
        self.window.update(self._recorder.stored or {})
        if self.ended:
            self._try_final()
            return
        self._recorder_seen = True
        held = self._held
        if held is not None and not self._holding_back():
            self._send_tick(held)

    # ------------------------------------------------------------------ services
    def _on_reset(self, _request: Any, response: Any) -> Any:
        if self.clock_mode == "realtime" and self._rt_thread is not None:
            response.success = False
            response.message = "pause the realtime simulation before a reset"
            return response
        with self._lock:
            self._reset_state()
            self.ended = ""
        response.success = True
        response.message = f"reset to {self._param('initial_speed_mps')} m/s at t = 0"
        if not self.paused:
            self._start()
        return response

    def _on_pause(self, request: Any, response: Any) -> Any:
        pause = bool(request.data)
        if pause and not self.paused:
            self.paused = True
            self._stop_rt_thread()
        elif not pause and self.paused:
            self.paused = False
            if self.clock_mode == "lockstep" and self._started:
                if self.answers.complete:  # answers that came while paused count now
                    self._lockstep_advance()
            else:
                self._start()
        response.success = True
        response.message = "paused" if self.paused else "running"
        return response

    # ------------------------------------------------------------------ running
    def _housekeeping(self) -> None:
        if self.ended:
            self._try_final()
            return
        if self.paused:
            return
        if not self._started:
            self._start()
            return
        if self.clock_mode == "lockstep":
            self._report_long_wait()
            tick = self.answers.awaited
            if tick is not None and time.monotonic() - self._await_since \
                    > self._cfg["command_timeout_s"]:
                # Lockstep never runs a tick on inputs other than the answers (a slow
                # machine must not change the numbers): an answer this late means a node
                # has stopped working, and the run stops, naming it.
                missing = self.answers.waiting_for
                self._end(f"no {missing} for the state at t = {tick.t:.2f} s within "
                          f"{self._cfg['command_timeout_s']:g} s (wall time); "
                          + self._silent_node(missing) + " stopped answering", failed=True)

    def _silent_node(self, missing: str) -> str:
        """The node whose answer is missing: the maneuver's driver input comes first (the
        controller waits for it), so a missing driver input names the maneuver node."""
        if "driver" in missing:
            return f"the maneuver node ({topics.NODE_NAMES[topics.Role.MANEUVER]})"
        return f"the controller node ({self._param('controller_node')})"

    def _report_long_wait(self) -> None:
        """A tick (or a held tick) waiting over a second: publish a status saying for what,
        so a stalled run names the node (the periodic statuses are sent as ticks go out)."""
        tick = self.answers.awaited or self._held
        if tick is not None and not self._reported_wait and \
                time.monotonic() - (self._await_since if self._held is None
                                    else self._held_since) > 1.0:
            self._reported_wait = True
            self._publish_status(tick.t)

    def _graph_ready(self) -> bool:
        need = int(self._param("expected_state_subscribers"))
        return (self.state_pub.get_subscription_count() >= need
                and (need == 0 or (self.driver_sub.get_publisher_count() >= 1
                                   and self.cmd_sub.get_publisher_count() >= 1))
                and self._recorder_seen and self.matched.ready())

    def _start(self) -> None:
        if self.ended or self._started and self.clock_mode == "lockstep":
            return
        if not self._graph_ready():
            return  # housekeeping tries again
        self._started = True
        if self.clock_mode == "lockstep":
            self._publish_tick(self.engine.tick)
        else:
            self._rt_thread = threading.Thread(target=self._realtime_loop, daemon=True)
            self._rt_thread.start()

    def _end(self, reason: str, failed: bool = False) -> None:
        """The simulation ends: final status, then (``exit_when_done``) deliver and exit."""
        if self.ended:
            return
        self.ended = reason
        self.paused = True
        if threading.current_thread() is not self._rt_thread:
            self._stop_rt_thread()
        if failed:
            self.stop_reason = reason
            self.get_logger().error(f"run stopped: {reason}")
        else:
            self.get_logger().info(f"run ended: {reason}")
        self._final_due = time.monotonic()
        self._try_final()

    def _try_final(self) -> None:
        """Send the final status once the recorder holds everything the run sent (so a node
        that exits on the final status, as a user's controller may, loses nothing in
        flight), or after :data:`FINAL_WAIT_S` of waiting, or at once without a recorder."""
        if not self.ended or self._final_sent:
            return
        if self._recorder_behind() and time.monotonic() - self._final_due < FINAL_WAIT_S:
            return  # the recorder's next status (or the housekeeping timer) tries again
        self._final_sent = True
        self._publish_status(self.engine.sim.time_s, final=True)
        if bool(self._param("exit_when_done")):
            self.finished = True

    def _recorder_behind(self) -> bool:
        """A recorder is there and has not stored all the run has sent on some topic."""
        watch = self._recorder
        if watch.stored is None or watch.silent():
            return False
        book = self._book()
        sent = dict(self.counts.counts)
        sent[topics.DRIVER_INPUT] = book.driver_inputs_accepted
        sent[topics.REAR_STEER_CMD] = book.commands_accepted
        return any(sent.get(t, 0) > watch.stored[t] for t in _FLOW_TOPICS
                   if t in watch.stored and t != topics.SIM_STATUS)

    # -- lockstep
    def _holding_back(self) -> str:
        sent = dict(self.counts.counts)
        sent[topics.DRIVER_INPUT] = self.answers.driver_inputs_accepted
        sent[topics.REAR_STEER_CMD] = self.answers.commands_accepted
        return self.window.holding_back(sent)

    def _publish_tick(self, tick: Tick) -> None:
        if self._holding_back():
            self._held = tick  # the recorder's next status releases it
            self._held_since = time.monotonic()
            self._reported_wait = False
            return
        self._send_tick(tick)

    def _send_tick(self, tick: Tick) -> None:
        if self._held is not None:
            self.held_s += time.monotonic() - self._held_since
        self._held = None
        try:
            raw = self._state_encoder.encode(tick.outputs, tick.t, tick.step)
        except conversions.NonFiniteError as exc:
            self._end(f"non-finite state at t = {tick.t:.4f} s: {exc}", failed=True)
            return
        self.answers.expect(tick)
        self._await_since = time.monotonic()
        self._reported_wait = False
        self._sent_at = time.perf_counter()
        self.state_pub.publish(raw)  # first: the answers' critical path starts here
        self.clock_pub.publish(codecs.encode_clock(tick.t))
        self._publish_side(tick)

    def _lockstep_advance(self) -> None:
        if self.paused or self.ended or self.answers.awaited is None \
                or self.answers.driver is None:
            return
        now = time.perf_counter()
        self.answer_wait_s += now - self._sent_at
        tick = self.answers.awaited
        driver, rear, timed_out = self.answers.close()
        self.command_timed_out = timed_out
        if timed_out:
            self.stale_commands += 1
            self.get_logger().warning(
                f"no rear-steer command for step {tick.step} (t = {tick.t:.2f} s) in time: "
                f"zero rear steer ({self.stale_commands} ticks so far)",
                throttle_duration_sec=1.0)
        self.ticks += 1
        if self.engine.advance(driver, rear):
            self._publish_tick(self.engine.tick)
        else:
            self._end(self.engine.diverged, failed=True)
        self.tick_work_s += time.perf_counter() - now

    def _publish_side(self, tick: Tick) -> None:
        """Odometry and IMU (every ``viz_period_s``) and status (every ``status_period_s``)
        of the state just published."""
        t = tick.t
        if t >= self._next_viz_s - 1e-12:
            self.odom_pub.publish(self._odom_encoder.encode(tick.outputs, tick.stamp_ns))
            self.imu_pub.publish(self._imu_encoder.encode(tick.outputs, tick.stamp_ns))
            self._next_viz_s = t + self._cfg["viz_period_s"]
        if t >= self._next_status_s - 1e-12:
            self._publish_status(t)
            self._next_status_s = t + self._cfg["status_period_s"]

    def _publish_status(self, t: float, final: bool = False) -> None:
        book = self._book()
        msg = topics.message_class(topics.SIM_STATUS)()
        conversions.set_stamp(msg.header.stamp, max(t, 0.0))
        msg.clock_mode = self.clock_mode
        msg.sim_time_s = float(t)
        pacer = self.pacer
        msg.step_lateness_s = float(pacer.lateness_s)
        msg.max_lateness_s = float(pacer.max_lateness_s)
        msg.p99_lateness_s = pacer.percentile(99.0)
        msg.steps = int(self.engine.sim.step_count)
        msg.overruns = int(pacer.overruns)
        overruns = pacer.take_overruns()
        msg.overrun_times_s = [o[0] for o in overruns]
        msg.overrun_lateness_s = [o[1] for o in overruns]
        msg.stale_commands = int(self.stale_commands)
        msg.command_timed_out = bool(self.command_timed_out)
        msg.running = not (final or self.paused)
        msg.stop_reason = self.stop_reason
        msg.end_reason = self.ended if final else ""
        msg.waiting_for = self._waiting_for()
        msg.driver_inputs_accepted = int(book.driver_inputs_accepted)
        msg.commands_accepted = int(book.commands_accepted)
        msg.late_commands = int(book.late_commands)
        msg.final = final
        reporting.publish_counted_status(self.status_pub, msg, self.counts, book.rejections)

    def _waiting_for(self) -> str:
        if self.ended:
            return ""
        if self.clock_mode == "lockstep":
            if self._held is not None:
                return f"recorder ({self._holding_back()})"
            missing = self.answers.waiting_for
            return {"driver input": "driver input (maneuver node)",
                    "rear-steer command": "rear-steer command (controller node)"}.get(
                        missing, missing.replace("driver input", "driver input (maneuver "
                                                 "node)"))
        age = self.engine.sim.time_s - self.rt_answers.driver_time_s
        return "driver input (maneuver node)" if age > self._cfg["command_timeout_s"] else ""

    # -- realtime
    def _realtime_loop(self) -> None:
        # Objects alive now (modules, numba, rclpy) leave the collector's generations, so a
        # full collection during the run has little to scan (it holds the GIL meanwhile).
        gc.collect()
        gc.freeze()
        _make_thread_realtime(int(self._param("realtime_priority")), self.get_logger())
        old_interval = sys.getswitchinterval()
        sys.setswitchinterval(_SWITCH_INTERVAL_S)
        try:
            self._realtime_run()
        finally:
            sys.setswitchinterval(old_interval)

    def _realtime_run(self) -> None:
        engine, book, pacer = self.engine, self.rt_answers, self.pacer
        sim = engine.sim
        pacer.start(sim.time_s)
        k = 0
        rear = 0.0
        driver = book.driver
        while not self.paused and not self.ended:
            pacer.wait(sim.time_s)
            with self._lock:
                if k % self.n_control == 0:
                    t = sim.time_s
                    rear, timed_out = book.rear_at(t, float(self._cfg["command_timeout_s"]))
                    # at the start a controller gets one timeout to send its first command
                    timed_out = timed_out and (book.commands_accepted > 0
                                               or t > self._cfg["command_timeout_s"])
                    self.stale_commands += timed_out
                    self.command_timed_out = timed_out
                    driver = book.driver
                    quiet = t - max(book.driver_time_s, 0.0)
                    if quiet > self._cfg["driver_timeout_s"]:
                        self._end(f"no driver input for {quiet:.2f} s of simulation time at "
                                  f"t = {t:.2f} s: {self._silent_node('driver')} stopped "
                                  "answering",
                                  failed=True)
                        return
                if not engine.advance(driver, rear, n_steps=1):
                    self._end(engine.diverged, failed=True)
                    return
                k += 1
                if k % self.n_state == 0:
                    tick = engine.tick
                    try:
                        raw = self._state_encoder.encode(tick.outputs, tick.t, tick.step)
                    except conversions.NonFiniteError as exc:
                        self._end(f"non-finite state at t = {tick.t:.4f} s: {exc}",
                                  failed=True)
                        return
                    book.published(tick)
                    self.state_pub.publish(raw)
                    self.clock_pub.publish(codecs.encode_clock(tick.t))
                    self._publish_side(tick)

    def _stop_rt_thread(self) -> None:
        thread = self._rt_thread
        if thread is not None:
            thread.join(timeout=2.0)
            self._rt_thread = None
            self._started = False

    def on_shutdown(self, executor: Any) -> None:
        """Stop the realtime thread, publish the final status if the run did not end, log the
        timing, and wait until every subscriber has what was published."""
        self.paused = True
        self._stop_rt_thread()
        pacer = self.pacer
        if self.clock_mode == "realtime" and self.engine.sim.step_count:
            self.get_logger().info(
                f"realtime: {self.engine.sim.step_count} steps, step lateness p99 "
                f"{pacer.percentile(99.0) * 1e3:.3f} ms, max "
                f"{pacer.max_lateness_s * 1e3:.3f} ms at t = {pacer.max_lateness_at_s:.3f} s, "
                f"{pacer.overruns} overruns"
                + (" (t/late ms: " + ", ".join(f"{t:.3f}/{late * 1e3:.2f}"
                                               for t, late in pacer.first_overruns) + ")"
                   if pacer.first_overruns else ""))
        if self.clock_mode == "lockstep" and self.ticks:
            self.get_logger().info(
                f"lockstep: {self.ticks} ticks, mean answer wait "
                f"{self.answer_wait_s / self.ticks * 1e3:.3f} ms, mean own work "
                f"{self.tick_work_s / self.ticks * 1e3:.3f} ms per tick; waited for the "
                f"recorder {self.window.holds} times, {self.held_s:.3f} s in all")
        if not self.ended:
            self.ended = "stopped before the maneuver was done (signal)"
        if not self._final_sent:
            self._final_sent = True
            self._publish_status(self.engine.sim.time_s, final=True)
        reporting.wait_delivered(self.counts, self.get_logger(), executor, self._recorder,
                                 reporting.delivery_timeout(self))


def _make_thread_realtime(priority: int, logger: Any) -> None:
    """SCHED_FIFO for the calling thread and 1 ns timer slack (sleep wakes on time)."""
    pr_set_timerslack = 29
    try:
        ctypes.CDLL(None).prctl(pr_set_timerslack, 1, 0, 0, 0)
    except (OSError, AttributeError):
        pass
    if priority <= 0:
        return
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (PermissionError, OSError) as exc:
        logger.warning(f"realtime priority {priority} not granted ({exc}); running with normal "
                       "scheduling, expect more step lateness under load")


def main(args: list[str] | None = None) -> int:
    """Console entry point ``simulator``."""
    return run_node(SimulatorNode, args, name="fourws_simulator")


if __name__ == "__main__":
    sys.exit(main())
