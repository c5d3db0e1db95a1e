"""Frequency response from recorded runs (fourws_analysis/frequency.py)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from fourws_analysis import bag as B
from fourws_analysis import frequency as F
from fourws_sim.params import vehicle_from_mapping

#: Table 4.1 set 1 (Yeh and Wu) of Samsundar (1996): m, Iz, a, b, per-axle Cf, Cr.
SET_1 = {
    "name": "table_4_1_set_1_test",
    "chassis": {"mass_kg": 3943.0, "yaw_inertia_kgm2": 6238.0, "cg_to_front_axle_m": 1.52,
                "cg_to_rear_axle_m": 1.70},
    "axle_tires": {"cornering_stiffness_front_n_per_rad": 84957.0,
                   "cornering_stiffness_rear_n_per_rad": 84957.0},
}
SPEED = 20.0


def simulate_2dof(vehicle, speed, t, delta_f):
    """lsim of the 2-DOF model; returns the VehicleState channels of the run."""
    from fourws_sim.models import linear2dof as m2

    A, Bm = m2.matrices(vehicle, speed)
    b = Bm[:, m2.INPUT.DELTA_F]
    C = np.eye(2)
    _, _, x = signal.lsim((A, b[:, None], C, np.zeros((2, 1))), delta_f, t)
    v, r = x[:, m2.STATE.V], x[:, m2.STATE.R]
    vdot = x @ A[m2.STATE.V] + b[m2.STATE.V] * delta_f
    return {"speed_mps": np.full(t.size, speed), "lateral_velocity_mps": v,
            "yaw_rate_radps": r, "sideslip_rad": np.arctan2(v, speed),
            "lateral_accel_mps2": vdot + speed * r, "front_wheel_angle_rad": delta_f}


def test_swept_sine_bag_matches_analytic_bode(tmp_path: Path) -> None:
    """Swept-sine 2-DOF run written as a bag: H1 estimate within 0.5 dB and 5 deg of the
    analytic transfer function wherever coherence > 0.95, over at least 0.2-3 Hz."""
    vehicle = vehicle_from_mapping(SET_1)
    dt = 1.0 / 200.0
    t = np.arange(0.0, 60.0, dt)
    # phi = -90 deg: the sweep starts from straight running
    delta = math.radians(1.0) * signal.chirp(t, 0.1, t[-1], 4.0, method="logarithmic",
                                             phi=-90.0)
    state = simulate_2dof(vehicle, SPEED, t, delta)
    config = {"vehicle": SET_1, "maneuver": {"type": "swept_sine"}, "law": "fws",
              "model": "2dof", "speed_mps": SPEED}
    B.write_run(tmp_path / "sweep", t, state, config, model="2dof")
    uni = B.resample(B.load_bag(tmp_path / "sweep"))
    model = F.linear_system(vehicle, "2dof", SPEED)
    for out in ("yaw_rate_radps", "lateral_accel_mps2", "sideslip_rad"):
        est = F.estimate_response(uni.channels["front_wheel_angle_rad"], uni.channels[out],
                                  uni.dt_s, method="transient", output=out)
        ok = est.trusted()
        f = est.freq_hz[ok]
        assert f.min() < 0.2 and f.max() > 3.0, (out, f.min(), f.max())
        ref = model.response(out, f)
        err_db = np.abs(est.gain_db[ok] - ref.gain_db)
        err_deg = np.abs((est.phase_deg[ok] - ref.phase_deg + 180.0) % 360.0 - 180.0)
        assert err_db.max() < 0.5, (out, err_db.max())
        assert err_deg.max() < 5.0, (out, err_deg.max())


def test_steady_state_gain_of_linear_system_is_textbook_yaw_gain() -> None:
    """DC yaw-rate gain of the FWS 2-DOF model: r/delta = U / (L + K_us U^2) (textbook)."""
    vehicle = vehicle_from_mapping(SET_1)
    L = vehicle.chassis.wheelbase_m
    expected = SPEED / (L + vehicle.understeer_gradient_rad_per_mps2 * SPEED ** 2)
    got = F.linear_system(vehicle, "2dof", SPEED).dc_gain("yaw_rate_radps")
    assert got == pytest.approx(expected, rel=1e-10)
    # a_y = U r at steady state
    assert F.linear_system(vehicle, "2dof", SPEED).dc_gain("lateral_accel_mps2") == \
        pytest.approx(SPEED * expected, rel=1e-10)


def test_metrics_of_second_order_system() -> None:
    """Resonance, bandwidth and phase of wn^2/(s^2 + 2 zeta wn s + wn^2) match the analytic
    formulas: peak 1/(2 zeta sqrt(1-zeta^2)) at wn sqrt(1-2 zeta^2); -3 dB at
    wn sqrt(1 - 2 zeta^2 + sqrt(4 zeta^4 - 4 zeta^2 + 2))."""
    zeta, wn = 0.3, 2 * math.pi * 1.5
    f = np.linspace(0.01, 5.0, 20000)
    s = 2j * math.pi * f
    fr = F.FrequencyResponse("y", "u", f, wn ** 2 / (s ** 2 + 2 * zeta * wn * s + wn ** 2))
    m = F.response_metrics(fr)
    assert m.steady_state_gain == pytest.approx(1.0, rel=1e-3)
    assert m.resonance_ratio == pytest.approx(1 / (2 * zeta * math.sqrt(1 - zeta ** 2)),
                                              rel=1e-3)
    assert m.resonance_freq_hz == pytest.approx(wn * math.sqrt(1 - 2 * zeta ** 2) / (2 * math.pi),
                                                rel=2e-3)
    bw = wn * math.sqrt(1 - 2 * zeta ** 2 + math.sqrt(4 * zeta ** 4 - 4 * zeta ** 2 + 2))
    assert m.bandwidth_hz == pytest.approx(bw / (2 * math.pi), rel=2e-3)
    w1 = 2 * math.pi
    assert m.phase_lag_1hz_deg == pytest.approx(
        math.degrees(math.atan2(2 * zeta * wn * w1, wn ** 2 - w1 ** 2)), abs=0.05)


def test_constant_input_has_no_frequency_response() -> None:
    """A run without excitation (constant steer) is refused, naming the input."""
    u = np.full(5000, 0.02)
    with pytest.raises(B.MetricUnavailableError, match="front_wheel_angle_rad.*no excitation"):
        F.estimate_response(u, np.sin(np.arange(5000) * 0.01), 0.01,
                            input_name="front_wheel_angle_rad")
