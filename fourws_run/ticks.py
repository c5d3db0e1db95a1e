# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The tick sequence of a fourws run, without ROS: one implementation for the node graph and the
offline twin.

A run advances in control ticks. At tick ``k`` the simulator holds state ``y_k`` (a
:class:`Tick`); the maneuver answers it with a driver command ``d_k``, the controller with a
rear-wheel angle ``delta_r_k``; the simulator integrates one control period holding both and
reaches ``y_{k+1}``. The classes here are that sequence, used by both
:func:`fourws_run.closed_loop.run_closed_loop` (in-process answers) and the simulator node
(:mod:`fourws_ros.simulator_node`, answers arriving as messages), so a lockstep graph run and
the offline twin perform the same float operations in the same order.

* :class:`TickEngine` -- the vehicle simulation advanced tick by tick; a diverging simulation
  is an outcome (:attr:`TickEngine.diverged`), not an exception of the caller's;
* :class:`LockstepAnswers` -- the answers to the tick waiting to advance: accepts exactly one
  driver input stamped with the tick's stamp and one command naming the tick's step and stamp,
  refuses (and counts, by reason) everything that cannot be that answer: another tick's or no
  tick's stamp, a second answer, non-finite or physically impossible values;
* :class:`RealtimeAnswers` -- the same trust rules for the wall-clock mode, where the latest
  valid command is held: a command counts only for a state the simulator really published,
  and its age is measured from that state's own time, so no message can disable the command
  timeout;
* :class:`Pacer` -- realtime pacing: deadlines, lateness histogram, overruns (each overrun is
  kept with its time so it reaches the bag through the status messages);
* :class:`FlowWindow` -- lockstep flow control: the simulator runs at most ``window``
  messages ahead of what the recorder reports stored, on every recorded topic, so a slow
  recorder never loses a message (the DDS history is deeper than the window).
"""

from __future__ import annotations

import collections
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

from fourws_control import LawInput
from fourws_run import interface
from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import DivergedError, ParameterError
from fourws_sim.params import GRAVITY_MPS2, Vehicle
from fourws_sim.simulator import Inputs

#: Relative tolerance of "a period is a whole multiple of the integration step".
MULTIPLE_RTOL = 1e-9
#: How many past ticks the answer books remember (to tell a late or repeated answer from one
#: that belongs to no tick of this run).
TICK_MEMORY = 4000


def whole_multiple(period_s: float, step_s: float, field_name: str,
                   source: str | None = None) -> int:
    """``round(period_s / step_s)``, checked to be a whole number >= 1.

    The one check of "a period is a whole multiple of the integration step" (scenarios, node
    parameters and the offline runner call it).

    Raises
    ------
    ParameterError
        Non-finite or non-positive values, or a period that is not a whole multiple.
    """
    for name, value in ((field_name, period_s), ("integration_step_s", step_s)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value) or value <= 0.0:
            raise ParameterError(name, f"must be a finite number > 0, got {value!r}", source)
    ratio = period_s / step_s
    n = int(round(ratio))
    if n < 1 or abs(ratio - n) > MULTIPLE_RTOL * ratio:
        raise ParameterError(field_name, f"must be a whole multiple of integration_step_s "
                             f"({step_s} s), got {period_s} s", source)
    return n


@dataclass(frozen=True)
class Tick:
    """One published state.

    Attributes
    ----------
    step : int
        Integration steps since reset (``VehicleState.step``).
    t : float
        Simulation time, s: exactly the simulator's float (``VehicleState.sim_time_s``).
    stamp_ns : int
        ``header.stamp`` of the state: ``t`` rounded to the ns.
    outputs : mapping
        ``Simulator.outputs()`` (the ``VehicleState`` fields).
    """

    step: int
    t: float
    stamp_ns: int
    outputs: Mapping[str, Any]


def simulator_inputs(command: DriverCommand, rear_angle_rad: float) -> Any:
    """The :class:`fourws_sim.simulator.Inputs` of a driver command and a rear road-wheel
    angle (rad, after the actuator); the simulator maps them to its model's input order."""
    return Inputs(front_wheel_angle_rad=command.front_wheel_angle_rad,
                  rear_wheel_angle_rad=rear_angle_rad,
                  steering_torque_nm=command.steering_torque_nm,
                  drive_torque_nm=command.drive_torque_nm,
                  brake_torque_nm=command.brake_torque_nm)


def law_input(outputs: Mapping[str, Any], front_wheel_angle_rad: float) -> Any:
    """The :class:`fourws_control.LawInput` of a tick: the state's outputs (a
    ``Simulator.outputs()`` mapping or a decoded ``VehicleState``) and the driver's front
    road-wheel angle of the same tick; the time is the state's exact ``sim_time_s``.

    The one place a law input is built: the controller node and the offline twin both call it,
    so they hand the law the same Python floats.
    """
    return LawInput(delta_f_rad=float(front_wheel_angle_rad),
                    speed_mps=float(outputs["speed_mps"]),
                    yaw_rate_radps=float(outputs["yaw_rate_radps"]),
                    roll_rad=float(outputs["roll_rad"]),
                    roll_rate_radps=float(outputs["roll_rate_radps"]),
                    lateral_velocity_mps=float(outputs["lateral_velocity_mps"]),
                    time_s=float(outputs["sim_time_s"]))


class TickEngine:
    """A :class:`~fourws_sim.simulator.Simulator` advanced tick by tick.

    Parameters
    ----------
    sim : Simulator
        Reset to the run's initial state.
    control_period_s : float
        Control period, s (a whole multiple of ``sim.dt_s``).
    """

    def __init__(self, sim: Any, control_period_s: float) -> None:
        self.sim = sim
        self.control_period_s = float(control_period_s)
        self.n_control = whole_multiple(control_period_s, sim.dt_s, "control_period_s")
        #: Why the simulation could not go on ('' while it can): the divergence, with its time.
        self.diverged = ""
        self._tick: Tick | None = None

    @property
    def tick(self) -> Tick:
        """The current state as a :class:`Tick` (built when first asked for after a step)."""
        if self._tick is None:
            outputs = self.sim.outputs()
            t = float(outputs.get("sim_time_s", self.sim.time_s))
            self._tick = Tick(self.sim.step_count, t, interface.time_to_ns(t), outputs)
        return self._tick

    def advance(self, driver: DriverCommand, rear_rad: float,
                n_steps: int | None = None) -> bool:
        """Integrate ``n_steps`` (default one control period) holding the inputs; False if the
        simulation diverged (:attr:`diverged` says where; the state stays the last finite)."""
        try:
            self.sim.step(simulator_inputs(driver, rear_rad),
                          n_steps=self.n_control if n_steps is None else n_steps)
        except DivergedError as exc:
            self.diverged = f"the simulation diverged at t = {exc.time_s:.4f} s: {exc}"
            self._tick = None
            return False
        self._tick = None
        return True

    def reset(self, speed_mps: float) -> Tick:
        """Back to straight running at ``speed_mps`` at t = 0."""
        self.sim.reset(speed_mps=speed_mps)
        self.diverged = ""
        self._tick = None
        return self.tick


# ============================================================================ input trust

#: Largest road-wheel angle a driver input may command, rad (60 deg: beyond any car's lock).
FRONT_ANGLE_LIMIT_RAD = math.radians(60.0)
#: Largest steering-wheel angle, rad (3 turns each way: beyond any steering rack).
STEERING_WHEEL_LIMIT_RAD = 3 * 2 * math.pi


@dataclass(frozen=True)
class InputLimits:
    """What a driver input or rear-steer command may ask of the simulated vehicle.

    Attributes
    ----------
    rear_angle_limit_rad : float
        The vehicle's rear actuator limit (``actuators.rear_angle_limit_rad``).
    torque_limit_nm : float
        Largest drive or brake torque per wheel, N m: twice the car's weight times its wheel
        radius -- far beyond what any tire can transmit, so only nonsense is refused.
    front_angle_limit_rad, steering_wheel_limit_rad : float
        See :data:`FRONT_ANGLE_LIMIT_RAD`, :data:`STEERING_WHEEL_LIMIT_RAD`.
    """

    rear_angle_limit_rad: float
    torque_limit_nm: float
    front_angle_limit_rad: float = FRONT_ANGLE_LIMIT_RAD
    steering_wheel_limit_rad: float = STEERING_WHEEL_LIMIT_RAD

    @classmethod
    def for_vehicle(cls, vehicle: Vehicle) -> "InputLimits":
        """The limits of ``vehicle`` (wheel radius 0.5 m when it has no body data)."""
        radius = vehicle.body.wheel_radius_m if vehicle.body is not None else 0.5
        return cls(float(vehicle.actuators.rear_angle_limit_rad),
                   2.0 * vehicle.chassis.mass_kg * GRAVITY_MPS2 * radius)

    def driver_problem(self, cmd: DriverCommand) -> str:
        """Why ``cmd`` cannot be a driver input ('' if it can)."""
        values = [cmd.steering_wheel_angle_rad, cmd.front_wheel_angle_rad,
                  cmd.steering_torque_nm, *cmd.drive_torque_nm, *cmd.brake_torque_nm]
        if len(cmd.drive_torque_nm) != interface.N_WHEELS \
                or len(cmd.brake_torque_nm) != interface.N_WHEELS:
            return f"needs {interface.N_WHEELS} drive and brake torques"
        if not math.isfinite(sum(values)):
            return "not finite"
        if abs(cmd.front_wheel_angle_rad) > self.front_angle_limit_rad:
            return (f"front road-wheel angle {cmd.front_wheel_angle_rad:.4g} rad beyond "
                    f"{self.front_angle_limit_rad:.3g} rad")
        if abs(cmd.steering_wheel_angle_rad) > self.steering_wheel_limit_rad:
            return (f"steering-wheel angle {cmd.steering_wheel_angle_rad:.4g} rad beyond "
                    f"{self.steering_wheel_limit_rad:.3g} rad")
        if min(cmd.brake_torque_nm) < 0.0:
            return "negative brake torque"
        torques = [abs(v) for v in (*cmd.drive_torque_nm, *cmd.brake_torque_nm,
                                    cmd.steering_torque_nm)]
        if max(torques) > self.torque_limit_nm:
            return f"torque {max(torques):.4g} N m beyond {self.torque_limit_nm:.4g} N m"
        return ""

    def command_problem(self, angle_rad: float) -> str:
        """Why ``angle_rad`` cannot be a rear-steer command ('' if it can)."""
        if not math.isfinite(angle_rad):
            return "not finite"
        if abs(angle_rad) > self.rear_angle_limit_rad * (1.0 + 1e-12):
            return (f"rear angle {angle_rad:.4g} rad beyond the limit "
                    f"{self.rear_angle_limit_rad:.4g} rad")
        return ""


@dataclass
class Rejections:
    """Inputs refused as not belonging to the run, counted by ``"<topic>: <reason>"``."""

    counts: collections.Counter[str] = field(default_factory=collections.Counter)
    last: str = ""

    def add(self, topic: str, reason: str, detail: str = "") -> bool:
        """Count one refusal; returns False (so callers can ``return rejections.add(...)``)."""
        key = f"{topic}: {reason}"
        self.counts[key] += 1
        self.last = f"{key} ({detail})" if detail else key
        return False

    @property
    def total(self) -> int:
        """All refusals."""
        return sum(self.counts.values())


class LockstepAnswers:
    """The answers to the tick waiting to advance (lockstep), with the trust rules.

    Parameters
    ----------
    limits : InputLimits
    """

    def __init__(self, limits: InputLimits) -> None:
        self.limits = limits
        self.awaited: Tick | None = None
        self.driver: DriverCommand | None = None
        self.rear_rad: float | None = None
        self.rejections = Rejections()
        self.driver_inputs_accepted = 0
        self.commands_accepted = 0
        self.late_commands = 0
        # stamp_ns -> (step, whether its command came in time) of ticks already run
        self._past: collections.OrderedDict[int, tuple[int, bool]] = collections.OrderedDict()
        self._past_steps: dict[int, int] = {}

    def expect(self, tick: Tick) -> None:
        """``tick`` has been published; its answers are now awaited."""
        self.awaited = tick
        self.driver = None
        self.rear_rad = None

    @property
    def waiting_for(self) -> str:
        """The answers still missing ('' when none is awaited or both are in)."""
        if self.awaited is None:
            return ""
        missing = [name for name, got in (("driver input", self.driver),
                                          ("rear-steer command", self.rear_rad))
                   if got is None]
        return " and ".join(missing)

    def offer_driver(self, stamp_ns: int, cmd: DriverCommand) -> bool:
        """A driver input stamped ``stamp_ns``; True if it is the awaited tick's answer."""
        topic = interface.DRIVER_INPUT
        tick = self.awaited
        if tick is not None and stamp_ns == tick.stamp_ns:
            if self.driver is not None:
                return self.rejections.add(topic, SECOND_ANSWER,
                                           f"t = {tick.t:.3f} s")
            problem = self.limits.driver_problem(cmd)
            if problem:
                return self.rejections.add(topic, "impossible values", problem)
            self.driver = cmd
            self.driver_inputs_accepted += 1
            return True
        if stamp_ns in self._past:
            # the tick ran on one answer already: whichever came first, one publisher too many
            return self.rejections.add(topic, SECOND_ANSWER,
                                       f"stamp {stamp_ns} ns, after the tick ran")
        return self.rejections.add(topic, "stamp of no published state",
                                   f"stamp {stamp_ns} ns")

    def offer_command(self, step: int, stamp_ns: int, angle_rad: float) -> bool:
        """A rear-steer command answering state ``step`` stamped ``stamp_ns``; True if it is
        the awaited tick's answer."""
        topic = interface.REAR_STEER_CMD
        tick = self.awaited
        if tick is not None and step == tick.step:
            if stamp_ns != tick.stamp_ns:
                return self.rejections.add(topic, "step and stamp of different states",
                                           f"step {step}, stamp {stamp_ns} ns")
            if self.rear_rad is not None:
                return self.rejections.add(topic, SECOND_ANSWER,
                                           f"step {step}")
            problem = self.limits.command_problem(angle_rad)
            if problem:
                return self.rejections.add(topic, "impossible values", problem)
            self.rear_rad = float(angle_rad)
            self.commands_accepted += 1
            return True
        past = self._past.get(stamp_ns)
        if past is not None and past[0] == step:
            if not past[1]:
                # the controller answered after the tick had run on without it
                self.late_commands += 1
                self._past[stamp_ns] = (step, True)
                return False
            return self.rejections.add(topic, SECOND_ANSWER,
                                       f"step {step}, after the tick ran")
        return self.rejections.add(topic, "step of no published state", f"step {step}")

    @property
    def complete(self) -> bool:
        """Both answers of the awaited tick are in."""
        return self.driver is not None and self.rear_rad is not None

    def close(self) -> tuple[DriverCommand, float, bool]:
        """End the awaited tick: ``(driver command, rear angle, timed out)``; a missing command
        is zero rear steer (``timed out`` True).

        Raises
        ------
        RuntimeError
            No driver input: a tick cannot run without one.
        """
        tick = self.awaited
        if tick is None or self.driver is None:
            raise RuntimeError("a tick cannot run without its driver input")
        timed_out = self.rear_rad is None
        self._past[tick.stamp_ns] = (tick.step, not timed_out)
        while len(self._past) > TICK_MEMORY:
            self._past.popitem(last=False)
        result = (self.driver, 0.0 if timed_out else float(self.rear_rad), timed_out)
        self.awaited, self.driver, self.rear_rad = None, None, None
        return result


class RealtimeAnswers:
    """Driver inputs and commands in realtime mode: the latest valid one is held.

    A message counts only if it answers a state this simulator published (step and stamp as
    published, remembered for :data:`TICK_MEMORY` states) and is not older than the one held.
    A command's age is the simulation time since *that state* was published, taken from the
    simulator's own record, never from the message.

    Parameters
    ----------
    limits : InputLimits
    """

    def __init__(self, limits: InputLimits) -> None:
        self.limits = limits
        self.rejections = Rejections()
        self._published: collections.OrderedDict[int, tuple[int, float]] = \
            collections.OrderedDict()  # stamp_ns -> (step, t)
        self.driver = DriverCommand(0.0, 0.0)
        self.driver_time_s = -math.inf
        self.rear_rad = 0.0
        self.rear_state_time_s = -math.inf
        self._rear_step = -1
        self.driver_inputs_accepted = 0
        self.commands_accepted = 0
        self.late_commands = 0

    def published(self, tick: Tick) -> None:
        """Remember a published state."""
        self._published[tick.stamp_ns] = (tick.step, tick.t)
        while len(self._published) > TICK_MEMORY:
            self._published.popitem(last=False)

    def was_published(self, stamp_ns: int) -> bool:
        """Whether a state stamped ``stamp_ns`` was published (within the memory)."""
        return stamp_ns in self._published

    def offer_driver(self, stamp_ns: int, cmd: DriverCommand) -> bool:
        """A driver input; True if accepted (it is then held)."""
        topic = interface.DRIVER_INPUT
        state = self._published.get(stamp_ns)
        if state is None:
            return self.rejections.add(topic, "stamp of no published state",
                                       f"stamp {stamp_ns} ns")
        if state[1] <= self.driver_time_s:
            return self.rejections.add(topic, "not newer than the held input",
                                       f"t = {state[1]:.3f} s")
        problem = self.limits.driver_problem(cmd)
        if problem:
            return self.rejections.add(topic, "impossible values", problem)
        self.driver, self.driver_time_s = cmd, state[1]
        self.driver_inputs_accepted += 1
        return True

    def offer_command(self, step: int, stamp_ns: int, angle_rad: float) -> bool:
        """A rear-steer command; True if accepted (it is then held)."""
        topic = interface.REAR_STEER_CMD
        state = self._published.get(stamp_ns)
        if state is None or state[0] != step:
            return self.rejections.add(topic, "step and stamp of no published state",
                                       f"step {step}, stamp {stamp_ns} ns")
        if step == self._rear_step:
            return self.rejections.add(topic, SECOND_ANSWER, f"step {step}")
        if step < self._rear_step:
            self.late_commands += 1
            return False
        problem = self.limits.command_problem(angle_rad)
        if problem:
            return self.rejections.add(topic, "impossible values", problem)
        self.rear_rad, self.rear_state_time_s, self._rear_step = float(angle_rad), state[1], step
        self.commands_accepted += 1
        return True

    def rear_at(self, t_s: float, timeout_s: float) -> tuple[float, bool]:
        """``(rear angle, timed out)`` to apply at simulation time ``t_s``: the held command,
        or zero once its state is older than ``timeout_s``."""
        if t_s - self.rear_state_time_s <= timeout_s:
            return self.rear_rad, False
        return 0.0, True


#: Refusal reasons the run's outcome depends on (the launcher reads them from the nodes'
#: rejection counts): a second answer to one state, and states that do not continue the run
#: although they are on its clock (a second publisher of states).
SECOND_ANSWER = "second answer to one state"
NOT_AFTER_PREVIOUS = "not after the previous state"
SKIPS_STATES = "skips states"


class StateGate:
    """Which vehicle states a maneuver or controller node answers.

    A state is answered only if it continues the simulator's own sequence: its time is
    exactly ``step * dt`` (the simulator's clock), its stamp is that time in ns, its step is
    a whole number of state periods after the previous one (exactly one in lockstep, where
    nothing may be skipped; any number in realtime, where a late subscriber may miss states)
    and, in lockstep, the run starts at step 0. A state from anywhere else -- a rogue node, a
    replayed bag, another run -- is refused and counted, so it cannot end a maneuver or steer
    a controller.

    Parameters
    ----------
    dt_s : float
        Integration step of the run, s.
    state_period_s : float
        Period of the published states, s (lockstep: the control period).
    lockstep : bool
        Exact continuation required.
    max_gap_s : float
        Realtime: the longest simulation time between two answered states, s (a longer jump
        is not the simulator's stream).
    """

    def __init__(self, dt_s: float, state_period_s: float, lockstep: bool,
                 max_gap_s: float = 1.0) -> None:
        self.dt_s = float(dt_s)
        self.every = whole_multiple(state_period_s, dt_s, "state_period_s")
        self.lockstep = lockstep
        self.max_gap_steps = max(int(round(max_gap_s / dt_s)), self.every)
        self.last_step: int | None = None
        self.rejections = Rejections()

    def admit(self, step: int, t_s: float, stamp_ns: int) -> bool:
        """Whether to answer the state (``step``, ``t_s``, ``stamp_ns``); counts refusals."""
        topic = interface.STATE
        if t_s != step * self.dt_s or stamp_ns != interface.time_to_ns(t_s):
            return self.rejections.add(topic, "time not of this run's clock",
                                       f"step {step}, t = {t_s!r} s")
        if step % self.every:
            return self.rejections.add(topic, "not a state period", f"step {step}")
        last = self.last_step
        if last is None:
            if self.lockstep and step != 0:
                return self.rejections.add(topic, "run does not start at step 0",
                                           f"step {step}")
        elif step <= last:
            return self.rejections.add(topic, NOT_AFTER_PREVIOUS,
                                       f"step {step} after {last}")
        elif (step - last != self.every if self.lockstep
              else step - last > self.max_gap_steps):
            return self.rejections.add(topic, SKIPS_STATES, f"step {step} after {last}")
        self.last_step = step
        return True

    def admits_final(self, t_s: float) -> bool:
        """Whether a final simulator status at simulation time ``t_s`` can be this run's:
        not before the last answered state, and (lockstep) at most one state period after it
        -- the simulator cannot run further ahead of a node that answers every state -- or
        (realtime) at most the longest gap the gate accepts. A final status from anywhere
        else (a rogue at t = 1e6 s, another run) is refused and counted, so it cannot stop
        the node."""
        t_last = (self.last_step or 0) * self.dt_s
        ahead = (self.every + 1 if self.lockstep else self.max_gap_steps) * self.dt_s
        if math.isfinite(t_s) and t_last <= t_s <= t_last + ahead:
            return True
        return self.rejections.add(interface.SIM_STATUS, "final status not of this run",
                                   f"t = {t_s!r} s after the state at {t_last!r} s")


# ============================================================================ realtime pacing

#: Step-lateness histogram: bin width, s, and bin count (the last bin collects everything
#: later than 20 ms).
LATENESS_BIN_S = 1e-5
LATENESS_BINS = 2000


class Pacer:
    """Wall-clock pacing of realtime integration.

    Each integration step has a deadline (wall time of the run's start plus the step's
    simulation time). :meth:`wait` sleeps until it and measures how late the step starts.
    A step more than one integration step late is an overrun: it is recorded with its time
    and the schedule is re-based instead of racing to catch up.

    Parameters
    ----------
    dt_s : float
        Integration step, s.
    clock, sleep : callable
        Wall clock (s) and sleep (tests pass simulated ones).
    """

    def __init__(self, dt_s: float, clock: Callable[[], float] = time.perf_counter,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        self.dt_s = dt_s
        self._clock, self._sleep = clock, sleep
        self._t0: float | None = None
        self.lateness_s = 0.0
        self.max_lateness_s = 0.0
        self.max_lateness_at_s = 0.0
        self.hist = np.zeros(LATENESS_BINS, dtype=np.int64)
        self.overruns = 0
        #: Overruns not yet reported: (simulation time, lateness) pairs.
        self.pending_overruns: list[tuple[float, float]] = []
        #: The first overruns of the run (for the shutdown log).
        self.first_overruns: list[tuple[float, float]] = []

    def start(self, sim_t: float) -> None:
        """Anchor the schedule: simulation time ``sim_t`` is now."""
        self._t0 = self._clock() - sim_t

    def wait(self, sim_t: float) -> float:
        """Sleep until the deadline of the step starting at ``sim_t``; its lateness, s."""
        if self._t0 is None:
            self.start(sim_t)
        assert self._t0 is not None
        deadline = self._t0 + sim_t
        now = self._clock()
        if now < deadline:
            self._sleep(deadline - now)
            now = self._clock()
        late = now - deadline
        self.lateness_s = late
        self.hist[min(max(int(late / LATENESS_BIN_S), 0), LATENESS_BINS - 1)] += 1
        if late > self.max_lateness_s:
            self.max_lateness_s, self.max_lateness_at_s = late, sim_t
        if late > self.dt_s:
            self.overruns += 1
            self.pending_overruns.append((sim_t, late))
            if len(self.first_overruns) < 20:
                self.first_overruns.append((sim_t, late))
            self._t0 += late  # re-base: simulated time does not race to catch up
        return late

    def take_overruns(self) -> list[tuple[float, float]]:
        """The overruns since the last call (they go into the next status message)."""
        taken, self.pending_overruns = self.pending_overruns, []
        return taken

    def percentile(self, q: float) -> float:
        """Percentile ``q`` (0..100) of the step lateness so far, s (bin upper edge; 0 before
        the first step)."""
        total = int(self.hist.sum())
        if total == 0:
            return 0.0
        idx = int(np.searchsorted(np.cumsum(self.hist), q / 100.0 * total))
        return (min(idx, LATENESS_BINS - 1) + 1) * LATENESS_BIN_S


# ============================================================================ flow control

class FlowWindow:
    """Lockstep flow control against the recorder.

    The simulator knows how many messages of each recorded topic the run has sent (its own,
    and the answers it accepted); the recorder reports how many it stored. Once any topic is
    more than ``window`` messages ahead the simulator holds its next tick until every topic
    is back within ``window // 2`` (hysteresis: the recorder then takes the backlog in
    batches, which is much cheaper than one message per wake-up, instead of releasing the
    simulator one tick at a time). With ``window`` below the DDS history depth no message can
    be pushed out of a queue before the recorder takes it, whatever the scheduling.

    Parameters
    ----------
    window : int
        Largest lead in messages (0 disables flow control).
    topics : iterable of str
        The recorded topics the simulator can count.
    """

    def __init__(self, window: int, topics: Any) -> None:
        self.window = int(window)
        self.topics = tuple(topics)
        self.stored: dict[str, int] = {t: 0 for t in self.topics}
        self._holding = ""
        #: How many times the simulator had to wait for the recorder.
        self.holds = 0

    def update(self, stored: Mapping[str, int]) -> None:
        """The recorder's stored counts (monotonic: an older report changes nothing)."""
        for topic, n in stored.items():
            if topic in self.stored and n > self.stored[topic]:
                self.stored[topic] = int(n)

    def holding_back(self, sent: Mapping[str, int]) -> str:
        """The topic the recorder is too far behind on ('' if none, or disabled)."""
        if self.window <= 0:
            return ""
        limit = self.window // 2 if self._holding else self.window
        for topic in self.topics:
            if sent.get(topic, 0) - self.stored[topic] > limit:
                if not self._holding:
                    self.holds += 1
                self._holding = topic
                return topic
        self._holding = ""
        return ""


__all__ = ["FRONT_ANGLE_LIMIT_RAD", "FlowWindow", "InputLimits", "LATENESS_BINS",
           "NOT_AFTER_PREVIOUS", "SECOND_ANSWER", "SKIPS_STATES", "LATENESS_BIN_S",
           "LockstepAnswers", "MULTIPLE_RTOL", "Pacer", "RealtimeAnswers",
           "Rejections", "STEERING_WHEEL_LIMIT_RAD", "StateGate", "TICK_MEMORY", "Tick",
           "TickEngine", "law_input", "simulator_inputs", "whole_multiple"]
