"""Simulator node: integrates a vehicle model and publishes its state (thin over the core).

Clock modes
-----------
``lockstep`` (deterministic, faster than real time)
    Tick ``k``: publish ``VehicleState`` ``y_k`` (and ``/clock``); wait until the maneuver
    answered with the ``DriverInput`` stamped ``y_k``'s stamp and the controller with the
    ``RearSteerCommand`` whose ``state_step`` is ``y_k.step``; integrate one control period
    with those inputs held; publish ``y_{k+1}``. This is the sequence of
    :func:`fourws_sim.closed_loop.run_closed_loop` (its docstring is the contract), so a
    lockstep run is bit-identical to it. ``state_period_s`` does not apply: one state per tick.
``realtime`` (paced by the wall clock)
    A dedicated thread integrates one step every ``integration_step_s`` of wall time,
    samples the latest driver input and rear-steer command at each control tick (zero-order
    hold), publishes the state every ``state_period_s``. Each step's start is compared with
    its wall-clock deadline: the lateness (last and max) and the overruns (steps that started
    a whole period late; the schedule is then re-based instead of racing to catch up) are
    published on ``/fourws/sim_status``.

Safety
------
* A rear-steer command older than ``command_timeout_s`` (simulation time in realtime mode,
  wall time waiting for the answer in lockstep mode) is replaced by zero rear steer; every
  such tick is counted (``stale_commands``) and flagged (``command_timed_out``).
* Commands that are not finite or exceed the vehicle's rear angle limit are ignored (logged,
  counted) — the timeout then applies. Non-finite driver inputs are ignored likewise.
* A non-finite state never leaves the node: the run stops, ``sim_status`` carries the reason
  (``running = false``), the process exits with code 3.

Services: ``/fourws/reset`` (``std_srvs/Trigger``) back to the initial speed at t = 0;
``/fourws/pause`` (``std_srvs/SetBool``, true = pause). With ``autostart`` false the node
starts paused (the launcher un-pauses it once the graph is complete).
"""

from __future__ import annotations

import dataclasses
import math
import sys
import threading
import time
from typing import Any

import numpy as np
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
from rclpy.node import Node

from fourws_ros import cdr, conversions, topics
from fourws_sim.errors import FourwsError, NonFiniteError, ParameterError, UnknownNameError

CLOCK_MODES = ("lockstep", "realtime")
#: Shortest/longest integration step a parameter may set, s.
MIN_STEP_S, MAX_STEP_S = 1e-5, 0.1
#: Lockstep: wall time to wait for the controller after it has missed a tick, s (a healthy
#: controller answers within ~1 ms).
LOST_WAIT_S = 0.02
#: Realtime: how many overruns are itemized in the shutdown log line.
MAX_OVERRUN_LOG = 20
#: Step-lateness histogram (realtime): bin width, s, and bin count (the last bin collects
#: everything later than 20 ms).
LATENESS_BIN_S = 1e-5
LATENESS_BINS = 2000
#: GIL switch interval while the realtime thread runs, s (Python's default 5 ms would let a
#: subscriber callback delay a step by up to 5 ms).
_SWITCH_INTERVAL_S = 1e-4


def _frange(lo: float, hi: float) -> list[FloatingPointRange]:
    return [FloatingPointRange(from_value=lo, to_value=hi)]


class SimulatorNode(Node):
    """Vehicle simulator (see module docstring)."""

    def __init__(self) -> None:
        super().__init__("fourws_simulator")
        ro = dict(read_only=True)
        self.declare_parameter("vehicle", "table_8_1", ParameterDescriptor(
            description="vehicle (config/vehicles name or YAML path)", **ro))
        self.declare_parameter("model", "8dof", ParameterDescriptor(
            description="vehicle model (fourws_sim.models name)", **ro))
        self.declare_parameter("tire", "", ParameterDescriptor(
            description="tire model override ('' = the vehicle file's)", **ro))
        self.declare_parameter("integrator", "rk4", ParameterDescriptor(
            description="integrator name", **ro))
        self.declare_parameter("integration_step_s", 1e-3, ParameterDescriptor(
            description="integration step, s", floating_point_range=_frange(MIN_STEP_S,
                                                                            MAX_STEP_S), **ro))
        self.declare_parameter("control_period_s", 0.01, ParameterDescriptor(
            description="control period (driver/controller tick), s; whole multiple of the "
                        "integration step", floating_point_range=_frange(MIN_STEP_S, 1.0), **ro))
        self.declare_parameter("state_period_s", 0.01, ParameterDescriptor(
            description="realtime: state publish period, s; whole multiple of the step",
            floating_point_range=_frange(MIN_STEP_S, 1.0), **ro))
        self.declare_parameter("viz_period_s", 0.02, ParameterDescriptor(
            description="odometry/IMU publish period (simulation time), s",
            floating_point_range=_frange(MIN_STEP_S, 10.0)))
        self.declare_parameter("status_period_s", 0.1, ParameterDescriptor(
            description="sim_status publish period (simulation time), s",
            floating_point_range=_frange(1e-3, 10.0)))
        self.declare_parameter("clock_mode", "lockstep", ParameterDescriptor(
            description="lockstep | realtime", **ro))
        self.declare_parameter("initial_speed_mps", 23.611111111111111, ParameterDescriptor(
            description="forward speed at reset, m/s", floating_point_range=_frange(0.0, 100.0)))
        self.declare_parameter("command_timeout_s", 1.0, ParameterDescriptor(
            description="rear-steer command age (realtime: simulation time; lockstep: wall "
                        "wait) after which rear steer falls back to zero, s",
            floating_point_range=_frange(1e-3, 60.0)))
        self.declare_parameter("autostart", True, ParameterDescriptor(
            description="start running at once (false: paused until /fourws/pause false)"))
        self.declare_parameter("expected_state_subscribers", 0, ParameterDescriptor(
            description="lockstep: wait for this many /fourws/state subscribers before the "
                        "first tick", integer_range=[IntegerRange(from_value=0, to_value=64,
                                                                  step=1)], **ro))
        self.declare_parameter("realtime_priority", 20, ParameterDescriptor(
            description="realtime: SCHED_FIFO priority of the integration thread (1-99; 0 = "
                        "normal scheduling). Needs CAP_SYS_NICE; without it the node warns "
                        "and runs with normal priority", integer_range=[IntegerRange(
                            from_value=0, to_value=99, step=1)], read_only=True))
        self.declare_parameter("recorder_window_ticks", 0, ParameterDescriptor(
            description="lockstep: run at most this many ticks ahead of the states the "
                        "recorder reports written (0 = no recorder flow control)",
            integer_range=[IntegerRange(from_value=0, to_value=topics.STREAM_DEPTH // 2,
                                        step=1)], read_only=True))
        self._cfg: dict[str, Any] = {name: self._param(name) for name in self._LIVE}
        self.add_on_set_parameters_callback(self._on_set)

        self._build_core()
        self._create_ros_interfaces()
        self.finished = False
        self.stop_reason = ""
        self.paused = not bool(self.get_parameter("autostart").value)
        self._lock = threading.Lock()
        self._rt_thread: threading.Thread | None = None
        self._reset_state()
        self._timer = self.create_timer(LOST_WAIT_S / 2, self._housekeeping)
        self.get_logger().info(
            f"{self.model_name} on {self.vehicle.name}, {self.clock_mode}, dt "
            f"{self.dt_s} s, control {self.control_period_s} s"
            + (" (paused)" if self.paused else ""))

    # ------------------------------------------------------------------ setup
    def _param(self, name: str) -> Any:
        return self.get_parameter(name).value

    def _build_core(self) -> None:
        from fourws_sim.params import Tire, load_vehicle
        from fourws_sim.simulator import Simulator

        self.clock_mode = str(self._param("clock_mode"))
        if self.clock_mode not in CLOCK_MODES:
            raise ParameterError("clock_mode", f"must be one of {', '.join(CLOCK_MODES)}, got "
                                 f"{self.clock_mode!r}")
        vehicle = load_vehicle(str(self._param("vehicle")))
        tire = str(self._param("tire"))
        if tire:
            from fourws_sim.tires import TIRES
            if tire not in TIRES:
                raise UnknownNameError("tire", tire, list(TIRES))
            base = vehicle.tire if vehicle.tire is not None else Tire()
            vehicle = dataclasses.replace(vehicle, tire=dataclasses.replace(base, model=tire))
        self.vehicle = vehicle
        self.model_name = str(self._param("model"))
        self.dt_s = float(self._param("integration_step_s"))
        self.control_period_s = float(self._param("control_period_s"))
        self.n_control = _whole_multiple(self.control_period_s, self.dt_s, "control_period_s")
        self.n_state = _whole_multiple(float(self._param("state_period_s")), self.dt_s,
                                       "state_period_s")
        self.sim = Simulator(vehicle, model=self.model_name,
                             integrator=str(self._param("integrator")), dt_s=self.dt_s)
        # compile the numba kernels now, not in the first (realtime) step
        from fourws_sim.closed_loop import simulator_inputs
        from fourws_sim.drivers import DriverCommand
        self.sim.reset(speed_mps=float(self._cfg["initial_speed_mps"]))
        self.sim.step(simulator_inputs(DriverCommand(0.0, 0.0), 0.0), n_steps=1)
        self.sim.outputs()
        self.rear_limit_rad = float(vehicle.actuators.rear_angle_limit_rad)

    def _create_ros_interfaces(self) -> None:
        from std_srvs.srv import SetBool, Trigger

        msg = topics.message_class
        self.state_pub = self.create_publisher(msg(topics.STATE), topics.STATE,
                                               topics.STREAM_QOS)
        self.clock_pub = self.create_publisher(msg(topics.CLOCK), topics.CLOCK,
                                               topics.CLOCK_QOS)
        self.odom_pub = self.create_publisher(msg(topics.ODOM), topics.ODOM, topics.STREAM_QOS)
        self.imu_pub = self.create_publisher(msg(topics.IMU), topics.IMU, topics.STREAM_QOS)
        self.status_pub = self.create_publisher(msg(topics.SIM_STATUS), topics.SIM_STATUS,
                                                topics.STATUS_QOS)
        # raw + fourws_ros.cdr: short lockstep answer chain
        self.driver_sub = self.create_subscription(msg(topics.DRIVER_INPUT),
                                                   topics.DRIVER_INPUT, self._on_driver,
                                                   topics.STREAM_QOS, raw=True)
        self.cmd_sub = self.create_subscription(msg(topics.REAR_STEER_CMD),
                                                topics.REAR_STEER_CMD, self._on_cmd,
                                                topics.STREAM_QOS, raw=True)
        self.create_subscription(msg(topics.RECORDER_PROGRESS), topics.RECORDER_PROGRESS,
                                 self._on_recorder_progress, topics.STATUS_QOS)
        self.recorder_window = int(self._param("recorder_window_ticks"))
        # state, odometry, IMU and clock go out as CDR bytes written straight from the outputs
        # (fourws_ros.cdr), not through Python messages: a shorter lockstep tick, and less
        # time holding the GIL in the realtime thread
        self._state_encoder = cdr.StateEncoder(self.model_name, topics.FRAME_BODY)
        self._odom_encoder = cdr.OdometryEncoder(topics.FRAME_ODOM, topics.FRAME_BODY)
        self._imu_encoder = cdr.ImuEncoder(topics.FRAME_BODY)
        self.create_service(Trigger, topics.SRV_RESET, self._on_reset)
        self.create_service(SetBool, topics.SRV_PAUSE, self._on_pause)

    _LIVE = ("viz_period_s", "status_period_s", "command_timeout_s", "initial_speed_mps")

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
        from fourws_sim.drivers import DriverCommand

        self.sim.reset(speed_mps=float(self._cfg["initial_speed_mps"]))
        self.step_count = 0
        self.driver = DriverCommand(0.0, 0.0)
        self.driver_stamp_ns = -1
        self.rear_cmd_rad = 0.0
        self.rear_cmd_step = -1
        self.rear_cmd_time_s = -math.inf
        self.stale_commands = 0
        self.command_timed_out = False
        self.lateness_s = 0.0
        self.max_lateness_s = 0.0
        self.lateness_hist = np.zeros(LATENESS_BINS, dtype=np.int64)
        self.overruns = 0
        self.max_lateness_at_s = 0.0
        self.overrun_log: list[tuple[float, float]] = []
        self.steps_done = 0
        self._next_viz_s = 0.0
        self._next_status_s = 0.0
        self._awaiting: _Tick | None = None  # lockstep: the state waiting for its answers
        self._blocked_state: Any = None  # lockstep: a tick held back by flow control
        self.ticks_published = 0
        self.recorder_states = 0
        self.answer_wait_s = 0.0  # lockstep: wall time from state sent to both answers in
        self.tick_work_s = 0.0  # lockstep: wall time integrating and publishing
        self._sent_at = 0.0
        self._await_since = 0.0
        self._started = False

    # ------------------------------------------------------------------ inputs
    def _on_driver(self, raw: bytes) -> None:
        try:
            stamp, cmd = cdr.parse_driver_input(raw)
            if not math.isfinite(sum(cmd.drive_torque_nm) + sum(cmd.brake_torque_nm)
                                 + cmd.front_wheel_angle_rad + cmd.steering_torque_nm
                                 + cmd.steering_wheel_angle_rad):
                conversions.check_finite_mapping(cmd.to_dict(), "driver input")
        except (cdr.CdrError, NonFiniteError) as exc:
            self.get_logger().error(f"ignored driver input: {exc}", throttle_duration_sec=1.0)
            return
        self.driver = cmd
        self.driver_stamp_ns = stamp
        if self._awaiting is not None:
            self._lockstep_try_advance()

    def _on_cmd(self, raw: bytes) -> None:
        try:
            msg = cdr.parse_rear_steer_command(raw)
        except cdr.CdrError as exc:
            self.get_logger().error(f"ignored rear-steer command: {exc}",
                                    throttle_duration_sec=1.0)
            return
        angle = msg["angle_rad"]
        if not math.isfinite(angle) or abs(angle) > self.rear_limit_rad * (1.0 + 1e-12):
            self.stale_commands += 1
            self.get_logger().error(
                f"ignored rear-steer command {angle!r} rad from law {msg['law']!r}: "
                f"{'not finite' if not math.isfinite(angle) else 'beyond the rear angle limit'}"
                f" ({self.rear_limit_rad} rad)", throttle_duration_sec=1.0)
            return
        self.rear_cmd_rad = angle
        self.rear_cmd_step = msg["state_step"]
        self.rear_cmd_time_s = msg["state_stamp_ns"] * 1e-9
        if self._awaiting is not None:
            self._lockstep_try_advance()

    def _on_recorder_progress(self, msg: Any) -> None:
        self.recorder_states = int(msg.data)
        blocked = self._blocked_state
        if blocked is not None and self.ticks_published - self.recorder_states <= \
                self.recorder_window:
            self._send_tick(blocked)

    # ------------------------------------------------------------------ services
    def _on_reset(self, _request: Any, response: Any) -> Any:
        if self.clock_mode == "realtime" and self._rt_thread is not None:
            response.success = False
            response.message = "pause the realtime simulation before a reset"
            return response
        with self._lock:
            self._reset_state()
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
                self._lockstep_try_advance()  # answers that came while paused count now
            else:
                self._start()
        response.success = True
        response.message = "paused" if self.paused else "running"
        return response

    # ------------------------------------------------------------------ running
    def _housekeeping(self) -> None:
        if self.finished or self.paused:
            return
        if not self._started:
            self._start()
            return
        if self.clock_mode == "lockstep" and self._awaiting is not None:
            waited = time.monotonic() - self._await_since
            # once the controller has missed a tick, the following ones wait only
            # LOST_WAIT_S (a stopped controller must not cost a full timeout per tick; one
            # that answers again within it is back in the loop)
            limit = LOST_WAIT_S if self.command_timed_out else self._cfg["command_timeout_s"]
            if waited > limit:
                self._lockstep_try_advance(timed_out=True)

    def _graph_ready(self) -> bool:
        need = int(self._param("expected_state_subscribers"))
        return (self.state_pub.get_subscription_count() >= need
                and (need == 0 or (self.driver_sub.get_publisher_count() >= 1
                                   and self.cmd_sub.get_publisher_count() >= 1)))

    def _start(self) -> None:
        if self.finished or self._started and self.clock_mode == "lockstep":
            return
        if self.clock_mode == "lockstep":
            if not self._graph_ready():
                return  # housekeeping tries again
            self._started = True
            self._publish_tick()
        else:
            self._started = True
            self._rt_thread = threading.Thread(target=self._realtime_loop, daemon=True)
            self._rt_thread.start()

    def _stop(self, reason: str) -> None:
        self.stop_reason = reason
        self.finished = True
        self.get_logger().error(f"run stopped: {reason}")
        self._publish_status(self.sim.time_s, running=False)

    # -- lockstep
    def _publish_tick(self) -> None:
        outputs = self.sim.outputs()
        t = float(outputs.get("sim_time_s", self.sim.time_s))
        step = self.step_count
        try:
            raw = self._state_encoder.encode(outputs, t, step)
        except NonFiniteError as exc:
            self._stop(f"non-finite state: {exc}")
            return
        tick = _Tick(raw, outputs, t, step, conversions.time_to_ns(t))
        window = self.recorder_window
        if window and self.ticks_published - self.recorder_states > window:
            self._blocked_state = tick  # the recorder's progress releases it
            return
        self._send_tick(tick)

    def _send_tick(self, tick: "_Tick") -> None:
        self._blocked_state = None
        self.ticks_published += 1
        self._awaiting = tick
        self._await_since = time.monotonic()
        self._sent_at = time.perf_counter()
        self.state_pub.publish(tick.raw)  # first: the answers' critical path starts here
        self.clock_pub.publish(cdr.encode_clock(tick.t))
        self._publish_side(tick.t, tick.outputs, tick.stamp_ns)

    def _lockstep_try_advance(self, timed_out: bool = False) -> None:
        tick = self._awaiting
        if tick is None or self.paused or self.finished:
            return
        have_driver = self.driver_stamp_ns == tick.stamp_ns
        have_cmd = self.rear_cmd_step == tick.step
        if not have_driver:
            # the maneuver is done (the launcher ends the run) or has stopped answering
            if timed_out:
                self.get_logger().warning(f"no driver input for step {tick.step}",
                                          throttle_duration_sec=5.0)
            return
        if not have_cmd and not timed_out:
            return
        rear = self.rear_cmd_rad if have_cmd else 0.0
        self.command_timed_out = not have_cmd
        if not have_cmd:
            self.stale_commands += 1
            self.get_logger().warning(
                f"no rear-steer command for step {tick.step} (t = {tick.t:.2f} s) "
                f"within {self._cfg['command_timeout_s']} s: zero rear steer "
                f"({self.stale_commands} ticks so far)", throttle_duration_sec=1.0)
        self._awaiting = None
        now = time.perf_counter()
        self.answer_wait_s += now - self._sent_at
        if self._integrate(rear, self.n_control):
            self._publish_tick()
        self.tick_work_s += time.perf_counter() - now

    def _integrate(self, rear_rad: float, n_steps: int) -> bool:
        from fourws_sim.closed_loop import simulator_inputs

        u = simulator_inputs(self.driver, rear_rad)
        try:
            # the simulator raises on a non-finite state; derived outputs are checked when
            # the state message is built (conversions.state_msg)
            self.sim.step(u, n_steps=n_steps)
        except FourwsError as exc:
            self._stop(f"non-finite state at t = {self.sim.time_s:.4f} s: {exc}")
            return False
        self.step_count += n_steps
        self.steps_done += n_steps
        return True

    def _publish_side(self, t: float, outputs: Any, stamp_ns: int) -> None:
        """Odometry and IMU (every ``viz_period_s``) and status (every ``status_period_s``) of
        the state published at ``t`` (s) from its ``outputs``, stamped ``stamp_ns``."""
        if t >= self._next_viz_s - 1e-12:
            self.odom_pub.publish(self._odom_encoder.encode(outputs, stamp_ns))
            self.imu_pub.publish(self._imu_encoder.encode(outputs, stamp_ns))
            self._next_viz_s = t + self._cfg["viz_period_s"]
        if t >= self._next_status_s - 1e-12:
            self._publish_status(t, running=True)
            self._next_status_s = t + self._cfg["status_period_s"]

    def lateness_percentile(self, q: float) -> float:
        """Percentile ``q`` (0..100) of the realtime step lateness so far, s (bin upper edge;
        0 before the first realtime step)."""
        total = int(self.lateness_hist.sum())
        if total == 0:
            return 0.0
        idx = int(np.searchsorted(np.cumsum(self.lateness_hist), q / 100.0 * total))
        return (min(idx, LATENESS_BINS - 1) + 1) * LATENESS_BIN_S

    def _publish_status(self, t: float, running: bool) -> None:
        msg = topics.message_class(topics.SIM_STATUS)()
        conversions.set_stamp(msg.header.stamp, max(t, 0.0))
        msg.clock_mode = self.clock_mode
        msg.sim_time_s = float(t)
        msg.step_lateness_s = float(self.lateness_s)
        msg.max_lateness_s = float(self.max_lateness_s)
        msg.p99_lateness_s = self.lateness_percentile(99.0)
        msg.steps = int(self.steps_done)
        msg.overruns = int(self.overruns)
        msg.stale_commands = int(self.stale_commands)
        msg.command_timed_out = bool(self.command_timed_out)
        msg.running = running
        msg.stop_reason = self.stop_reason
        self.status_pub.publish(msg)

    # -- realtime
    def _realtime_loop(self) -> None:
        import gc

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
        dt = self.dt_s
        timeout = float(self._cfg["command_timeout_s"])
        t0 = time.perf_counter() - self.sim.time_s
        k = 0
        rear = 0.0
        while not self.paused and not self.finished:
            deadline = t0 + self.sim.time_s
            now = time.perf_counter()
            if now < deadline:
                time.sleep(deadline - now)
                now = time.perf_counter()
            late = now - deadline
            self.lateness_s = late
            self.lateness_hist[min(max(int(late / LATENESS_BIN_S), 0), LATENESS_BINS - 1)] += 1
            if late > self.max_lateness_s:
                self.max_lateness_s = late
                self.max_lateness_at_s = self.sim.time_s
            if late > dt:
                self.overruns += 1
                if len(self.overrun_log) < MAX_OVERRUN_LOG:
                    self.overrun_log.append((self.sim.time_s, late))
                t0 += late  # re-base: simulated time does not race to catch up
            with self._lock:
                if k % self.n_control == 0:
                    t = self.sim.time_s
                    if t - self.rear_cmd_time_s <= timeout:
                        rear = self.rear_cmd_rad
                        self.command_timed_out = False
                    else:
                        rear = 0.0
                        if self.rear_cmd_step >= 0 or t > timeout:
                            self.stale_commands += 1
                            self.command_timed_out = True
                if not self._integrate(rear, 1):
                    return
                k += 1
                if k % self.n_state == 0:
                    outputs = self.sim.outputs()
                    t = float(outputs.get("sim_time_s", self.sim.time_s))
                    try:
                        raw = self._state_encoder.encode(outputs, t, self.step_count)
                    except NonFiniteError as exc:
                        self._stop(f"non-finite state: {exc}")
                        return
                    self.state_pub.publish(raw)
                    self.clock_pub.publish(cdr.encode_clock(t))
                    self._publish_side(t, outputs, conversions.time_to_ns(t))

    def _stop_rt_thread(self) -> None:
        thread = self._rt_thread
        if thread is not None:
            thread.join(timeout=2.0)
            self._rt_thread = None
            self._started = False

    def on_shutdown(self, _executor: Any) -> None:
        """Stop the realtime thread, publish the final status, log the timing."""
        if self.clock_mode == "realtime" and self.steps_done:
            self.get_logger().info(
                f"realtime: {self.steps_done} steps, step lateness p99 "
                f"{self.lateness_percentile(99.0) * 1e3:.3f} ms, max "
                f"{self.max_lateness_s * 1e3:.3f} ms at t = {self.max_lateness_at_s:.3f} s, "
                f"{self.overruns} overruns"
                + (" (t/late ms: " + ", ".join(f"{t:.3f}/{late * 1e3:.2f}"
                                               for t, late in self.overrun_log) + ")"
                   if self.overrun_log else ""))
        if self.clock_mode == "lockstep" and self.ticks_published > 1:
            n = self.ticks_published - 1
            self.get_logger().info(
                f"lockstep: {n} ticks, mean answer wait {self.answer_wait_s / n * 1e3:.3f} ms, "
                f"mean own work {self.tick_work_s / n * 1e3:.3f} ms per tick")
        self.paused = True
        self._stop_rt_thread()
        if not self.stop_reason:
            self._publish_status(self.sim.time_s, running=False)


@dataclasses.dataclass
class _Tick:
    """One lockstep state: its CDR bytes, the outputs it was made from, the exact simulation
    time (s), the integration step and the header stamp (ns) the answers carry."""

    raw: bytes
    outputs: Any
    t: float
    step: int
    stamp_ns: int


def _make_thread_realtime(priority: int, logger: Any) -> None:
    """SCHED_FIFO for the calling thread and 1 ns timer slack (sleep wakes on time)."""
    import ctypes
    import os

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


def _whole_multiple(period_s: float, step_s: float, field: str) -> int:
    ratio = period_s / step_s
    n = int(round(ratio))
    if n < 1 or abs(ratio - n) > 1e-9 * ratio:
        raise ParameterError(field, f"must be a whole multiple of integration_step_s "
                             f"({step_s} s), got {period_s} s")
    return n


def main(args: list[str] | None = None) -> int:
    """Console entry point ``simulator``."""
    from fourws_ros.runtime import run_node
    return run_node(SimulatorNode, args, name="fourws_simulator")


if __name__ == "__main__":
    sys.exit(main())
