# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Every rear-steer law in the loop it runs in: the 8-DOF car of chapter 8 (table_8_1), the law
sampled at the 100 Hz default control rate and held by the 5 deg / 30 deg/s actuator
(fourws_run.closed_loop, the offline twin of the lockstep node graph).

Sources: ISO 7401 (step steer at 4 m/s^2, ramp within 0.15 s), the linearized 8-DOF closed
with each law and sampled at the control period (fourws_analysis.compare.eightdof_sampled_loop:
a loop is stable when every |z| < 1), the feed-forward term of each law (its gain on delta_f
times the steering rate of the ramp is a rear-steer rate the actuator must follow).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from fourws_analysis.compare import eightdof_linear_system, eightdof_sampled_loop
from fourws_analysis.frequency import dc_gain
from fourws_control import Signal, available_laws, make_loop_law
from fourws_run.closed_loop import run_closed_loop
from fourws_sim.maneuvers import load_maneuver_spec
from fourws_sim.params import load_vehicle

CAR = "table_8_1"
#: The default control period, s (config/scenarios/default.yaml).
PERIOD_S = 0.01
#: ISO 7401's lateral acceleration for the step, m/s^2.
TARGET_AY_MPS2 = 4.0
#: Laws whose sampled closed loop with table_8_1 is unstable (asserted below): sol2 on an
#: oversteer car (sol2.py; test_maneuvers.py::test_sol2_car_diverges_with_the_steering_held).
UNSTABLE = {"sol2"}
STABLE = [law for law in available_laws() if law not in UNSTABLE]
#: Largest |z| of the stable loops' lateral modes (linearized 8-DOF, 85 km/h, 100 Hz): 0.9831
#: for fws, the slow roll-oversteer mode, time constant -T/ln|z| = 0.59 s.
MAX_STABLE_RADIUS = 0.985
#: Settled: the last second of a 6 s run, 4.4 s after the steering ramp (7.5 time constants of
#: the slowest mode: its transient has decayed to e^-7.5 = 6e-4 of its size).
SETTLED_FROM_S = 5.0
DURATION_S = 6.0
#: Bound on the settled yaw-rate swing (peak to peak) relative to the steady yaw rate: 0.2 %,
#: a few times the decayed transient (0.06 %) plus the speed-hold driver's speed ripple
#: (~0.01 m/s, 0.04 % of 23.6 m/s, which scales the yaw rate alike). A limit cycle like the
#: continuous lqr design's at 100 Hz swings by ~100 % (0.19 rad/s, test_maneuvers.py).
SWING_BOUND = 2e-3
#: No saturation once the steer is held (0.4 s after the ramp ends, when a rate-limited
#: actuator has caught up with the ramp).
HELD_FROM_S = 1.0


def _step(amplitude_rad: float, duration_s: float = DURATION_S):
    data = load_maneuver_spec("step_steer_85kmh").to_dict()
    data.update(amplitude_rad=float(amplitude_rad), duration_s=duration_s)
    return load_maneuver_spec(data)


def _swing(res, from_s: float) -> float:
    """Peak-to-peak yaw rate after ``from_s`` relative to its mean there."""
    r = res["yaw_rate_radps"][res.time_s >= from_s]
    return float(np.ptp(r) / abs(np.mean(r)))


@functools.lru_cache(maxsize=None)
def _iso7401_run(law: str) -> tuple:
    """The ISO 7401 step at 85 km/h whose steady lateral acceleration is 4 m/s^2 (within
    1 %): the amplitude starts from the linearized 8-DOF's steady-state gain and is refined
    by secant steps on simulated runs (the car's a_y grows less than linearly with the steer:
    fws gets 3.5 m/s^2 from the linear estimate). Returns ``(result, amplitude, a_y)``."""
    car = load_vehicle(CAR)
    speed = _step(0.0).initial_speed_mps
    gain = dc_gain(eightdof_linear_system(car, speed, law, None,
                                          {"control_period_s": PERIOD_S}),
                   "lateral_accel_mps2")

    def run(amplitude: float) -> tuple:
        res = run_closed_loop(car, _step(amplitude), law, control_period_s=PERIOD_S)
        return res, float(np.mean(res["lateral_accel_mps2"][res.time_s >= SETTLED_FROM_S]))

    amps = [TARGET_AY_MPS2 / gain]
    res, a_y = run(amps[0])
    a_ys = [a_y]
    amps.append(amps[0] * TARGET_AY_MPS2 / a_y)
    for _ in range(4):
        res, a_y = run(amps[-1])
        a_ys.append(a_y)
        if abs(a_y / TARGET_AY_MPS2 - 1.0) < 0.01:
            break
        slope = (a_ys[-1] - a_ys[-2]) / (amps[-1] - amps[-2])
        amps.append(amps[-1] + (TARGET_AY_MPS2 - a_y) / slope)
    return res, amps[len(a_ys) - 1], a_y


def test_sampled_linearization_finds_the_unstable_law():
    """The linearized 8-DOF at 85 km/h closed with each law and sampled at 100 Hz: every law
    but sol2 is stable, with its slowest lateral mode at |z| <= 0.985 (the premise of the
    settling bound below); sol2's loop is unstable (|z| > 1)."""
    car = load_vehicle(CAR)
    speed = _step(0.0).initial_speed_mps
    # the 8-DOF's speed and wheel-spin modes (z = 1 at a trim without drag) do not respond
    # to steering: radius(1e-6) leaves them out
    radius = {law: eightdof_sampled_loop(car, speed, PERIOD_S, law, None,
                                         {"control_period_s": PERIOD_S}).radius(1e-6)
              for law in available_laws()}
    assert {law for law, rho in radius.items() if rho >= 1.0} == UNSTABLE
    assert max(radius[law] for law in STABLE) < MAX_STABLE_RADIUS


@pytest.mark.parametrize("law", STABLE)
def test_iso7401_step_at_4_mps2_settles_within_the_actuator(law: str) -> None:
    """ISO 7401 step at 85 km/h and 4 m/s^2, steer held, 100 Hz: the yaw rate settles (swing
    over the last second below SWING_BOUND: no limit cycle); the rear command never reaches
    the 5 deg angle limit; the actuator follows every command once the steer is held, and
    during the ramp exactly when the law's feed-forward rate |k_delta| * ramp rate is within
    the 30 deg/s rate limit (sol1 and rwc4_3dof ask ~32 deg/s, so the actuator lags them for
    a few ticks of the ramp)."""
    car = load_vehicle(CAR)
    act = car.actuators
    res, amplitude, a_y = _iso7401_run(law)
    assert a_y == pytest.approx(TARGET_AY_MPS2, rel=0.01)
    assert _swing(res, SETTLED_FROM_S) < SWING_BOUND
    assert np.max(np.abs(res.rear_law_rad)) < act.rear_angle_limit_rad
    lagging = np.abs(res.rear_law_rad - res.rear_angle_rad) > 1e-12
    assert not np.any(lagging[res.time_s >= HELD_FROM_S])
    params = _step(amplitude).params
    law_obj = make_loop_law(law, car, PERIOD_S)
    k_delta = law_obj.gains(_step(0.0).initial_speed_mps)[Signal.DELTA_F]
    feed_forward_rate = abs(k_delta * amplitude) / params.ramp_time_s
    assert bool(np.any(lagging)) == (feed_forward_rate > act.rear_rate_limit_rad_per_s)


@pytest.mark.parametrize("period_s", [0.01, 0.02])
def test_lqr_settles_with_the_steer_held_at_100_and_50_hz(period_s: float) -> None:
    """The shipped ISO 7401 step (1.5 deg at 85 km/h), lqr designed for the loop's period:
    the yaw-rate swing after 2 s is below 1 % of its steady value (the continuous design at
    100 Hz keeps swinging by ~0.19 rad/s, test_maneuvers.py), and the actuator follows every
    command (angle and rate within 5 deg and 30 deg/s)."""
    car = load_vehicle(CAR)
    res = run_closed_loop(car, load_maneuver_spec("step_steer_85kmh"), "lqr",
                          control_period_s=period_s)
    assert res.config["control_period_s"] == period_s
    assert _swing(res, 2.0) < 0.01
    assert np.max(np.abs(res.rear_law_rad)) < car.actuators.rear_angle_limit_rad
    np.testing.assert_allclose(res.rear_angle_rad, res.rear_law_rad, rtol=0.0, atol=1e-12)


@pytest.mark.parametrize("law", available_laws())
def test_eightdof_closed_loop_is_the_law_gains_on_the_linearization(law: str) -> None:
    """The 8-DOF closed loop is the law's own gains on the linearized model: the expected
    matrices are built here from the finite-difference Jacobians at straight running and
    the law's gain vector in Signal order, each gain put on the 8-DOF state of the same
    meaning (delta_r = k_delta delta_f + k_r R + k_phi PHI + k_p P + k_V V), the earth-frame
    position and the idle free-steering states left out (nothing depends on them: zero
    columns). eightdof_linear_system (A, B, the rear-command output) and
    eightdof_sampled_loop (the zero-order-hold transition matrix) must equal them to the last
    bit (the same floating-point operations), at a walking-pace-faded and two driving
    speeds."""
    import scipy.signal

    from fourws_analysis.linearize import jacobians, model_derivatives
    from fourws_sim.models import eightdof as m8

    car = load_vehicle(CAR)
    s, i = m8.STATE, m8.INPUT
    law_obj = make_loop_law(law, car, PERIOD_S)  # built once: lqr's design takes seconds
    for speed in (1.5, 16.0, 30.0):
        p = m8.params_for(car)
        x0, u0 = m8.initial_state(p, speed), np.zeros(len(i))
        a, b = jacobians(model_derivatives(m8), x0, u0, p)
        # the linearization differentiates the compiled right-hand side: the NumPy
        # reference's Jacobians agree to round-off
        a_ref, b_ref = jacobians(m8.derivatives, x0, u0, p)
        np.testing.assert_allclose(a, a_ref, rtol=0, atol=1e-12 * np.max(np.abs(a_ref)))
        np.testing.assert_allclose(b, b_ref, rtol=0, atol=1e-12 * np.max(np.abs(b_ref)))
        k = law_obj.gains(speed)
        k_x = np.zeros(len(s))
        k_x[s.R], k_x[s.PHI] = k[Signal.YAW_RATE], k[Signal.ROLL]
        k_x[s.P], k_x[s.V] = k[Signal.ROLL_RATE], k[Signal.LATERAL_VELOCITY]
        a_cl = a + np.outer(b[:, i.DELTA_R], k_x)
        b_cl = b[:, i.DELTA_F] + b[:, i.DELTA_R] * k[Signal.DELTA_F]
        # the earth-frame position, and with fixed steering control the free steering
        # system's two states (they stay 0), drive nothing
        idle = (s.X, s.Y, s.DELTA_S, s.DELTA_S_RATE)
        keep = [j for j in range(len(s)) if j not in idle]
        assert np.all(a_cl[:, list(idle)] == 0.0)
        assert np.all(np.any(a_cl[:, keep] != 0.0, axis=0))

        system = eightdof_linear_system(car, speed, law_obj)
        assert list(system.state_labels) == [s(j).name for j in keep]
        np.testing.assert_array_equal(system.A, a_cl[np.ix_(keep, keep)])
        np.testing.assert_array_equal(system.B[:, 0], b_cl[keep])
        rear = system.find_output("rear_wheel_angle_rad")
        np.testing.assert_array_equal(system.C[rear], k_x[keep])
        assert system.D[rear, 0] == k[Signal.DELTA_F]

        phi, gamma, *_ = scipy.signal.cont2discrete(
            (a[np.ix_(keep, keep)], b[keep][:, [i.DELTA_R]], np.zeros((1, len(keep))),
             np.zeros((1, 1))), PERIOD_S, method="zoh")
        loop = eightdof_sampled_loop(car, speed, PERIOD_S, law_obj)
        np.testing.assert_array_equal(loop.Phi, phi + gamma @ k_x[keep][None, :])
