"""ISO 17288 free-steer metrics on synthetic signals with closed forms (fourws_analysis.iso17288).

Source of every number: the damped oscillation x = x0 e^(-sigma t) cos(omega t), whose
extrema, zero crossings, overshoot and residual are written out by hand below.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fourws_analysis.bag import MetricUnavailableError
from fourws_analysis.iso17288 import (RESIDUAL_TIME_S, oscillation, pulse_metrics,
                                      release_metrics)

DT = 0.01  # s, the recorded state period
ZETA, FREQ_HZ = 0.15, 1.3


def _omega() -> tuple[float, float]:
    """(sigma, omega_d) of the damped oscillation (1/s, rad/s)."""
    wn = 2.0 * math.pi * FREQ_HZ / math.sqrt(1.0 - ZETA ** 2)
    return ZETA * wn, 2.0 * math.pi * FREQ_HZ


def test_oscillation_gives_damping_ratio_and_frequency() -> None:
    """Half-cycle logarithmic decrement and extrema spacing recover zeta and f_d of a damped
    cosine sampled at 100 Hz within 0.5 % (the extrema refined by parabolas)."""
    sigma, wd = _omega()
    t = np.arange(0.0, 8.0, DT)
    y = 0.3 + 2.0 * np.exp(-sigma * t) * np.cos(wd * t)
    osc = oscillation(t, y, 0.3)
    assert osc.damping_ratio == pytest.approx(ZETA, rel=5e-3)
    assert osc.frequency_hz == pytest.approx(FREQ_HZ, rel=5e-3)
    assert osc.extrema >= 6
    flat = oscillation(t, 0.3 + np.exp(-t), 0.3)  # no swing: nothing to measure
    assert flat.damping_ratio is None and flat.frequency_hz is None


def test_release_metrics_of_a_damped_return() -> None:
    """Steady r0 until the release, then r0 e^(-sigma tau) cos(omega tau): overshoot
    e^(-sigma tau*) |cos(omega tau*)| at tan(omega tau*) = -sigma/omega, first zero at
    pi / (2 omega), residual r0 e^(-3 sigma) cos(3 omega), settled when the envelope last
    leaves 5 % of r0, zeta and f_d of the oscillation (within 2 %: it is measured about the
    record's final value, the mean of its last 0.5 s, which sits 3e-4 r0 off zero and biases
    the small late extrema)."""
    sigma, wd = _omega()
    release, r0, d0 = 10.0, 0.14, 1.2
    t = np.arange(0.0, 16.0, DT)
    tau = np.maximum(t - release, 0.0)
    shape = np.exp(-sigma * tau) * np.cos(wd * tau)
    r = r0 * shape
    d = d0 * shape  # the steering wheel returns the same way
    m = release_metrics(t, r, d, release, lateral_accel_mps2=np.full_like(t, 4.0))
    assert m.yaw_rate_initial_radps == pytest.approx(r0, rel=1e-12)
    assert m.lateral_accel_initial_mps2 == pytest.approx(4.0)
    t_min = (math.pi - math.atan(sigma / wd)) / wd
    over = math.exp(-sigma * t_min) * abs(math.cos(wd * t_min))
    assert m.yaw_rate_overshoot == pytest.approx(over, rel=2e-3)
    assert m.steering_wheel_overshoot == pytest.approx(over, rel=2e-3)
    assert m.yaw_rate_zero_time_s == pytest.approx(math.pi / (2.0 * wd), abs=1e-4)
    assert m.residual_yaw_rate_radps == pytest.approx(
        r0 * math.exp(-3.0 * sigma) * math.cos(3.0 * wd), abs=1e-6)
    # settled: the last sample with |r| > 5 % r0 lies where the envelope is about 5 %
    envelope_end = math.log(1.0 / 0.05) / sigma
    assert m.settling_time_s is not None
    assert envelope_end - 1.0 / FREQ_HZ < m.settling_time_s <= envelope_end + DT
    assert m.yaw.damping_ratio == pytest.approx(ZETA, rel=2e-2)
    assert m.yaw.frequency_hz == pytest.approx(FREQ_HZ, rel=2e-2)


def test_release_needs_the_record_around_it() -> None:
    t = np.arange(0.0, 12.0, DT)
    with pytest.raises(MetricUnavailableError, match="after"):
        release_metrics(t, np.ones_like(t), np.ones_like(t), 10.0)


def test_pulse_metrics_of_a_free_oscillation() -> None:
    """After a pulse ending at t_e the yaw rate swings as R e^(-sigma tau) sin(omega tau):
    the peak is R e^(-sigma tau_p) sin(omega tau_p) at tan(omega tau_p) = omega/sigma; the
    oscillation, read from OSCILLATION_DELAY_S after the pulse, has zeta and f_d."""
    sigma, wd = _omega()
    t_s, t_e, big_r = 0.5, 0.7, 0.2
    t = np.arange(0.0, 6.0, DT)
    tau = np.maximum(t - t_e, 0.0)
    r = big_r * np.exp(-sigma * tau) * np.sin(wd * tau)
    m = pulse_metrics(t, r, 3.0 * r, t_s, t_e)
    tau_p = math.atan(wd / sigma) / wd
    peak = big_r * math.exp(-sigma * tau_p) * math.sin(wd * tau_p)
    assert m.peak_yaw_rate_radps == pytest.approx(peak, rel=2e-3)
    assert m.peak_steering_wheel_rad == pytest.approx(3.0 * peak, rel=2e-3)
    assert m.yaw.damping_ratio == pytest.approx(ZETA, rel=5e-3)
    assert m.yaw.frequency_hz == pytest.approx(FREQ_HZ, rel=5e-3)
    assert m.residual_yaw_rate_radps == pytest.approx(
        big_r * math.exp(-sigma * RESIDUAL_TIME_S) * math.sin(wd * RESIDUAL_TIME_S), abs=1e-6)
