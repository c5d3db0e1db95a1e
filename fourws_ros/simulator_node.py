# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Simulator node: the vehicle model of a run, publishing its state and taking the answers.

The node is an adapter: what happens on a driver input, a rear-steer command, the recorder's
progress and the passing of time is the clock mode's, :class:`fourws_run.clock_modes.LockstepClock`
or :class:`~fourws_run.clock_modes.RealtimeClock` (no ROS there; read their module docstring
for the two modes), on the tick sequence of :mod:`fourws_run.ticks` that the offline twin
shares. The node declares the parameters, builds the core, converts messages, publishes what
the clock hands it (state and ``/clock`` on every tick, odometry/IMU every ``viz_period_s``,
status every ``status_period_s``) and ends the run.

Trust
-----
Inputs that cannot be this run's answers -- another tick's or no tick's stamp, a second
answer, non-finite or impossible values, a command naming a state that was never published --
are refused and counted by reason (``SimulatorStatus.rejected_*``). In realtime, where the
latest input is applied as it comes, driver inputs and commands are also taken only from the
run's maneuver and controller nodes (publisher identity from the ROS graph): a foreign
publisher copying the run's stamps cannot steer the car.

Liveness
--------
The run starts once every subscriber the run expects has matched the state publisher and the
answers have publishers (:class:`fourws_ros.peers.PeerWatch`); a graph missing a node after
``startup_timeout_s``, or one whose node announced a configuration failure, ends the node with
one line naming the missing peer. A lockstep tick without its answers for ``answer_timeout_s``
of wall time, or a peer that leaves the graph, ends the run as failed, naming the node.

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

import dataclasses
import json
import math
import sys
import time
from typing import Any, Callable

from rcl_interfaces.msg import SetParametersResult
from std_srvs.srv import SetBool, Trigger

from fourws_ros import conversions, peers, reporting, topics
from fourws_ros.identity import PublisherNames, RunNodeFilter
from fourws_ros.node_base import FourwsNode
from fourws_ros.scene_publisher import ScenePublisher
from fourws_ros.simulator_params import declare_parameters
from fourws_ros.runtime import EXIT_PEERS, report_phase, run_node
from fourws_run import codecs
from fourws_run.clock_modes import (CLOCK_MODES, DRIVER_INPUT, LockstepClock, RealtimeClock,
                                    make_clock)
from fourws_run.ticks import FlowWindow, InputLimits, Tick, TickEngine, whole_multiple
from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import ParameterError, UnknownNameError
from fourws_sim.maneuvers import make_maneuver
from fourws_sim.params import Tire
from fourws_sim.simulator import Simulator

#: Period of the housekeeping timer (start, lockstep waits, the final status), s.
HOUSEKEEPING_S = 0.01
#: After the simulation ended: how long (wall) the final status waits for the recorder to
#: hold everything the run sent, s.
FINAL_WAIT_S = 10.0
#: Topics whose counts the simulator knows for flow control: its own recorded publications
#: and the answers it accepted.
FLOW_TOPICS = (*(t for t in topics.RECORDED_TOPICS
                 if topics.WRITER_ROLES[t] == (topics.Role.SIMULATOR,)),
               topics.DRIVER_INPUT, topics.REAR_STEER_CMD)


class SimulatorNode(FourwsNode):
    """Vehicle simulator (see module docstring)."""

    #: Parameters that may change while the node runs (validated, cached in ``_cfg``).
    _LIVE = ("viz_period_s", "status_period_s", "answer_timeout_s", "recorder_timeout_s",
             "driver_timeout_s", "initial_speed_mps", "command_stale_periods")

    def __init__(self) -> None:
        super().__init__("fourws_simulator")
        declare_parameters(self)
        self._cfg: dict[str, Any] = {name: self._param(name) for name in self._LIVE}
        self.add_on_set_parameters_callback(self._on_set)
        self.finished = False  # run_node: stop spinning
        self.stop_reason = ""  # run_node: exit code 3 (the run stopped for its own reason)
        self.ended = ""  # why the simulation ended ('' while it runs)
        self._final_sent = False
        self._final_due = 0.0
        self._build_core()
        #: realtime takes answers only from the run's nodes: run_node spins with message info
        self.needs_message_info = self.clock_mode == "realtime"
        self._create_ros_interfaces()
        self.clock = self._make_clock()
        #: the run should go (autostart, or un-paused by /fourws/pause): it starts once the
        #: graph is complete
        self._run_wanted = bool(self._param("autostart"))
        self._timer = self.create_timer(HOUSEKEEPING_S, self._housekeeping)
        self.get_logger().info(
            f"{self.model_name} on {self.vehicle.name}, {self.clock_mode}, dt "
            f"{self.dt_s} s, control {self.control_period_s} s"
            + ("" if self._run_wanted else " (paused)"))

    # ------------------------------------------------------------------ setup
    def _param(self, name: str) -> Any:
        return self.get_parameter(name).value

    def _build_core(self) -> None:
        # numba (about 0.5 s warm) only once the parameters are valid: a bad file fails fast
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
        report_phase("compiling")
        sim = Simulator(vehicle, model=self.model_name,
                        integrator=str(self._param("integrator")), dt_s=self.dt_s)
        self.engine = TickEngine(sim, self.control_period_s)
        # compile the numba kernels now, not in the first (realtime) step
        self.engine.reset(float(self._cfg["initial_speed_mps"]))
        self.engine.advance(DriverCommand(0.0, 0.0), 0.0, n_steps=1)
        self.engine.reset(float(self._cfg["initial_speed_mps"]))
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
        # raw + fourws_run.codecs: short lockstep answer chain; realtime callbacks take the
        # message info (the publisher's identity)
        realtime = self.clock_mode == "realtime"
        self.driver_sub = self.create_subscription(
            msg(topics.DRIVER_INPUT), topics.DRIVER_INPUT,
            self._on_driver_from if realtime else self._on_driver, topics.STREAM_READ_QOS,
            raw=True)
        self.cmd_sub = self.create_subscription(
            msg(topics.REAR_STEER_CMD), topics.REAR_STEER_CMD,
            self._on_cmd_from if realtime else self._on_cmd, topics.STREAM_READ_QOS, raw=True)
        self.create_subscription(msg(topics.MANEUVER_STATUS), topics.MANEUVER_STATUS,
                                 self._on_maneuver_status, topics.STATUS_READ_QOS)
        self.create_subscription(msg(topics.RECORDER_STATUS), topics.RECORDER_STATUS,
                                 self._on_recorder_status, topics.STATUS_READ_QOS)
        self._recorder = reporting.RecorderWatch(self, subscribe=False)
        self._recorder_seen = int(self._param("recorder_window")) == 0
        self._run_nodes = RunNodeFilter(
            PublisherNames(self), lambda role_param: str(self._param(role_param)),
            lambda topic, detail: self.clock.rejections.add(topic, "not from the run's node",
                                                            detail))
        self.peers = peers.PeerWatch(self, float(self._param("startup_timeout_s")))
        state_subscribers = self.matched.expected.get(
            topics.STATE, int(self._param("expected_state_subscribers")))
        self.peers.need_subscribers(self.state_pub, topics.STATE, state_subscribers)
        if state_subscribers:
            self.peers.need_publishers(self.driver_sub, topics.DRIVER_INPUT)
            self.peers.need_publishers(self.cmd_sub, topics.REAR_STEER_CMD)
        # state, odometry, IMU and clock go out as CDR bytes written straight from the outputs
        # (fourws_run.codecs), not through Python messages: a shorter lockstep tick, and less
        # time holding the GIL in the realtime thread
        self._state_encoder = codecs.StateEncoder(self.model_name, topics.FRAME_BODY)
        self._odom_encoder = codecs.OdometryEncoder(topics.FRAME_ODOM, topics.FRAME_BODY)
        self._imu_encoder = codecs.ImuEncoder(topics.FRAME_BODY)
        self._end_s = float(self._param("end_time_s"))
        self.scene: ScenePublisher | None = None
        if bool(self._param("publish_scene")):
            self.scene = ScenePublisher(self, self.counts, self.vehicle, self._maneuver(),
                                        float(self._param("path_period_s")))
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

    def _make_clock(self) -> LockstepClock | RealtimeClock:
        """The clock mode's object, with a fresh engine state and answer book."""
        self.engine.reset(float(self._cfg["initial_speed_mps"]))
        self._next_viz_s = 0.0
        self._next_status_s = 0.0
        common = dict(engine=self.engine, sink=self, limits=self.limits)
        if self.clock_mode == "lockstep":
            return make_clock("lockstep", **common,
                              window=FlowWindow(int(self._param("recorder_window")),
                                                FLOW_TOPICS),
                              sent_counts=self._sent_counts,
                              answer_timeout_s=lambda: float(self._cfg["answer_timeout_s"]),
                              recorder_timeout_s=lambda: float(
                                  self._cfg["recorder_timeout_s"]))
        return make_clock("realtime", **common, state_steps=self.n_state,
                          stale_after_s=lambda: (int(self._cfg["command_stale_periods"])
                                                 * self.control_period_s),
                          driver_timeout_s=lambda: float(self._cfg["driver_timeout_s"]),
                          answer_timeout_s=lambda: float(self._cfg["answer_timeout_s"]),
                          priority=int(self._param("realtime_priority")),
                          warn=self.get_logger().warning)

    def _on_set(self, params: list[Any]) -> SetParametersResult:
        """Validate live changes (ranges are enforced by the descriptors); cache the values."""
        for p in params:
            if p.name in self._LIVE and p.name != "command_stale_periods" and not (
                    isinstance(p.value, float) and math.isfinite(p.value)):
                return SetParametersResult(successful=False,
                                           reason=f"{p.name}: must be a finite float")
        for p in params:
            if p.name in self._LIVE:
                self._cfg[p.name] = p.value
        return SetParametersResult(successful=True)

    # ------------------------------------------------------------------ the sink of the clock
    def publish_state(self, tick: Tick) -> bool:
        """Publish the state of ``tick`` (first: the answers' critical path starts there),
        then the clock (cheap: one time stamp)."""
        try:
            raw = self._state_encoder.encode(tick.outputs, tick.t, tick.step)
        except conversions.NonFiniteError as exc:
            self.end(f"non-finite state at t = {tick.t:.4f} s: {exc}", True)
            return False
        self.state_pub.publish(raw)
        self.clock_pub.publish(codecs.encode_clock(tick.t))
        return True

    def side_publications(self, tick: Tick) -> list[Callable[[], bool]]:
        """The rest of ``tick``'s publications, in order: the scene's transforms (and
        markers when due), its path and course when due, odometry and IMU and the status when
        due; at ``end_time_s`` the end of
        the run after this state (the clock calls them now, or realtime one per integration
        step, :class:`fourws_run.clock_modes.RealtimeClock`: at most four of them, so at the
        default 5 ms state period each has a step of its own)."""
        t = tick.t
        jobs: list[Callable[[], bool]] = []
        viz_due = t >= self._next_viz_s - 1e-12
        if viz_due:
            self._next_viz_s = t + self._cfg["viz_period_s"]
        if self.scene is not None:
            jobs += [lambda publish=publish: publish() or True
                     for publish in self.scene.publications(tick, viz_due)]
        if viz_due:
            def odometry() -> bool:
                self.odom_pub.publish(self._odom_encoder.encode(tick.outputs, tick.stamp_ns))
                self.imu_pub.publish(self._imu_encoder.encode(tick.outputs, tick.stamp_ns))
                return True
            jobs.append(odometry)
        if t >= self._next_status_s - 1e-12:
            self._next_status_s = t + self._cfg["status_period_s"]
            jobs.append(lambda: self._publish_status(t) or True)
        if self._end_s > 0.0 and t >= self._end_s - 1e-12:
            jobs.append(lambda: self.end(f"end time {self._end_s:g} s reached", False) or False)
        return jobs

    def _maneuver(self) -> Any:
        """The run's maneuver (``maneuver_json``), for the scene's course; None without."""
        text = str(self._param("maneuver_json"))
        if not text:
            return None
        try:
            return make_maneuver(json.loads(text), self.vehicle)
        except json.JSONDecodeError as exc:
            raise ParameterError("maneuver_json", f"not JSON ({exc})") from None

    def report_wait(self, t: float) -> None:
        """A tick has waited a second: a status says for what."""
        self._publish_status(t)

    def silent_node(self, missing: str) -> str:
        """The node whose answer is missing, by its ROS name."""
        if missing == DRIVER_INPUT:
            return f"the maneuver node ({self._param('maneuver_node')})"
        return f"the controller node ({self._param('controller_node')})"

    def end(self, reason: str, failed: bool) -> None:
        """The simulation ends: final status, then (``exit_when_done``) deliver and exit."""
        if self.ended:
            return
        self.ended = reason
        self.clock.pause()
        if failed:
            self.stop_reason = reason
            self.get_logger().error(f"run stopped: {reason}")
        else:
            self.get_logger().info(f"run ended: {reason}")
        self._final_due = time.monotonic()
        self._try_final()

    def _sent_counts(self) -> dict[str, int]:
        sent = dict(self.counts.counts)
        sent[topics.DRIVER_INPUT] = self.clock.book.driver_inputs_accepted
        sent[topics.REAR_STEER_CMD] = self.clock.book.commands_accepted
        return sent

    # ------------------------------------------------------------------ inputs
    def _on_driver(self, raw: bytes) -> None:
        try:
            stamp, cmd = codecs.parse_driver_input(raw)
        except codecs.CodecError as exc:
            self.clock.rejections.add(topics.DRIVER_INPUT, "not a DriverInput", str(exc))
            return
        self.clock.offer_driver(stamp, cmd)

    def _on_driver_from(self, raw: bytes, info: Any) -> None:
        self._run_nodes.offer(topics.DRIVER_INPUT, info, "maneuver_node", raw, self._on_driver)

    def _on_cmd(self, raw: bytes) -> None:
        try:
            msg = codecs.parse_rear_steer_command(raw)
        except codecs.CodecError as exc:
            self.clock.rejections.add(topics.REAR_STEER_CMD, "not a RearSteerCommand", str(exc))
            return
        self.clock.offer_command(msg["state_step"], msg["state_stamp_ns"], msg["angle_rad"])

    def _on_cmd_from(self, raw: bytes, info: Any) -> None:
        self._run_nodes.offer(topics.REAR_STEER_CMD, info, "controller_node", raw,
                              self._on_cmd)

    def _on_maneuver_status(self, msg: Any) -> None:
        if not msg.done or self.ended:
            return
        stamp = conversions.stamp_to_ns(msg.header.stamp)
        # lockstep: the maneuver ends the run instead of answering the awaited state;
        # realtime: it must name a published state
        if not self.clock.is_awaited(stamp):
            self.clock.rejections.add(topics.MANEUVER_STATUS, "done for no awaited state",
                                      f"stamp {stamp} ns")
            return
        self.end(f"maneuver {msg.maneuver!r} {msg.event or 'done'}", False)

    def _on_recorder_status(self, msg: Any) -> None:
        self._recorder.update(msg)
        self._recorder_seen = True
        if self.ended:
            self._try_final()
            return
        self.clock.recorder_stored(self._recorder.stored or {})

    # ------------------------------------------------------------------ services
    def _on_reset(self, _request: Any, response: Any) -> Any:
        if isinstance(self.clock, RealtimeClock) and self.clock.started \
                and not self.clock.paused:
            response.success = False
            response.message = "pause the realtime simulation before a reset"
            return response
        self.clock = self._make_clock()
        if self.scene is not None:
            self.scene.restart()
        self.ended = ""
        self.stop_reason = ""
        self._final_sent = False
        response.success = True
        response.message = f"reset to {self._param('initial_speed_mps')} m/s at t = 0"
        return response

    def _on_pause(self, request: Any, response: Any) -> Any:
        pause = bool(request.data)
        self._run_wanted = not pause
        if pause:
            self.clock.pause()
        elif self.clock.started and not self.ended:
            self.clock.resume()
        # (not started yet: housekeeping starts it once the graph is complete)
        response.success = True
        response.message = "paused" if pause else "running"
        return response

    # ------------------------------------------------------------------ running
    def _housekeeping(self) -> None:
        if self.ended:
            self._try_final()
            return
        self._run_nodes.poll()
        clock = self.clock
        if not clock.started:
            why = self.peers.check_startup(self._start_waits)
            if why:
                self.exit_code = EXIT_PEERS
                self.end(why, True)
            elif self._run_wanted and self._graph_ready():
                clock.resume()
            return
        if clock.paused:
            return
        gone = self.peers.gone()
        if gone:
            self.exit_code = EXIT_PEERS
            self.end(f"{gone}; {self._waiting_text()}".rstrip("; "), True)
            return
        clock.housekeeping()

    def _waiting_text(self) -> str:
        waiting = self.clock.waiting_for()
        return f"the simulation waited for {waiting}" if waiting else ""

    def _graph_ready(self) -> bool:
        return self.peers.ready() and self._recorder_seen and self.matched.ready()

    def _start_waits(self) -> list[str]:
        """What the start waits for besides the peers: the recorder's first status (its
        stored counts pace a lockstep run) and the run's subscribers of each publication."""
        out = [] if self._recorder_seen else [f"a first {topics.RECORDER_STATUS}"]
        if not self.matched.ready():
            out += self.matched.unmatched_text()
        return out

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
        sent = self._sent_counts()
        return any(sent.get(t, 0) > watch.stored[t] for t in FLOW_TOPICS
                   if t in watch.stored and t != topics.SIM_STATUS)

    def _publish_status(self, t: float, final: bool = False) -> None:
        clock = self.clock
        book = clock.book
        pacer = clock.pacer
        msg = topics.message_class(topics.SIM_STATUS)()
        conversions.set_stamp(msg.header.stamp, max(t, 0.0))
        msg.clock_mode = self.clock_mode
        msg.sim_time_s = float(t)
        msg.step_lateness_s = float(pacer.lateness_s)
        msg.max_lateness_s = float(pacer.max_lateness_s)
        msg.p99_lateness_s = pacer.percentile(99.0)
        msg.steps = int(self.engine.sim.step_count)
        msg.wall_time_s = float(clock.wall_time_s)
        msg.overruns = int(pacer.overruns)
        overruns = pacer.take_overruns()
        msg.overrun_times_s = [o[0] for o in overruns]
        msg.overrun_lateness_s = [o[1] for o in overruns]
        msg.stale_commands = int(clock.stale_commands)
        msg.command_timed_out = bool(clock.command_timed_out)
        msg.running = not (final or clock.paused)
        msg.stop_reason = self.stop_reason
        msg.end_reason = self.ended if final else ""
        msg.waiting_for = "" if self.ended else clock.waiting_for()
        msg.driver_inputs_accepted = int(book.driver_inputs_accepted)
        msg.commands_accepted = int(book.commands_accepted)
        msg.late_commands = int(book.late_commands)
        msg.final = final
        reporting.publish_counted_status(self.status_pub, msg, self.counts, book.rejections)

    def on_shutdown(self, executor: Any) -> None:
        """Stop the realtime thread, publish the final status if the run did not end, log the
        timing, and wait until every subscriber has what was published."""
        self.clock.pause()
        summary = self.clock.summary()
        if summary:
            self.get_logger().info(summary)
        if not self.ended:
            self.ended = "stopped before the maneuver was done (signal)"
        if not self._final_sent:
            self._final_sent = True
            self._publish_status(self.engine.sim.time_s, final=True)
        reporting.wait_delivered(self.counts, self.get_logger(), executor, self._recorder,
                                 reporting.delivery_timeout(self))


def main(args: list[str] | None = None) -> int:
    """Console entry point ``simulator``."""
    return run_node(SimulatorNode, args, name="fourws_simulator")


if __name__ == "__main__":
    sys.exit(main())
