# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""ISO 7401 step metrics, ISO 4138 understeer gradient, eigenvalue identification and
numerical linearization (fourws_analysis/iso7401.py, iso4138.py, identify.py, linearize.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, signal

from fourws_analysis import identify, iso4138, iso7401, linearize
from fourws_analysis.bag import MetricUnavailableError
from fourws_sim.params import vehicle_from_mapping
from test_analysis_frequency import SET_1  # Table 4.1 set 1 (Yeh and Wu)


def second_order_step(t: np.ndarray, zeta: float, wn: float, gain: float) -> np.ndarray:
    """Unit-step response of gain wn^2/(s^2 + 2 zeta wn s + wn^2), zero for t < 0."""
    wd = wn * math.sqrt(1 - zeta ** 2)
    tt = np.maximum(t, 0.0)
    y = gain * (1 - np.exp(-zeta * wn * tt) * (np.cos(wd * tt)
                                               + zeta / math.sqrt(1 - zeta ** 2)
                                               * np.sin(wd * tt)))
    return np.where(t >= 0.0, y, 0.0)


def test_step_metrics_of_second_order_response() -> None:
    """Peak time pi/wd, overshoot exp(-zeta pi/sqrt(1-zeta^2)), 90 % response time (root of
    the analytic response), steady-state gain K/step."""
    zeta, wn, gain, step = 0.4, 2 * math.pi * 1.2, 0.35, math.radians(2.0)
    dt = 1e-3
    t = np.arange(0.0, 8.0, dt)
    t_step = 1.0
    # steer ramps over 2 samples centred on t_step so its 50 % point is exactly t_step
    steer = step * np.clip((t - t_step) / dt + 0.5, 0.0, 1.0)
    y = second_order_step(t - t_step, zeta, wn, gain * step)
    res = iso7401.step_metrics(t, steer, {"yaw_rate_radps": y})
    m = res.responses["yaw_rate_radps"]
    wd = wn * math.sqrt(1 - zeta ** 2)
    assert res.t0_s == pytest.approx(t_step, abs=1e-9)
    assert m.peak_response_time_s == pytest.approx(math.pi / wd, rel=2e-3)
    assert m.overshoot == pytest.approx(math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2)),
                                        rel=2e-3)
    t90 = optimize.brentq(lambda s: second_order_step(np.array([s]), zeta, wn, 1.0)[0] - 0.9,
                          1e-6, math.pi / wd)
    assert m.response_time_s == pytest.approx(t90, rel=3e-3)
    assert m.steady_state_gain == pytest.approx(gain, rel=1e-3)
    assert m.settled


def test_tb_factor_is_peak_time_times_sideslip() -> None:
    """TB = T(yaw peak) * beta_ss in deg; with beta following the same 2nd-order shape."""
    zeta, wn = 0.5, 2 * math.pi
    dt = 1e-3
    t = np.arange(0.0, 6.0, dt)
    steer = math.radians(1.0) * np.clip((t - 1.0) / dt + 0.5, 0.0, 1.0)
    yaw = second_order_step(t - 1.0, zeta, wn, 0.1)
    beta = second_order_step(t - 1.0, 0.9, wn, math.radians(-0.8))
    res = iso7401.step_metrics(t, steer, {"yaw_rate_radps": yaw}, sideslip_rad=beta)
    tp = math.pi / (wn * math.sqrt(1 - zeta ** 2))
    assert res.tb_factor_s_deg == pytest.approx(tp * 0.8, rel=3e-3)


def _spike_run(bump_at_s: float, bump_width_s: float, bump_size: float,
               rear_moves: bool = False) -> iso7401.StepResult:
    """A step sampled at 100 Hz as a bag gives it: yaw rate a 2nd-order response (zeta 0.5,
    wn 8 rad/s: peak time pi/wd = 0.453 s); lateral acceleration a 2nd-order response
    (zeta 0.7, wn 6 rad/s: 4.6 % overshoot at 0.733 s) plus a Gaussian bump of
    ``bump_size`` x its steady state at ``bump_at_s`` after the step, standard deviation
    ``bump_width_s``; the rear angle steps by 0.5 x the front step at t0 when it moves."""
    dt = 0.01
    t = np.arange(0.0, 6.0, dt)
    step = math.radians(1.5)
    steer = step * np.clip((t - 0.5) / 0.1, 0.0, 1.0)  # 0.1 s ramp: t0 = 0.55 s
    t0 = 0.55
    yaw = second_order_step(t - t0, 0.5, 8.0, 0.1)
    ay = second_order_step(t - t0, 0.7, 6.0, 2.0) \
        + 2.0 * bump_size * np.exp(-0.5 * ((t - t0 - bump_at_s) / bump_width_s) ** 2)
    rear = np.where(t >= t0, 0.5 * step, 0.0) if rear_moves else np.zeros_like(t)
    return iso7401.step_metrics(t, steer, {"yaw_rate_radps": yaw, "lateral_accel_mps2": ay},
                                rear_wheel_rad=rear)


def test_lateral_acceleration_spike_is_flagged_with_its_cause() -> None:
    """The spike rule (iso7401 module docstring): a_y peak earlier than half the yaw rate's
    peak time (0.453 s / 2 = 0.227 s) and narrower (full width at half the overshoot) than
    that. A bump at 0.08 s, sigma 0.015 s (FWHM 2.355 sigma = 0.035 s) is a spike; its cause
    is the rear steer when the rear angle moves in that window, else the steer ramp."""
    res = _spike_run(0.08, 0.015, 1.5, rear_moves=True)
    yaw, ay = res.responses["yaw_rate_radps"], res.responses["lateral_accel_mps2"]
    wd = 8.0 * math.sqrt(1 - 0.25)
    assert yaw.peak_response_time_s == pytest.approx(math.pi / wd, abs=0.01)
    assert ay.peak_response_time_s == pytest.approx(0.08, abs=0.01)
    # peak: the 2nd-order part at 0.08 s plus the bump's 1.5 x the steady state
    base = second_order_step(np.array([0.08]), 0.7, 6.0, 1.0)[0]
    assert ay.overshoot == pytest.approx(base + 1.5 - 1.0, abs=0.05)
    assert ay.spike.startswith("one spike 0.08 s after the step")
    assert "rear-steer command" in ay.spike and "+0.75 deg" in ay.spike  # 0.5 x 1.5 deg
    assert ay.to_dict()["overshoot_is_spike"] is True
    assert "steer ramp itself" in _spike_run(0.08, 0.015, 1.5).responses[
        "lateral_accel_mps2"].spike
    assert yaw.spike == ""  # the rule is for the lateral acceleration


@pytest.mark.parametrize("bump_at_s, bump_width_s, bump_size", [
    (0.08, 0.0, 0.0),     # no bump: the 2nd-order overshoot at 0.733 s is the car's own
    (0.30, 0.015, 1.5),   # narrow, but after half the yaw rise (0.30 > 0.227 s)
    (0.15, 0.20, 1.5),    # centred early, but wide (FWHM 2.355 x 0.2 = 0.47 s > 0.227 s)
])
def test_an_overshoot_of_the_cars_own_response_is_not_a_spike(
        bump_at_s: float, bump_width_s: float, bump_size: float) -> None:
    res = _spike_run(bump_at_s, max(bump_width_s, 1e-3), bump_size)
    ay = res.responses["lateral_accel_mps2"]
    assert ay.overshoot is not None and ay.overshoot > 0.0
    assert ay.spike == ""
    assert ay.to_dict()["overshoot_is_spike"] is False


def test_step_without_hold_is_refused() -> None:
    """A pulse (steer back to zero after 0.5 s) gives no steady state: clear message."""
    t = np.arange(0.0, 5.0, 1e-3)
    steer = np.where((t > 1.0) & (t < 1.5), 0.02, 0.0)
    with pytest.raises(MetricUnavailableError, match="held 0.5.* s after the step"):
        iso7401.step_metrics(t, steer, {"yaw_rate_radps": steer})


def _simulate_2dof(vehicle, speed, t, delta):
    from fourws_sim.models import linear2dof as m2

    A, B = m2.matrices(vehicle, speed)
    b = B[:, m2.INPUT.DELTA_F]
    _, _, x = signal.lsim((A, b[:, None], np.eye(2), np.zeros((2, 1))), delta, t)
    v, r = x[:, m2.STATE.V], x[:, m2.STATE.R]
    ay = x @ A[m2.STATE.V] + b[m2.STATE.V] * delta + speed * r
    return A, v, r, ay


@pytest.mark.parametrize("speed", [15.0, 30.0])
def test_understeer_gradient_from_constant_speed_ramp(speed: float) -> None:
    """Slow ramp steer at constant speed on the 2-DOF model: K_us within 2 % of
    m/L (b/Cf - a/Cr); characteristic speed sqrt(L/K_us)."""
    vehicle = vehicle_from_mapping(SET_1)
    dt = 0.01
    t = np.arange(0.0, 40.0, dt)
    L = vehicle.chassis.wheelbase_m
    kus = vehicle.understeer_gradient_rad_per_mps2
    # ramp to the steer of a_y = 4 m/s^2 over 40 s (quasi-steady: ~0.1 m/s^2 per s)
    delta_max = (L / speed ** 2 + kus) * 4.0
    delta = delta_max * t / t[-1]
    _, v, r, ay = _simulate_2dof(vehicle, speed, t, delta)
    settled = t > 3.0  # past the initial transient (time constants < 0.5 s)
    res = iso4138.steady_state_handling(ay[settled], delta[settled], r[settled],
                                        np.full(t.size, speed)[settled], L,
                                        sideslip_rad=np.arctan2(v, speed)[settled])
    assert res.understeer_gradient_rad_per_mps2 == pytest.approx(kus, rel=0.02)
    assert res.characteristic_speed_mps == pytest.approx(math.sqrt(L / kus), rel=0.01)
    assert res.critical_speed_mps is None
    # steady-state sideslip gradient of the 2-DOF: beta/ay = (b/U^2 - m a/(Cr L)) ... / via
    # the closed form beta_ss = delta*(b - m a U^2/(L Cr))/(L + Kus U^2), ay_ss = U^2 delta/(...)
    cr = vehicle.axle_tires.cornering_stiffness_rear_n_per_rad
    a, b, m = (vehicle.chassis.cg_to_front_axle_m, vehicle.chassis.cg_to_rear_axle_m,
               vehicle.chassis.mass_kg)
    expected_beta_grad = (b - m * a * speed ** 2 / (L * cr)) / speed ** 2
    assert res.sideslip_gradient_rad_per_mps2 == pytest.approx(expected_beta_grad, rel=0.02)


def test_understeer_needs_lateral_acceleration_span() -> None:
    """Straight running: no lateral acceleration span -> clear message."""
    n = 500
    with pytest.raises(MetricUnavailableError, match="spans 0.00 m/s"):
        iso4138.steady_state_handling(np.zeros(n), np.zeros(n), np.zeros(n),
                                      np.full(n, 20.0), 3.0)


@pytest.mark.parametrize("speed", [10.0, 25.0])
def test_identified_eigenvalues_of_2dof_step(speed: float) -> None:
    """Eigenvalues identified from a 2-DOF step response (yaw rate and lateral velocity)
    match eig(A) within 1 %."""
    vehicle = vehicle_from_mapping(SET_1)
    dt = 1e-3
    t = np.arange(0.0, 4.0, dt)
    delta = np.where(t >= 0.5, math.radians(2.0), 0.0)
    A, v, r, _ = _simulate_2dof(vehicle, speed, t, delta)
    modes = identify.identify_modes(t, delta, [r, v], order=2)
    pairs = identify.match_eigenvalues(modes.eigenvalues, np.linalg.eigvals(A))
    assert len(pairs) == 2
    for _, _, rel in pairs:
        assert rel < 0.01


def test_finite_difference_jacobian_reproduces_linear_model() -> None:
    """Numerical linearization of the 2-DOF model's derivatives gives its (A, B) exactly
    (central differences are exact for a linear function, up to rounding)."""
    from fourws_sim.models import linear2dof as m2

    vehicle = vehicle_from_mapping(SET_1)
    p = m2.params_for(vehicle, 20.0)
    a, b = linearize.jacobians(m2.derivatives, np.array([0.3, -0.1]), np.array([0.01, 0.0]), p)
    A, B = m2.matrices(vehicle, 20.0)
    np.testing.assert_allclose(a, A, rtol=1e-7, atol=1e-7)
    np.testing.assert_allclose(b, B, rtol=1e-7, atol=1e-4)
    sweep = linearize.eigenvalues_vs_speed(vehicle, [10.0, 20.0], model="2dof")
    np.testing.assert_allclose(np.sort_complex(sweep.eigenvalues[1]),
                               np.sort_complex(np.linalg.eigvals(A)), rtol=1e-6)
