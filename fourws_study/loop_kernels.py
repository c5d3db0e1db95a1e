# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Numba kernels of whole closed-loop runs of the offline twin, for one tire model.

A template of :mod:`fourws_sim.variants`: :func:`fourws_study.kernel.loop_kernel_for` loads
it once per tire model (``fourws_study.loop_kernels[sti]``, ...), so each variant calls that
tire's compiled RK4 loop and right-hand side (:func:`fourws_sim.models.eightdof.kernel_module`)
and numba's disk cache keeps one entry per variant.

The kernels run every control tick of :func:`fourws_run.closed_loop.run_closed_loop` in one
compiled call, for the maneuvers whose steering is a function of time and whose driver only
holds the speed: the tick's outputs (the 8-DOF right-hand side with the held input, as
``Simulator.outputs``), the speed-hold driver (:func:`fourws_sim.drivers.speed_hold_request`,
:func:`~fourws_sim.drivers.split_brake_torque`), the law (its
:class:`~fourws_control.base.GainFunction` through the dispatch of
:mod:`fourws_control.compiled`, :func:`~fourws_control.base.gain_speed`,
:func:`~fourws_control.base.rear_angle_of`), the actuator
(:func:`~fourws_control.base.actuator_step`) and one control period of the compiled RK4 loop
(:attr:`fourws_sim.models.eightdof.Kernels.rk4`). Those functions are the ones the
interpreted twin calls, so the kernel performs the twin's float operations in the twin's
order; the steering angles of each tick are the maneuver's own, computed before the call.
The maneuver's :class:`~fourws_sim.outcome.VehicleLimits` are checked on every state before
it is answered, as ``Maneuver.done`` does (:func:`fourws_sim.outcome.breach_code` with the
limits as numbers, slots ``D_MAX_SIDESLIP`` ... of ``drv``): a state that breaks them ends the
run there, as the state after the last tick (code ``LIMITS``). What only the interpreted twin
decides -- a refused input, a law that fails, a diverging state -- ends a point with a code,
and the point is run again by the twin, which says why.

A tick (:func:`_respond`, :func:`_state_row`, :func:`_no_commands`) is written once; the
memory layout of the states makes the two kernels, both over a block of points:
:func:`closed_loop_block` runs them point after point (:func:`_run_point`; a single run is a
block of one), :func:`closed_loop_lanes` integrates :data:`fourws_sim.lanes.LANES` of them at
a time in vector instructions.
"""

from __future__ import annotations

import math

import numpy as np

from fourws_control import compiled
from fourws_control.base import actuator_step, gain_speed, rear_angle_of
from fourws_sim import drivers, variants
from fourws_sim.drivers import speed_hold_request, speed_hold_torque, split_brake_torque
from fourws_sim.lanes import LANES
from fourws_sim import outcome
from fourws_sim.models.eightdof import (INPUT, N_AUX, N_INPUT, N_STATE, STATE, aux_from_array,
                                        kernel_module, kernels_for, lane_kernels_for)
from fourws_sim.outcome import NO_BREACH, breach_code

#: Tire model of this variant (:func:`fourws_sim.variants.tire_of` its module name).
TIRE_NAME: str = variants.tire_of(__name__)
_KERNELS = kernels_for(TIRE_NAME)
#: The tire's batch kernels of LANES points (None: the tire has no lane function).
_LANES = lane_kernels_for(TIRE_NAME)
_rk4 = _KERNELS.rk4
_rhs = _KERNELS.rhs
#: The law's gains by law kind (:func:`fourws_control.compiled.compiled_gains`, which also
#: lets numba compile the law step's plain functions); the driver's plain functions.
_law_gains = compiled.compiled_gains()
variants.register_plain((speed_hold_request, speed_hold_torque, split_brake_torque, breach_code))

#: Recorded channels, one column each of the kernel's output (SI units; the names of
#: ``VehicleState`` and of :class:`fourws_analysis.bag.UniformRun`).
CHANNELS = ("sim_time_s", "x_m", "y_m", "heading_rad", "speed_mps", "lateral_velocity_mps",
            "yaw_rate_radps", "roll_rad", "roll_rate_radps", "sideslip_rad",
            "longitudinal_accel_mps2", "lateral_accel_mps2", "front_wheel_angle_rad",
            "rear_wheel_angle_rad", "steering_wheel_angle_rad", "front_wheel_angle_cmd_rad",
            "rear_law_rad", "rear_command_rad", "drive_torque_total_nm",
            "brake_torque_total_nm")
N_CHANNELS = len(CHANNELS)
(C_T, C_X, C_Y, C_PSI, C_U, C_V, C_R, C_PHI, C_P, C_BETA, C_AX, C_AY, C_DF, C_DR, C_HAND,
 C_FRONT, C_LAW, C_REAR, C_DRIVE, C_BRAKE) = range(N_CHANNELS)
#: The channels of the vehicle state (the rest are the answers to it).
STATE_CHANNELS = CHANNELS[:C_HAND]

#: Slots of the driver parameter vector ``drv`` (the speed-hold driver, the simulator's input
#: limits, the maneuver's vehicle limits).
#: ``D_DRIVEN_*``: each wheel's share of the drive torque (``drivers.drive_fractions``).
(D_ENABLED, D_KP, D_KI, D_MAX_DECEL, D_MAX_ACCEL, D_MASS, D_RADIUS, D_ROLLING, D_BRAKE_FRONT,
 D_DRIVEN_FL, D_DRIVEN_FR, D_DRIVEN_RL, D_DRIVEN_RR, D_TARGET, D_TORQUE_LIMIT,
 D_REAR_LIMIT, D_DRAG, D_MAX_SIDESLIP, D_MIN_SPEED, D_MAX_ROLL) = range(20)
N_DRIVER = D_MAX_ROLL + 1

#: Exit codes: every tick run; the run ended at a state past the maneuver's vehicle limits
#: (its last row is that state); or where the interpreted twin must take over.
DONE, LIMITS, DIVERGED, DRIVER_REFUSED, LAW_FAILED, COMMAND_REFUSED = range(6)

i_u, i_v, i_r, i_phi, i_p = (int(STATE.U), int(STATE.V), int(STATE.R), int(STATE.PHI),
                             int(STATE.P))
i_x, i_y, i_psi = int(STATE.X), int(STATE.Y), int(STATE.PSI)
j_df, j_dr, j_st = int(INPUT.DELTA_F), int(INPUT.DELTA_R), int(INPUT.STEER_TORQUE)
j_d0, j_b0 = int(INPUT.DRIVE_FL), int(INPUT.BRAKE_FL)
# slots of the right-hand side's auxiliary array, read through its public unpacker
_SLOTS = aux_from_array(np.arange(N_AUX, dtype=np.float64))
a_df, a_dr = int(_SLOTS.delta_f_rad), int(_SLOTS.delta_r_rad)
a_ax, a_ay = int(_SLOTS.ax_mps2), int(_SLOTS.ay_mps2)


def _gains(kind, speed, params, out):  # type: ignore[no-untyped-def]
    """The gains of law kind ``kind`` (:func:`fourws_control.compiled.law_kind`) at
    ``speed`` into ``out`` (zeroed first)."""
    for i in range(out.shape[0]):
        out[i] = 0.0
    _law_gains(kind, speed, params, out)


def _state_row(x, t, ax, ay, delta_f, delta_r, row):  # type: ignore[no-untyped-def]
    """The state channels of ``row`` at time ``t`` from state ``x`` and what the right-hand
    side gives with the held input (accelerations, applied road-wheel angles)."""
    U = x[i_u]
    V = x[i_v]
    row[C_T] = t
    row[C_X] = x[i_x]
    row[C_Y] = x[i_y]
    row[C_PSI] = x[i_psi]
    row[C_U] = U
    row[C_V] = V
    row[C_R] = x[i_r]
    row[C_PHI] = x[i_phi]
    row[C_P] = x[i_p]
    row[C_BETA] = math.atan2(V, U) if (U != 0.0 or V != 0.0) else 0.0
    row[C_AX] = ax
    row[C_AY] = ay
    row[C_DF] = delta_f
    row[C_DR] = delta_r


def _outputs(x, u, q, cf, cr, dx, aux, t, row):  # type: ignore[no-untyped-def]
    """The state channels of ``row`` at time ``t``: ``Simulator.outputs()`` of state ``x``
    with the held input ``u`` (accelerations and applied road-wheel angles from the
    right-hand side)."""
    _rhs(x, u, q, cf, cr, dx, aux)
    _state_row(x, t, aux[a_ax], aux[a_ay], aux[a_df], aux[a_dr], row)


def _respond(x, u, k, dt, n_step, row, hand_k, front_k, drv,  # type: ignore
             law_kind, law_params, min_speed, angle_limit, max_step, carry, drive, brake,
             k_gain):
    """The answers to tick ``k``'s state: the maneuver node's (its steering, the speed-hold
    driver), the controller's (the law through the actuator), and the input the simulator
    holds for the next control period, written into ``u``. ``carry`` holds the driver's
    integral, the time of its last answer and the actuator's angle between ticks. Returns
    ``DONE`` or why the twin must take over."""
    t = (k * n_step) * dt
    U = x[i_u]
    V = x[i_v]
    r = x[i_r]
    phi = x[i_phi]
    p = x[i_p]
    # the maneuver node's answer: its steering, and the speed-hold driver
    d_f = front_k
    for i in range(4):
        drive[i] = 0.0
        brake[i] = 0.0
    if drv[D_ENABLED] != 0.0 and drv[D_RADIUS] > 0.0:
        dt_drv = 0.0 if k == 0 else max(t - carry[1], 0.0)
        request, carry[0] = speed_hold_request(
            drv[D_TARGET] - U, carry[0], dt_drv, drv[D_KP], drv[D_KI], drv[D_MAX_DECEL],
            drv[D_MAX_ACCEL])
        total = speed_hold_torque(request, U, drv[D_MASS], drv[D_RADIUS], drv[D_ROLLING],
                                  drv[D_DRAG])
        if total >= 0.0:
            for i in range(4):
                if drv[D_DRIVEN_FL + i] > 0.0:
                    drive[i] = total * drv[D_DRIVEN_FL + i]
        else:
            bfl, bfr, brl, brr = split_brake_torque(-total, drv[D_BRAKE_FRONT])
            brake[0] = bfl
            brake[1] = bfr
            brake[2] = brl
            brake[3] = brr
    carry[1] = t
    torque_limit = drv[D_TORQUE_LIMIT]
    for i in range(4):
        if not (abs(drive[i]) <= torque_limit and abs(brake[i]) <= torque_limit):
            return DRIVER_REFUSED
    # the controller node's answer: the law through the actuator
    speed, scale = gain_speed(U, min_speed)
    _gains(law_kind, speed, law_params, k_gain)
    if scale != 1.0:
        for i in range(5):
            k_gain[i] = k_gain[i] * scale
    for i in range(5):
        if not math.isfinite(k_gain[i]):
            return LAW_FAILED
    c = rear_angle_of(k_gain, d_f, r, phi, p, V)
    if not math.isfinite(c):
        return LAW_FAILED
    angle = actuator_step(carry[2], c, angle_limit, max_step)
    carry[2] = angle
    if abs(angle) > drv[D_REAR_LIMIT] * (1.0 + 1e-12):
        return COMMAND_REFUSED
    row[C_HAND] = hand_k
    row[C_FRONT] = d_f
    row[C_LAW] = c
    row[C_REAR] = angle
    row[C_DRIVE] = drive[0] + drive[1] + drive[2] + drive[3]
    row[C_BRAKE] = brake[0] + brake[1] + brake[2] + brake[3]
    # the simulator integrates one control period holding both answers
    u[j_df] = d_f
    u[j_dr] = angle
    u[j_st] = 0.0
    for i in range(4):
        u[j_d0 + i] = drive[i]
        u[j_b0 + i] = brake[i]
    return DONE


def _past_limits(row, drv):  # type: ignore[no-untyped-def]
    """The state of ``row`` breaks the maneuver's vehicle limits (``Maneuver.done``: the
    run ends at it)."""
    return breach_code(row[C_BETA], row[C_U], row[C_PHI], drv[D_MAX_SIDESLIP],
                       drv[D_MIN_SPEED], drv[D_MAX_ROLL]) != NO_BREACH


def _no_commands(row):  # type: ignore[no-untyped-def]
    """The final row (the state after the last tick, which the simulator publishes last and
    the maneuver answers as done) has no answers: its command columns are NaN."""
    for c in range(C_HAND, N_CHANNELS):
        row[c] = math.nan


def _run_point(x, q, cf, cr, dt, n_step, hand, front, drv,  # type: ignore[no-untyped-def]
               law_kind, law_params, min_speed, angle_limit, max_step, out):
    """Run ``out.shape[0] - 1`` control ticks of one point from state ``x`` (modified in
    place).

    Parameters
    ----------
    x : float64 array
        8-DOF state at tick 0 (``eightdof.initial_state``).
    q, cf, cr : float64 arrays
        Packed 8-DOF parameters and the front and rear tire coefficients.
    dt : float
        Integration step, s.
    n_step : int
        Integration steps per control period.
    hand, front : float64 arrays
        The maneuver's steering-wheel and front road-wheel angle of each tick, rad.
    drv : float64 array
        Speed-hold driver and input limits (slots ``D_*``).
    law_kind : int
        The law's kind (:func:`fourws_control.compiled.law_kind`).
    law_params : float64 array
        The law's :class:`~fourws_control.base.GainFunction` parameters.
    min_speed, angle_limit, max_step : float
        The law's fade speed (m/s), the actuator's angle limit (rad) and largest move per
        control period (rad).
    out : float64 array (n_ticks + 1, N_CHANNELS)
        Filled tick by tick with :data:`CHANNELS`; the last row holds the state after the
        last tick (its command columns NaN); with ``LIMITS``, row ``k`` (the ticks recorded)
        is the state past the limits, its command columns NaN, and the rows after it are
        not written.

    Returns
    -------
    (int, int)
        Exit code (``DONE``, ``LIMITS`` or why the twin must take over) and the ticks
        recorded.
    """
    n_ticks = out.shape[0] - 1
    u = np.zeros(N_INPUT)
    dx = np.zeros(N_STATE)
    aux = np.zeros(N_AUX)
    k_gain = np.zeros(5)
    drive = np.zeros(4)
    brake = np.zeros(4)
    carry = np.zeros(3)  # the driver's integral and last time, the actuator's angle
    for k in range(n_ticks + 1):
        # the tick's outputs: Simulator.outputs() with the input held since the last step
        _outputs(x, u, q, cf, cr, dx, aux, (k * n_step) * dt, out[k])
        if k == n_ticks:  # the state after the last tick
            _no_commands(out[k])
            break
        if _past_limits(out[k], drv):  # the maneuver is done at this state
            _no_commands(out[k])
            return LIMITS, k
        code = _respond(x, u, k, dt, n_step, out[k], hand[k], front[k], drv, law_kind,
                        law_params, min_speed, angle_limit, max_step, carry, drive, brake,
                        k_gain)
        if code != DONE:
            return code, k
        if _rk4(x, u, q, cf, cr, dt, n_step) < n_step:
            return DIVERGED, k + 1
    return DONE, n_ticks


def closed_loop_block(x, q, cf, cr, dt, n_step, hand, front,  # type: ignore[no-untyped-def]
                      n_ticks, drv, law_kind, law_flat, law_start, min_speed, angle_limit,
                      max_step, out, codes, ticks):
    """A block of points (same tire, step and control period) in one call, point after
    point: point ``b`` runs :func:`_run_point` on row ``b`` of every per-point array (a
    single run is a block of one).

    Parameters
    ----------
    x : float64 array (B, N_STATE)
        Initial states, advanced in place.
    q, cf, cr : float64 arrays (B, ...)
        Packed 8-DOF parameters and tire coefficients of each point.
    dt, n_step : float, int
        Integration step (s) and steps per control period, shared by the block.
    hand, front : float64 arrays (B, T)
        Steering of each tick (point ``b`` reads its first ``n_ticks[b]``).
    n_ticks : int64 array (B,)
    drv : float64 array (B, N_DRIVER)
    law_kind : int64 array (B,)
    law_flat, law_start : float64 array, int64 array (B + 1,)
        The gain-function parameters of point ``b`` are ``law_flat[law_start[b]:
        law_start[b + 1]]`` (laws differ in their number of parameters).
    min_speed, angle_limit, max_step : float64 arrays (B,)
    out : float64 array (B, T + 1, N_CHANNELS)
        Point ``b`` fills its first ``n_ticks[b] + 1`` rows.
    codes, ticks : int64 arrays (B,)
        Each point's exit code and ticks recorded.
    """
    for b in range(x.shape[0]):
        n = n_ticks[b]
        code, k = _run_point(x[b], q[b], cf[b], cr[b], dt, n_step, hand[b, :n], front[b, :n],
                             drv[b], law_kind[b], law_flat[law_start[b]:law_start[b + 1]],
                             min_speed[b], angle_limit[b], max_step[b], out[b, :n + 1])
        codes[b] = code
        ticks[b] = k


def closed_loop_lanes(x, q, cf, cr, dt, n_step, hand, front,  # type: ignore
                      n_ticks, drv, law_kind, law_flat, law_start, min_speed, angle_limit,
                      max_step, out, codes, ticks):
    """:func:`closed_loop_block` (same arguments and results) with the integration of
    :data:`fourws_sim.lanes.LANES` points at a time in vector instructions
    (``rk4_lanes`` of the tire's kernel module): each control tick answers every point with
    the scalar code of :func:`_run_point` (``_respond``; the tick's outputs from one lane
    right-hand side of all points), then one control period of RK4 runs for all of them at
    once. A point gets exactly its :func:`_run_point` numbers (the lane right-hand side
    calls the scalar one's equations; ``test_study.py``). Only for a tire with lane kernels
    (``_LANES`` not None)."""
    n_points = x.shape[0]
    n_x = N_STATE * LANES
    IN = np.zeros(_LANES.N_IN * LANES)
    OUT = np.zeros(_LANES.N_OUT * LANES)
    X = np.zeros(n_x)
    K = np.zeros((4, n_x))
    XT = np.zeros(n_x)
    RATE = np.zeros(LANES)
    stepping = np.zeros(LANES, dtype=np.int64)
    running = np.zeros(LANES, dtype=np.int64)
    ul = np.zeros((LANES, N_INPUT))
    carry = np.zeros((LANES, 3))
    k_gain = np.zeros(5)
    drive = np.zeros(4)
    brake = np.zeros(4)
    xs = np.zeros(N_STATE)  # one lane's state (its tick's answers, its sub-steps)
    us = np.zeros(N_INPUT)
    qs = np.zeros(q.shape[1])
    cfs = np.zeros(cf.shape[1])
    crs = np.zeros(cr.shape[1])
    work = np.zeros((6, N_STATE))
    aux = np.zeros(N_AUX)
    for g0 in range(0, n_points, LANES):
        n_lanes = min(LANES, n_points - g0)
        most = 0
        for j in range(LANES):
            b = g0 + min(j, n_lanes - 1)  # idle lanes integrate a copy of the last point
            for i in range(N_INPUT):
                ul[j, i] = 0.0
            for i in range(3):
                carry[j, i] = 0.0
            _LANES.pack_lane(IN, j, x[b], ul[j], q[b], cf[b], cr[b])
            for i in range(N_STATE):
                X[i * LANES + j] = x[b, i]
            running[j] = 1 if j < n_lanes else 0
            if j < n_lanes and n_ticks[b] > most:
                most = n_ticks[b]
        for k in range(most + 1):
            # the tick's outputs of every lane at once: the right-hand side of the state with
            # the input held since the last step (Simulator.outputs())
            for i in range(n_x):
                IN[i] = X[i]
            _LANES.rhs_lanes(IN, OUT)
            for j in range(n_lanes):
                if running[j] == 0:
                    continue
                b = g0 + j
                xj = xs
                for i in range(N_STATE):
                    xj[i] = X[i * LANES + j]
                row = out[b, k]
                _state_row(xj, (k * n_step) * dt, OUT[_LANES.R_AX * LANES + j],
                           OUT[_LANES.R_AY * LANES + j], OUT[_LANES.R_DF * LANES + j],
                           OUT[_LANES.R_DR * LANES + j], row)
                if k == n_ticks[b]:  # the state after the last tick
                    _no_commands(row)
                    codes[b] = DONE
                    ticks[b] = k
                    running[j] = 0
                    continue
                if _past_limits(row, drv[b]):  # the maneuver is done at this state
                    _no_commands(row)
                    codes[b] = LIMITS
                    ticks[b] = k
                    running[j] = 0
                    continue
                code = _respond(xj, ul[j], k, dt, n_step, row, hand[b, k], front[b, k],
                                drv[b], law_kind[b], law_flat[law_start[b]:law_start[b + 1]],
                                min_speed[b], angle_limit[b], max_step[b], carry[j], drive,
                                brake, k_gain)
                if code != DONE:
                    codes[b] = code
                    ticks[b] = k
                    running[j] = 0
                    continue
                for i in range(N_INPUT):
                    IN[(_LANES.R_U + i) * LANES + j] = ul[j, i]
            n_running = 0
            for j in range(LANES):
                stepping[j] = running[j]
                n_running += running[j]
            if n_running == 0:
                break
            _LANES.rk4_lanes(X, IN, OUT, K, XT, RATE, stepping, dt, n_step, xs, us, qs, cfs,
                             crs, work, aux)
            for j in range(n_lanes):
                if running[j] != 0 and stepping[j] == 0:  # a state became non-finite
                    codes[g0 + j] = DIVERGED
                    ticks[g0 + j] = k + 1
                    running[j] = 0


# ------------------------------------------------------------------------------ compiling

#: numba options: those of the 8-DOF kernels (IEEE division, no fast-math: no contraction or
#: reassociation, so the compiled arithmetic is the interpreted one).
JIT_OPTIONS = dict(compiled.JIT_OPTIONS)
#: What this variant compiles in besides this file: the laws (their modules, the registry's
#: order of the kinds, the law step), the driver, the vehicle-limits rule, and the 8-DOF
#: kernels of the tire.
VARIANT = variants.Variant(__file__, TIRE_NAME, (*compiled.source_modules(), drivers, outcome),
                           JIT_OPTIONS, depends=(kernel_module(TIRE_NAME).VARIANT,))

_gains = VARIANT.inline(_gains)
_outputs = VARIANT.inline(_outputs)
_state_row = VARIANT.inline(_state_row)
_respond = VARIANT.inline(_respond)
_no_commands = VARIANT.inline(_no_commands)
_past_limits = VARIANT.inline(_past_limits)
_run_point = VARIANT.inline(_run_point)
closed_loop_block = VARIANT.jit(closed_loop_block)
#: The batch kernel in vector instructions, where the tire has lane kernels.
HAS_LANES = _LANES is not None
if HAS_LANES:
    closed_loop_lanes = VARIANT.jit(closed_loop_lanes)
