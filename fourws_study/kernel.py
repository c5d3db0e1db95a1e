# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""One closed-loop run of a study point: compiled where it can be, the interpreted twin
otherwise, the same numbers either way.

A run of a :class:`~fourws_run.config.RunConfig` gives a :class:`LoopRecord` (one row per
control tick: the ``VehicleState`` channels, the driver's commands, the law's command and the
actuator's angle). :func:`run_compiled` computes it in one compiled call for the whole run
(:mod:`fourws_study.loop_kernels`) when the run is one the kernel performs exactly as
:func:`fourws_run.closed_loop.run_closed_loop` does (:func:`compiled_plan` says why not
otherwise), :func:`run_interpreted` with the interpreted twin; a study point takes the first
where it can (:func:`fourws_study.point.run_points`):

* the 8-DOF model with the RK4 integrator (the simulator's compiled path);
* a maneuver whose steering is a function of time and whose driver only holds the initial
  speed (:data:`TIME_STEERED`, with no end condition of its own); the steering of every tick
  is taken from the maneuver itself before the call, and the kernel ends the run where the
  maneuver would, at its duration or at the first state past its
  :class:`~fourws_sim.outcome.VehicleLimits` (the twin's ``end_reason`` then, from the same
  :meth:`~fourws_sim.outcome.VehicleLimits.violation` of that state);
* a registered law whose :class:`~fourws_control.base.GainFunction` is one of the gain
  functions its class declares (:func:`fourws_control.compiled.law_kind`: every law fourws
  ships);
* a lockstep run.

Everything else -- the path-following lane change, the ISO 4138 ramp that ends on a
condition, braking in a turn, the linear models -- and every compiled run that meets what
only the interpreted twin decides (a refused input, a failing law, a diverging state: the
kernel stops with a code) runs through :func:`fourws_run.closed_loop.run_twin` itself.
The compiled path is tested to give the twin's arrays bit for bit (``test/test_study.py``).

A study runs the compiled points of a block together (:func:`run_compiled_block`, one
compiled call per tire, step and control period): in vector instructions, 16 points at a
time (:func:`fourws_study.loop_kernels.closed_loop_lanes`), when the tire has lane kernels
(the STI tire with its Table C.1 ``G2 = 1``), else point after point
(:func:`~fourws_study.loop_kernels.closed_loop_block`). Either gives each point exactly the
numbers of its single run (:func:`run_compiled`: the point-after-point kernel on a block of
one).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from fourws_control import Law, RearSteerActuator, compiled, make_loop_law
from fourws_run.closed_loop import ClosedLoopResult, run_twin
from fourws_run.config import RunConfig
from fourws_run.ticks import InputLimits, whole_multiple
from fourws_sim import variants
from fourws_sim.drivers import drive_fractions
from fourws_sim.maneuvers import Maneuver, make_maneuver
from fourws_sim.models import eightdof
from fourws_sim.outcome import VehicleLimits

#: Maneuver types whose steering depends on time only and whose driver holds the initial speed
#: throughout (the compiled path takes them; the others need the interpreted twin).
TIME_STEERED = ("step_steer", "ramp_steer", "sine", "swept_sine", "random_steer", "pulse")
#: What the twin says of a run it completed.
DURATION = "duration"

#: Steering of each tick by maneuver definition (:func:`_steering`).
_STEERING: dict[str, tuple[np.ndarray, np.ndarray]] = {}
_STEERING_CACHE_SIZE = 64


#: The study's compiled closed loop, a template of :mod:`fourws_sim.variants`.
LOOP_TEMPLATE = "fourws_study.loop_kernels"


def loop_kernel_for(tire_name: str) -> ModuleType:
    """The :mod:`fourws_study.loop_kernels` variant of tire model ``tire_name``
    (:func:`fourws_sim.variants.load`: built once per process, compiled at its first call and
    cached on disk).

    Raises
    ------
    UnknownNameError
        Unknown tire model.
    """
    return variants.load(LOOP_TEMPLATE, tire_name)


@dataclass
class LoopRecord:
    """The arrays of one closed-loop run, one row per control tick.

    Attributes
    ----------
    time_s : numpy.ndarray
        Tick times, s.
    channels : dict of str to numpy.ndarray
        :data:`fourws_study.loop_kernels.CHANNELS` (SI units): the ``VehicleState`` fields,
        the driver's ``steering_wheel_angle_rad`` and ``front_wheel_angle_cmd_rad``, the
        law's ``rear_law_rad``, the actuator's ``rear_command_rad`` and the summed drive and
        brake torques.
    end_reason : str
        ``duration``, the maneuver's end or abort reason, or the divergence (the twin's
        ``end_reason``).
    engine : str
        ``compiled`` or ``twin`` (``graph`` for a recorded run): which path computed it.
    fallback : str
        Why the twin ran ('' when the compiled path did).
    final : dict of str to float or None
        The state channels after the last tick (the state the simulator publishes last and
        the maneuver answers as done; a bag holds it); None when the run diverged.
    loop_seconds : float
        Wall time of the compiled call alone, s (0 for the twin; ``fourws bench --study``).
    """

    time_s: np.ndarray
    channels: dict[str, np.ndarray]
    end_reason: str
    engine: str
    fallback: str = ""
    final: dict[str, float] | None = None
    loop_seconds: float = 0.0

    @property
    def diverged(self) -> bool:
        """The simulation diverged (``end_reason`` says when)."""
        return self.end_reason.startswith("the simulation diverged")


def build_law(config: RunConfig) -> Law:
    """The run's law as its controller builds it (:func:`fourws_control.make_loop_law` on the
    belief vehicle for the controller's period)."""
    return make_loop_law(config.law, config.belief, config.controller_period_s,
                         config.law_options)


def compiled_plan(config: RunConfig, law: Law | None = None) -> str:
    """Why ``config`` cannot take the compiled path ('' if it can)."""
    if not config.controller.builtin:
        return "a user controller"
    if config.model != "8dof" or config.integrator != "rk4":
        return f"model {config.model} with {config.integrator} (compiled: 8dof with rk4)"
    if not config.lockstep:
        return "a realtime run"
    if config.maneuver.type not in TIME_STEERED:
        return f"maneuver type {config.maneuver.type} (its driver steers from the state)"
    if law is not None:
        gains = law.gain_function()
        if gains is None or compiled.law_kind(gains.function) is None:
            return f"law {config.law} has no compiled gain function"
    return ""


def twin_record(result: ClosedLoopResult, fallback: str = "") -> LoopRecord:
    """A :class:`LoopRecord` of the interpreted twin's result."""
    # numba: the compiled loop only (the interpreted twin runs without it)
    from fourws_study.loop_kernels import CHANNELS

    out = result.outputs
    channels: dict[str, np.ndarray] = {}
    for name in CHANNELS:
        if name in out and out[name].ndim == 1:
            channels[name] = out[name]
    channels["steering_wheel_angle_rad"] = result.driver["steering_wheel_angle_rad"]
    channels["front_wheel_angle_cmd_rad"] = result.driver["front_wheel_angle_rad"]
    channels["rear_law_rad"] = result.rear_law_rad
    channels["rear_command_rad"] = result.rear_angle_rad
    drive, brake = result.driver["drive_torque_nm"], result.driver["brake_torque_nm"]
    channels["drive_torque_total_nm"] = drive[:, 0] + drive[:, 1] + drive[:, 2] + drive[:, 3]
    channels["brake_torque_total_nm"] = brake[:, 0] + brake[:, 1] + brake[:, 2] + brake[:, 3]
    # numba: the compiled loop only (the interpreted twin runs without it)
    from fourws_study.loop_kernels import STATE_CHANNELS

    final = None if result.diverged else {
        name: float(result.final_outputs[name]) for name in STATE_CHANNELS}
    return LoopRecord(result.time_s, channels, result.end_reason, "twin", fallback, final)


def run_interpreted(config: RunConfig, fallback: str = "") -> LoopRecord:
    """Run ``config`` with the interpreted twin (:func:`fourws_run.closed_loop.run_twin`)."""
    return twin_record(run_twin(config), fallback)


def _steering(man: Maneuver, speed: float, dt: float,
              n_step: int) -> tuple[np.ndarray, np.ndarray] | str:
    """The steering-wheel and front road-wheel angle the maneuver commands at each tick the
    twin runs (ticks ``t_k = k n dt`` until the maneuver is done), or why there are none.

    Computed by the maneuver itself (``command`` at each tick; for the
    :data:`TIME_STEERED` types the steering depends on the time only) and kept per maneuver
    definition without its speed and speed hold, which the steering does not read.
    """
    spec = man.spec.to_dict()
    for key in ("initial_speed_mps", "speed_hold", "name", "description"):
        spec.pop(key, None)
    ratio = man.vehicle.steering.ratio if man.vehicle.steering is not None else None
    key = json.dumps([spec, ratio, dt, n_step], sort_keys=True, default=str)
    if key in _STEERING:
        return _STEERING[key]
    period = n_step * dt
    limit = int(math.ceil(man.duration_s / period)) + 1
    hand, front = [], []
    probe = {"speed_mps": speed}
    for k in range(limit):
        t = (k * n_step) * dt
        if man.done(t, None):
            break
        cmd = man.command(t, probe)
        hand.append(cmd.steering_wheel_angle_rad)
        front.append(cmd.front_wheel_angle_rad)
    else:
        return "the maneuver does not end within its duration"
    if not front:
        return "the maneuver ends before its first tick"
    result = (np.array(hand, dtype=np.float64), np.array(front, dtype=np.float64))
    for arr in result:
        arr.flags.writeable = False
    if len(_STEERING) >= _STEERING_CACHE_SIZE:
        _STEERING.pop(next(iter(_STEERING)))
    _STEERING[key] = result
    return result


@dataclass
class Prepared:
    """One point ready for the compiled loop (:func:`prepare_compiled`): its row of the
    arguments of :func:`fourws_study.loop_kernels.closed_loop_block` and what turns its output
    into a record.

    ``group`` is what points of one compiled block call must share: tire variant,
    integration step and steps per control period. ``lanes``: the point can run in the
    vector-instruction batch kernel (:func:`fourws_study.loop_kernels.closed_loop_lanes`: its
    tire has lane kernels and the coefficients they take).
    """

    module: ModuleType
    group: tuple[str, float, int]
    x: np.ndarray
    q: np.ndarray
    cf: np.ndarray
    cr: np.ndarray
    hand: np.ndarray
    front: np.ndarray
    drv: np.ndarray
    kind: int
    law_params: np.ndarray
    min_speed: float
    angle_limit: float
    max_step: float
    abort_reason: str
    limits: VehicleLimits
    lanes: bool = False


def prepare_compiled(config: RunConfig, law: Law) -> Prepared | str:
    """The compiled loop's arguments for ``config``, or why the twin must run it (a string).

    Parameters
    ----------
    config : RunConfig
        A run :func:`compiled_plan` accepts.
    law : Law
        The run's law (:func:`build_law`; shared by the points of one belief).
    """
    why = compiled_plan(config, law)
    if why:
        return why
    vehicle = config.vehicle
    dt = config.integration_step_s
    period = config.controller_period_s
    n_step = whole_multiple(period, dt, "control_period_s")
    # the simulator's construction and reset (Simulator.__init__/reset)
    p = eightdof.params_for(vehicle, config.tire)
    eightdof.check_step(p, dt, config.integrator, vehicle.source or vehicle.name)
    speed = config.maneuver.initial_speed_mps
    x = eightdof.initial_state(p, float(speed))
    man = make_maneuver(config.maneuver, vehicle)
    if type(man).check_end is not Maneuver.check_end:
        return f"maneuver type {config.maneuver.type} ends on a condition of its own"
    steering = _steering(man, float(speed), dt, n_step)
    if isinstance(steering, str):
        return steering
    hand_a, front_a = steering
    limits = InputLimits.for_vehicle(vehicle)
    if not (np.all(np.abs(front_a) <= limits.front_angle_limit_rad)
            and np.all(np.abs(hand_a) <= limits.steering_wheel_limit_rad)):
        return "a steering input the simulator refuses"
    # the speed-hold driver and the actuator (SpeedHoldDriver, RearSteerActuator)
    sh = config.maneuver.speed_hold
    module = loop_kernel_for(p.tire_name)
    drv = np.zeros(module.N_DRIVER)
    drv[module.D_ENABLED] = 1.0 if sh.enabled else 0.0
    drv[module.D_KP], drv[module.D_KI] = sh.kp_per_s, sh.ki_per_s2
    drv[module.D_MAX_DECEL], drv[module.D_MAX_ACCEL] = sh.max_decel_mps2, sh.max_accel_mps2
    drv[module.D_MASS] = vehicle.chassis.mass_kg
    drv[module.D_RADIUS] = vehicle.body.wheel_radius_m if vehicle.body is not None else 0.0
    drv[module.D_ROLLING] = (vehicle.tire.rolling_resistance if vehicle.tire is not None
                             else 0.0)
    drv[module.D_DRAG] = (vehicle.aero.drag_coefficient_kg_per_m if vehicle.aero is not None
                          else 0.0)
    drv[module.D_BRAKE_FRONT] = sh.brake_front_fraction
    drv[module.D_DRIVEN_FL:module.D_DRIVEN_FL + 4] = drive_fractions(sh.driven_axle, vehicle)
    drv[module.D_TARGET] = speed
    drv[module.D_TORQUE_LIMIT] = limits.torque_limit_nm
    drv[module.D_REAR_LIMIT] = limits.rear_angle_limit_rad
    # the limits Maneuver.done applies to every state (the maneuver's own object)
    vehicle_limits = man.spec.vehicle_limits
    drv[module.D_MAX_SIDESLIP] = vehicle_limits.max_sideslip_rad
    drv[module.D_MIN_SPEED] = vehicle_limits.min_forward_speed_mps
    drv[module.D_MAX_ROLL] = vehicle_limits.max_roll_rad
    actuator = RearSteerActuator(config.belief)
    gains = law.gain_function()
    assert gains is not None
    kind = compiled.law_kind(gains.function)
    assert kind is not None
    condition = getattr(p.tire, "LANE_CONDITION", None)  # a coefficient lanes need
    lanes = module.HAS_LANES and (condition is None or all(
        float(coeffs[condition[0]]) == condition[1]
        for coeffs in (p.coeffs_front, p.coeffs_rear)))
    return Prepared(module, (p.tire_name, float(dt), int(n_step)), x, p.arr, p.coeffs_front,
                    p.coeffs_rear, hand_a, front_a, drv, int(kind),
                    np.ascontiguousarray(gains.params, dtype=np.float64),
                    float(law.min_speed_mps), float(actuator.angle_limit_rad),
                    float(actuator.rate_limit_rad_per_s * float(period)),
                    man.abort_reason or DURATION, vehicle_limits, lanes)


def _record(prep: Prepared, code: int, out: np.ndarray, loop_seconds: float
            ) -> LoopRecord | str:
    """The record of one compiled run (``out``: its rows, the last the state it ended at),
    or why the twin must run it."""
    module = prep.module
    if code == module.LIMITS and out.shape[0] == 1:
        return "the car is past its vehicle limits at the first state"  # the twin refuses it
    if code not in (module.DONE, module.LIMITS):
        return {module.DIVERGED: "the simulation diverged",
                module.DRIVER_REFUSED: "a driver input the simulator refuses",
                module.LAW_FAILED: "the law failed",
                module.COMMAND_REFUSED: "a rear command the simulator refuses"}[int(code)]
    channels = {name: out[:-1, i].copy() for i, name in enumerate(module.CHANNELS)}
    final = {name: float(out[-1, i]) for i, name in enumerate(module.CHANNELS)
             if name in module.STATE_CHANNELS}
    reason = prep.abort_reason
    if code == module.LIMITS:  # the maneuver's end reason, as Maneuver.done gives it
        breach = prep.limits.violation(final["sim_time_s"], final)
        assert breach is not None, final
        reason = breach.reason
    return LoopRecord(channels["sim_time_s"], channels, reason, "compiled",
                      final=final, loop_seconds=loop_seconds)


def run_compiled(config: RunConfig, law: Law) -> LoopRecord | str:
    """Run ``config`` alone in the compiled loop (a block of one point in
    :func:`fourws_study.loop_kernels.closed_loop_block`, the scalar kernel); the
    :class:`LoopRecord`, or why the twin must run it (a string)."""
    prep = prepare_compiled(config, law)
    if isinstance(prep, str):
        return prep
    return _run_group([prep], lanes=False)[0]


def run_compiled_block(preps: list[Prepared]) -> list[LoopRecord | str]:
    """Run prepared points in one compiled call per group of equal tire, step and control
    period (:func:`fourws_study.loop_kernels.closed_loop_lanes` for the points that can run
    in vector instructions, :func:`~fourws_study.loop_kernels.closed_loop_block` for the
    others); each point's record, or why the twin must run it. The records equal
    :func:`run_compiled`'s bit for bit (``test/test_study.py``)."""
    results: list[LoopRecord | str] = [""] * len(preps)
    groups: dict[tuple[tuple[str, float, int], bool], list[int]] = {}
    for i, prep in enumerate(preps):
        groups.setdefault((prep.group, prep.lanes), []).append(i)
    for (_, lanes), members in groups.items():
        for i, record in zip(members, _run_group([preps[i] for i in members], lanes)):
            results[i] = record
    return results


def _run_group(block: list[Prepared], lanes: bool) -> list[LoopRecord | str]:
    """Points of one group (equal tire, step and control period) in one compiled call: the
    lane kernel if ``lanes``, else point after point. Each point's ``loop_seconds`` is the
    call's time shared in proportion to its ticks."""
    module = block[0].module
    _, dt, n_step = block[0].group
    n_ticks = np.array([p.front.size for p in block], dtype=np.int64)
    width = int(n_ticks.max())
    hand = np.zeros((len(block), width))
    front = np.zeros((len(block), width))
    for j, p in enumerate(block):
        hand[j, :p.hand.size] = p.hand
        front[j, :p.front.size] = p.front
    sizes = np.array([p.law_params.size for p in block], dtype=np.int64)
    law_start = np.concatenate(([0], np.cumsum(sizes))).astype(np.int64)
    law_flat = (np.concatenate([p.law_params for p in block]) if sizes.sum()
                else np.zeros(0))
    out = np.zeros((len(block), width + 1, module.N_CHANNELS))
    codes = np.zeros(len(block), dtype=np.int64)
    ticks = np.zeros(len(block), dtype=np.int64)
    x = np.stack([p.x for p in block])
    t0 = time.perf_counter()
    kernel = module.closed_loop_lanes if lanes else module.closed_loop_block
    kernel(
        x, np.stack([p.q for p in block]), np.stack([p.cf for p in block]),
        np.stack([p.cr for p in block]), float(dt), int(n_step), hand, front, n_ticks,
        np.stack([p.drv for p in block]), np.array([p.kind for p in block], np.int64),
        np.ascontiguousarray(law_flat, dtype=np.float64), law_start,
        np.array([p.min_speed for p in block]), np.array([p.angle_limit for p in block]),
        np.array([p.max_step for p in block]), out, codes, ticks)
    seconds = time.perf_counter() - t0
    total = max(int(n_ticks.sum()), 1)
    return [_record(p, int(codes[j]), out[j, :int(ticks[j]) + 1],
                    seconds * int(n_ticks[j]) / total) for j, p in enumerate(block)]


__all__ = ["LOOP_TEMPLATE", "LoopRecord", "Prepared", "TIME_STEERED",
           "build_law", "compiled_plan", "loop_kernel_for", "prepare_compiled", "run_compiled",
           "run_compiled_block", "run_interpreted", "twin_record"]
