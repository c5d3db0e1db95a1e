"""Frequency response from recorded runs (fourws_analysis/frequency.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import control
import numpy as np
import pytest
from scipy import signal

from fourws_analysis import bag as B
from fourws_analysis import frequency as F
from fourws_analysis import linear
from fourws_analysis import units as U
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
    model = linear.linear_system(vehicle, "2dof", SPEED)
    for out in ("yaw_rate_radps", "lateral_accel_mps2", "sideslip_rad"):
        est = F.estimate_response(uni.channels["front_wheel_angle_rad"], uni.channels[out],
                                  uni.dt_s, method="transient", output=out)
        ok = est.trusted()
        f = est.freq_hz[ok]
        assert f.min() < 0.2 and f.max() > 3.0, (out, f.min(), f.max())
        ref = F.model_response(model, out, f)
        err_db = np.abs(est.gain_db[ok] - ref.gain_db)
        err_deg = np.abs((est.phase_deg[ok] - ref.phase_deg + 180.0) % 360.0 - 180.0)
        assert err_db.max() < 0.5, (out, err_db.max())
        assert err_deg.max() < 5.0, (out, err_deg.max())


def test_steady_state_gain_of_linear_system_is_textbook_yaw_gain() -> None:
    """DC yaw-rate gain of the FWS 2-DOF model: r/delta = U / (L + K_us U^2) (textbook)."""
    vehicle = vehicle_from_mapping(SET_1)
    L = vehicle.chassis.wheelbase_m
    expected = SPEED / (L + vehicle.understeer_gradient_rad_per_mps2 * SPEED ** 2)
    got = F.dc_gain(linear.linear_system(vehicle, "2dof", SPEED), "yaw_rate_radps")
    assert got == pytest.approx(expected, rel=1e-10)
    # a_y = U r at steady state
    assert F.dc_gain(linear.linear_system(vehicle, "2dof", SPEED), "lateral_accel_mps2") == \
        pytest.approx(SPEED * expected, rel=1e-10)



def test_dc_gain_of_a_singular_model_is_its_low_frequency_limit() -> None:
    """A model with a mode the input reaches but no output sees (x1' = x2, like the 8-DOF's
    heading) has a singular A: the DC gain is the limit of the response, here of
    y/u = 1/(s + 2), 0.5 (within (2 pi DC_LIMIT_HZ / 2)^2 ~ 1e-11). A missing output is
    named with the model's outputs."""
    system = control.ss([[0.0, 1.0], [0.0, -2.0]], [[0.0], [1.0]], [[0.0, 1.0]], [[0.0]],
                        inputs=[U.ROAD_WHEEL.channel], outputs=["yaw_rate_radps"],
                        name="integrator and lag")
    assert F.dc_gain(system, "yaw_rate_radps") == pytest.approx(0.5, rel=1e-10)
    fr = F.model_response(system, "yaw_rate_radps", np.array([1.0]))
    assert fr.response[0] == pytest.approx(1.0 / (2j * math.pi + 2.0), rel=1e-12)
    assert fr.label == "integrator and lag" and fr.input == U.ROAD_WHEEL.channel
    with pytest.raises(B.MetricUnavailableError, match="no output 'roll_rad'.*yaw_rate_radps"):
        F.dc_gain(system, "roll_rad")

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


# --------------------------------------------------------------------------------------------
# random, pulse and steering-wheel inputs; the maneuvers are the shipped files, run with the
# project's own input generators (fourws_sim.maneuvers) and written as bags like the sweep

#: Outputs compared with the analytic 2-DOF response (roll is zero in the 2-DOF).
OUTPUTS_2DOF = ("yaw_rate_radps", "lateral_accel_mps2", "sideslip_rad")
#: Steering ratio of the steering-wheel tests (K_sr of config/vehicles/table_8_1.yaml).
STEERING_RATIO = 16.3


def _maneuver_bag(path: Path, maneuver: dict, vehicle_map: dict = SET_1,
                  driver_topic: bool = False) -> float:
    """Run ``maneuver`` (a maneuver mapping) open loop on the linear 2-DOF model of
    ``vehicle_map`` at the maneuver's initial speed and write the bag; returns the speed, m/s.

    The inputs come from ``Maneuver.command`` (hand-wheel and road-wheel angle of every
    200 Hz tick); ``driver_topic`` also records them as ``/fourws/driver_input``.
    """
    from fourws_sim.maneuvers import make_maneuver

    vehicle = vehicle_from_mapping(vehicle_map)
    man = make_maneuver(maneuver, vehicle)
    speed = man.initial_speed_mps
    t = np.arange(0.0, man.duration_s, 1.0 / 200.0)
    commands = [man.command(tk, {"speed_mps": speed}) for tk in t]
    front = np.array([c.front_wheel_angle_rad for c in commands])
    hand = np.array([c.steering_wheel_angle_rad for c in commands])
    config = {"vehicle": vehicle_map, "maneuver": man.spec.to_dict(), "law": "fws",
              "model": "2dof", "speed_mps": speed}
    driver = ({"steering_wheel_angle_rad": hand, "front_wheel_angle_rad": front}
              if driver_topic else None)
    B.write_run(path, t, simulate_2dof(vehicle, speed, t, front), config, driver=driver,
                model="2dof")
    return speed


def _shipped(name: str, **changes: Any) -> dict:
    """The mapping of ``config/maneuvers/<name>.yaml`` with ``changes`` applied."""
    from fourws_sim.maneuvers import load_maneuver_spec

    return {**load_maneuver_spec(name).to_dict(), **changes}


def _errors(est: F.FrequencyResponse, model: control.StateSpace, mask: np.ndarray,
            scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Gain (dB) and phase (deg, wrapped to +-180) differences of ``est`` from the analytic
    response times ``scale`` at the points of ``mask``."""
    ref = F.model_response(model, est.output, est.freq_hz[mask]).response * scale
    ratio = est.response[mask] / ref
    return 20.0 * np.log10(np.abs(ratio)), np.degrees(np.angle(ratio))


#: Seed of the random-steer tests (pinned here, not taken from the shipped file).
RANDOM_SEED = 1


@pytest.fixture(scope="module")
def random_bag(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """The shipped random_steer maneuver (0.05-3 Hz, 0.5 deg rms, 61 s) as a 2-DOF bag."""
    path = tmp_path_factory.mktemp("random") / "random_steer"
    return path, _maneuver_bag(path, _shipped("random_steer", seed=RANDOM_SEED))


@pytest.fixture(scope="module")
def pulse_bag(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """The shipped pulse maneuver (triangle, 0.4 s, 3 deg, 5 s record) as a 2-DOF bag."""
    path = tmp_path_factory.mktemp("pulse") / "pulse"
    return path, _maneuver_bag(path, _shipped("pulse"))


def _welch_random_error(coherence: np.ndarray | float, n_segments: int) -> np.ndarray:
    """Normalized random error of the H1 gain, which is also the standard deviation of its
    phase in rad (Bendat and Piersol, Random Data, ch. 9, frequency response estimates):
    eps = sqrt(1 - gamma^2) / (|gamma| sqrt(2 n_d))."""
    g2 = np.asarray(coherence, dtype=float)
    return np.sqrt(1.0 - g2) / (np.sqrt(g2) * math.sqrt(2.0 * n_segments))


def test_random_steer_bag_welch_h1_within_random_error_of_analytic_bode(
        random_bag: tuple[Path, float]) -> None:
    """Random-steer 2-DOF bag, Welch H1 (the path of ``random_steer`` runs) vs the analytic
    transfer function wherever coherence > 0.95 and the input is excited.

    Tolerance from the H1 random error with the record used: 10 s Hann segments, 50 %
    overlap, 61 s record -> n_d = 11 segments; at the trust threshold gamma^2 = 0.95 the
    error is eps = 0.049. Every trusted point must lie within 4 eps of the analytic value
    (20 log10(1 + 4 eps) = 1.55 dB, 4 eps = 11.2 deg; 4 sigma, so that none of the ~90
    points exceeds it by chance), and the RMS over the trusted band within the 1-sigma
    value at the threshold (0.41 dB, 2.8 deg; most points have far higher coherence),
    which a systematic error of 0.5 dB or a 10 ms delay exceeds. In a noise-free simulation
    the coherence loss comes from the window (the response to input from before a
    segment), which acts like output noise: over 60 seeds the RMS gain error of points with
    coherence 0.95-0.99 was within 10 % of eps, the phase error ~1.4 eps (the window's
    time-delay bias adds to it); the RMS bounds held for all 60 seeds, the point bounds for
    57. The seed is pinned. The trusted band must cover 0.2-3 Hz (input band 0.05-3 Hz,
    0.1 Hz bins) with >= 80 % of its bins.
    """
    path, speed = random_bag
    uni = B.resample(B.load_bag(path))
    model = linear.linear_system(vehicle_from_mapping(SET_1), "2dof", speed)
    segment_s = 1.0 / 0.1  # estimate_response's default resolution, 0.1 Hz
    duration = uni.time_s[-1] - uni.time_s[0]
    n_d = int((duration - segment_s) // (segment_s / 2)) + 1
    assert n_d == 11
    eps = float(_welch_random_error(F.COHERENCE_MIN, n_d))
    tol_db, tol_deg = 20.0 * math.log10(1.0 + 4.0 * eps), math.degrees(4.0 * eps)
    rms_db, rms_deg = 20.0 * math.log10(1.0 + eps), math.degrees(eps)
    for out in OUTPUTS_2DOF:
        est = F.estimate_response(uni.channels["front_wheel_angle_rad"], uni.channels[out],
                                  uni.dt_s, method="welch", output=out)
        ok = est.trusted()
        f = est.freq_hz[ok]
        band = (est.freq_hz >= 0.1 - 1e-9) & (est.freq_hz <= 3.0 + 1e-9)
        assert f.min() <= 0.2 and f.max() >= 3.0, (out, f.min(), f.max())
        assert np.count_nonzero(ok & band) >= 0.8 * np.count_nonzero(band), out
        err_db, err_deg = _errors(est, model, ok)
        assert np.abs(err_db).max() < tol_db, (out, np.abs(err_db).max())
        assert np.abs(err_deg).max() < tol_deg, (out, np.abs(err_deg).max())
        assert np.sqrt(np.mean(err_db ** 2)) < rms_db, (out, np.sqrt(np.mean(err_db ** 2)))
        assert np.sqrt(np.mean(err_deg ** 2)) < rms_deg, (out, np.sqrt(np.mean(err_deg ** 2)))


def test_pulse_bag_transient_estimate_matches_analytic_bode(
        pulse_bag: tuple[Path, float]) -> None:
    """Pulse 2-DOF bag, full-record (transient) estimate vs the analytic transfer function
    within 0.1 dB and 1 deg from 0 Hz to at least 3.5 Hz.

    The record (5 s) holds the whole response, so Y(f) = H(f) U(f) bin by bin; what is
    left is the tail cut off at the end (the yaw mode, Re(lambda) = -2.4 1/s, decays to
    e^(-2.4 * 4.1) = 5e-5 of its size after the pulse) and the 200 Hz sampling (relative
    (omega T)^2 / 12 = 1e-3, 0.01 dB, at 3.6 Hz): inside 0.1 dB / 1 deg. The excited band
    of a 0.4 s triangle (input power 20 dB down at ~3.7 Hz) decides the trusted band;
    coherence of one record without band averaging is 1 by construction and decides
    nothing. The 0 Hz point is the steady-state gain (the integrals of output and input).
    """
    path, speed = pulse_bag
    uni = B.resample(B.load_bag(path))
    model = linear.linear_system(vehicle_from_mapping(SET_1), "2dof", speed)
    for out in OUTPUTS_2DOF:
        est = F.estimate_response(uni.channels["front_wheel_angle_rad"], uni.channels[out],
                                  uni.dt_s, method="transient", output=out)
        ok = est.trusted()
        f = est.freq_hz[ok]
        assert f.min() == 0.0 and f.max() >= 3.5, (out, f.min(), f.max())
        assert np.all(ok[est.freq_hz <= 3.5]), out  # no hole in the band
        err_db, err_deg = _errors(est, model, ok)
        assert np.abs(err_db).max() < 0.1, (out, np.abs(err_db).max())
        assert np.abs(err_deg).max() < 1.0, (out, np.abs(err_deg).max())
        assert abs(est.response[0].real) == pytest.approx(abs(F.dc_gain(model, out)), rel=1e-3)


@pytest.mark.parametrize("driver_topic", [True, False], ids=["driver_input", "ratio_only"])
def test_response_per_steering_wheel_angle_is_road_wheel_response_over_ratio(
        tmp_path: Path, driver_topic: bool) -> None:
    """Per steering-wheel angle (``analyze_run``'s ``<output>/steering_wheel_angle_rad``):
    delta_sw = N delta_f, so H_sw = H_f / N: gain 20 log10 N dB lower, same phase.

    A pulse given as a hand-wheel angle (steer_input steering_wheel, N = 16.3), with the
    driver input recorded (hand-wheel angle from /fourws/driver_input) or not (hand-wheel
    angle = road-wheel angle times the ratio of the stored vehicle). The two estimates of
    the run differ by exactly -20 log10 N dB and 0 deg, each matches the analytic
    H_f / N within the pulse tolerance (0.1 dB, 1 deg), and the steady-state gain per
    steering-wheel angle is the analytic DC gain / N within 0.1 %.
    """
    from fourws_analysis.compare import analyze_run

    vehicle_map = {**SET_1, "steering": {"ratio": STEERING_RATIO}}
    maneuver = _shipped("pulse", steer_input="steering_wheel")
    maneuver["amplitude_rad"] *= STEERING_RATIO  # the same 3 deg at the road wheels
    speed = _maneuver_bag(tmp_path / "pulse_sw", maneuver, vehicle_map, driver_topic)
    res = analyze_run(B.resample(B.load_bag(tmp_path / "pulse_sw")), eig_sweep=False)
    model = linear.linear_system(vehicle_from_mapping(SET_1), "2dof", speed)
    ratio_db = 20.0 * math.log10(STEERING_RATIO)
    for out in OUTPUTS_2DOF:
        sw = res.frequency[f"{out}/steering_wheel_angle_rad"]
        rw = res.frequency[f"{out}/front_wheel_angle_rad"]
        ok = sw.trusted()
        np.testing.assert_array_equal(ok, rw.trusted())
        assert sw.freq_hz[ok].min() == 0.0 and sw.freq_hz[ok].max() >= 3.5, out
        np.testing.assert_allclose(sw.gain_db[ok] - rw.gain_db[ok], -ratio_db, atol=1e-9)
        np.testing.assert_allclose(sw.phase_deg[ok], rw.phase_deg[ok], atol=1e-9)
        err_db, err_deg = _errors(sw, model, ok, scale=1.0 / STEERING_RATIO)
        assert np.abs(err_db).max() < 0.1, (out, np.abs(err_db).max())
        assert np.abs(err_deg).max() < 1.0, (out, np.abs(err_deg).max())
        gain = res.frequency_metrics[f"{out}/steering_wheel_angle_rad"].steady_state_gain
        assert gain == pytest.approx(abs(F.dc_gain(model, out)) / STEERING_RATIO, rel=1e-3)


def test_analyze_recognizes_random_and_pulse_runs(random_bag: tuple[Path, float],
                                                  pulse_bag: tuple[Path, float],
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """``fourws analyze`` (``analyze_run`` behind it) picks the estimator from the stored
    maneuver type and reports frequency-response metrics for both runs:

    * pulse -> full-record estimate, whose trusted band starts at 0 Hz; its steady-state
      gain is the analytic DC gain within 0.1 % (see the pulse test for the error budget);
    * random_steer -> Welch, band from the first 10 s-segment bin, 0.1 Hz; its
      steady-state gain is the gain there, the analytic |H(0.1 Hz)| (+2.6, -3.2, -2.3 %
      from DC for yaw rate, a_y, sideslip) within the 3-sigma H1 error at that bin's
      coherence (n_d = 11).
    """
    from fourws_cli.main import main

    (random_path, speed), (pulse_path, pulse_speed) = random_bag, pulse_bag
    assert speed == pulse_speed
    rc = main(["analyze", str(random_path), str(pulse_path), "--json", "--no-sweep",
               "--quiet"])
    assert rc == 0
    runs = json.loads(capsys.readouterr().out)["runs"]
    model = linear.linear_system(vehicle_from_mapping(SET_1), "2dof", speed)
    pulse, random = runs["pulse"], runs["random_steer"]
    assert (pulse["maneuver"], random["maneuver"]) == ("pulse", "random_steer")
    uni = B.resample(B.load_bag(random_path))
    for out in OUTPUTS_2DOF:
        key = f"{out}/front_wheel_angle_rad"
        m = pulse["frequency_response"][key]
        assert m["trusted_band_hz"][0] == 0.0 and m["trusted_band_hz"][1] >= 3.5
        gain = m[U.gain_key(out, "front_wheel_angle_rad")]
        assert gain == pytest.approx(abs(F.dc_gain(model, out)), rel=1e-3)
        m = random["frequency_response"][key]
        assert m["trusted_band_hz"][0] == pytest.approx(0.1)
        assert m["trusted_band_hz"][1] >= 3.0
        est = F.estimate_response(uni.channels["front_wheel_angle_rad"], uni.channels[out],
                                  uni.dt_s, method="welch", output=out)
        low = est.trusted() & np.isclose(est.freq_hz, 0.1)
        tol = 3.0 * float(_welch_random_error(est.coherence[low][0], 11))
        ref = abs(F.model_response(model, out, np.array([0.1])).response[0])
        gain = m[U.gain_key(out, "front_wheel_angle_rad")]
        assert gain == pytest.approx(ref, rel=tol), (out, tol)


def test_single_period_sine_is_one_transient_matching_analytic_bode(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The ISO 7401 single-period sine (shipped ``sine``: 0.5 Hz, 1.5 deg, 85 km/h) is one
    transient from rest, so ``fourws analyze`` uses the full-record estimate: within 0.1 dB
    and 1 deg of the analytic 2-DOF response at every trusted point (the same error budget
    as the pulse: the record ends 3.5 s after the input, where the yaw mode has decayed to
    e^(-2.4 * 3.5) = 2e-4). One period of sin(w0 t) has the spectrum
    w0 (1 - e^(-i w T)) / (w0^2 - w^2), zero at 0 and at k f0 for k >= 2, so the trusted
    band must hold 0.5 Hz and leave out the 0 Hz and 1 Hz input zeros. The steady-state gain
    is then the gain of the first bin, 1/6 Hz (6 s record), within 0.1 dB of the analytic one
    there, and says so; the phase lag at 1 Hz is interpolated across the input zero, between
    the 5/6 and 7/6 Hz bins, within 4 deg of the analytic lag (the phase curves by about
    3 deg over that gap)."""
    from fourws_cli.main import main

    path = tmp_path / "sine"
    speed = _maneuver_bag(path, _shipped("sine"))
    rc = main(["analyze", str(path), "--json", "--no-sweep", "--quiet"])
    assert rc == 0
    run = json.loads(capsys.readouterr().out)["runs"]["sine"]
    assert run["maneuver"] == "sine"
    model = linear.linear_system(vehicle_from_mapping(SET_1), "2dof", speed)
    uni = B.resample(B.load_bag(path))
    for out in OUTPUTS_2DOF:
        met = run["frequency_response"][f"{out}/front_wheel_angle_rad"]
        band = met["trusted_band_hz"]
        assert band[0] <= 0.5 <= band[1], (out, band)
        low = F.model_response(model, out, np.array([band[0]]))
        assert band[0] == pytest.approx(1.0 / 6.0)
        gain = met[U.gain_key(out, "front_wheel_angle_rad")]
        assert gain == pytest.approx(low.gain[0], rel=0.012), out
        assert any("steady-state gain taken at" in n for n in met["notes"]), met["notes"]
        lag = -F.model_response(model, out, np.array([1.0])).phase_deg[0]
        assert met["phase_lag_1hz_deg"] == pytest.approx(lag, abs=4.0), out
        est = F.estimate_response(uni.channels["front_wheel_angle_rad"], uni.channels[out],
                                  uni.dt_s, method="transient", output=out)
        ok = est.trusted()
        assert not ok[est.freq_hz == 0.0].any() and not ok[np.isclose(est.freq_hz, 1.0)].any()
        assert ok[np.isclose(est.freq_hz, 0.5)].all(), out
        err_db, err_deg = _errors(est, model, ok)
        assert np.abs(err_db).max() < 0.1, (out, np.abs(err_db).max())
        assert np.abs(err_deg).max() < 1.0, (out, np.abs(err_deg).max())
