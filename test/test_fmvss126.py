"""FMVSS No. 126 (UN R13-H, UN GTR 8): the sine-with-dwell and slowly-increasing-steer
maneuvers, A, the amplitude series, the regulation's metrics and a run series.

Sources of the numbers: the regulation's definitions (S5.2, S7.6, S7.9, S7.11) evaluated by
hand on synthetic signals whose timing points and integrals have closed forms, and a run
series of the 8-DOF on a wet road.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from fourws_analysis import fmvss126
from fourws_cli.cmd_run import _run_name
from fourws_run.scenario import load_scenario, scenario_from_mapping
from fourws_run.series import REGULATION, run_series, scenario_runs
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers import load_maneuver_spec, make_maneuver
from fourws_sim.maneuvers.esc import (REFERENCE_LATERAL_ACCEL_MPS2, reference_amplitude_rad,
                                      series_factors)
from fourws_sim.params import load_vehicle

DT = 0.001  # s, a fine grid: interpolation errors of the timing points are O(dt^2)
F = 0.7  # Hz
DWELL = 0.5  # s
START = 1.0  # s
DEG = math.radians(1.0)


def swd_angle(t: np.ndarray, amplitude_rad: float, start_s: float = START) -> np.ndarray:
    """The regulation's steering-wheel angle of a sine with dwell (S7.9), written out."""
    tau = t - start_s
    out = amplitude_rad * np.sin(2 * np.pi * F * tau)
    dwell = (tau >= 0.75 / F) & (tau < 0.75 / F + DWELL)
    out[dwell] = -amplitude_rad
    late = tau >= 0.75 / F + DWELL
    out[late] = amplitude_rad * np.sin(2 * np.pi * F * (tau[late] - DWELL))
    out[(tau < 0.0) | (tau > 1.0 / F + DWELL)] = 0.0
    return out


# ------------------------------------------------------------------------ the maneuvers
def test_sine_with_dwell_waveform_and_coasting() -> None:
    """The maneuver steers the regulation's waveform: +A at 1/(4f), -A from 3/(4f) through the
    500 ms dwell, back to 0 at 1/f + dwell (1.93 s after the start); its road-wheel angle is
    the steering-wheel angle over the ratio; from the start of the steer no drive torque."""
    spec = load_maneuver_spec("sine_with_dwell")
    spec = dataclasses.replace(spec, params=dataclasses.replace(
        spec.params, amplitude_rad=100 * DEG, reference_amplitude_rad=20 * DEG))
    vehicle = load_vehicle("table_8_1")
    man = make_maneuver(spec, vehicle)
    still = {"speed_mps": 20.0}
    t = np.array([0.5, START + 0.25 / F, START + 0.75 / F + 1e-6, START + 0.75 / F + 0.49,
                  START + 1.0 / F + DWELL + 1e-6, 4.0])
    cmds = [man.command(float(x), still) for x in t]
    hand = np.array([c.steering_wheel_angle_rad for c in cmds])
    np.testing.assert_allclose(hand, [0.0, 100 * DEG, -100 * DEG, -100 * DEG, 0.0, 0.0],
                               atol=1e-9)
    ratio = vehicle.steering.ratio
    np.testing.assert_allclose([c.front_wheel_angle_rad for c in cmds], hand / ratio,
                               atol=1e-15)
    assert sum(cmds[0].drive_torque_nm) > 0.0  # holding 80 km/h before the steer
    assert all(sum(c.drive_torque_nm) == 0.0 == sum(c.brake_torque_nm) for c in cmds[1:])
    assert [man.phase(float(x)) for x in t] == ["settle", "sine", "dwell", "dwell", "coast",
                                                 "coast"]


def test_unresolved_sine_with_dwell_cannot_run_and_steer_input_is_fixed() -> None:
    """A multiple of an A not yet found is refused (A depends on the law); the type's angles
    are steering-wheel angles and a road-wheel input is refused."""
    with pytest.raises(ParameterError, match="amplitude_factor"):
        make_maneuver("sine_with_dwell", load_vehicle("table_8_1"))
    data = load_maneuver_spec("sine_with_dwell").to_dict()
    data["steer_input"] = "road_wheel"
    with pytest.raises(ParameterError) as err:
        load_maneuver_spec(data)
    assert err.value.field == "steer_input"


def test_amplitude_series_follows_s7_9_4() -> None:
    """1.5 A in steps of 0.5 A to the larger of 6.5 A and 270 deg, at most 300 deg."""
    a = 20 * DEG  # 6.5 A = 130 deg < 270: steps to 260 deg, then 270
    f = series_factors(a)
    assert f[:3] == [1.5, 2.0, 2.5] and f[-2] == 13.0
    assert f[-1] * a == pytest.approx(270 * DEG)
    assert len(f) == 25
    a = 45 * DEG  # 6.5 A = 292.5 deg: the final run
    assert [round(x * 45, 6) for x in series_factors(a)][-3:] == [247.5, 270.0, 292.5]
    a = 50 * DEG  # 6.5 A = 325 deg > 300: ends at 300 deg (6 A)
    assert [round(x * 50, 6) for x in series_factors(a)] == [
        75.0, 100.0, 125.0, 150.0, 175.0, 200.0, 225.0, 250.0, 275.0, 300.0]
    assert [round(x * 250, 6) for x in series_factors(250 * DEG)] == [300.0]


def test_reference_amplitude_is_the_regression_at_0_3_g() -> None:
    """A steady-state line a_y = c (delta_H - d0) ramped at 13.5 deg/s: the regression gives
    delta_H(0.3 g) = d0 + 0.3 g / c, signed by the direction. (c = 0.1 m/s^2 per deg puts the
    regression's first sample, 0.1 g, 0.7 s after the kinks of the ramp, where the 6 Hz
    filter's transient has decayed to e^-6.8 of its size: 1e-5 of A.)"""
    t = np.arange(0.0, 12.0, 0.01)
    swa = np.where(t > 1.0, math.radians(13.5) * (t - 1.0), 0.0)
    c, d0 = 0.1 / DEG, 2.0 * DEG  # 0.1 m/s^2 per deg beyond 2 deg
    ay = np.maximum(c * (swa - d0), 0.0)
    got = reference_amplitude_rad(t, swa, ay, start_s=1.0)
    assert got == pytest.approx(d0 + REFERENCE_LATERAL_ACCEL_MPS2 / c, rel=2e-5)
    assert reference_amplitude_rad(t, -swa, -ay, start_s=1.0) == pytest.approx(-got, rel=1e-12)


# ------------------------------------------------------------------------ the metrics
def test_timing_points_are_the_hand_computed_ones() -> None:
    """BOS: the angle reaches 5 deg, t = t0 + asin(5/A_s) / (2 pi f); COS: back to zero after
    the dwell, t = t0 + 1/f + dwell; the reversal at t0 + 1/(2f). Exact signal (COS within
    the sample period: the sampled angle is exactly 0 from the first sample after the steer,
    where the interpolation ends). After the regulation's 10 Hz phaseless filter the timing
    points move by the filter's response to the waveform's corners: it rounds the start of the
    sine (the 5-deg crossing comes 1.0 ms earlier) and rings after its end (the filtered angle
    is -2.2 deg at the ideal COS and crosses zero 14.3 ms later): BOS within 2 ms, COS within
    20 ms, both always after the ideal ones' filtered corner."""
    t = np.arange(0.0, 6.0, DT)
    amp = 100 * DEG
    swa = swd_angle(t, amp)
    bos = START + math.asin(5.0 / 100.0) / (2 * math.pi * F)
    cos_ = START + 1.0 / F + DWELL
    got_bos, got_cos, direction, rev = fmvss126.timing_points(t, swa)
    assert got_bos == pytest.approx(bos, abs=1e-6)
    assert got_cos == pytest.approx(cos_, abs=DT)
    assert rev == pytest.approx(START + 0.5 / F, abs=1e-6) and direction == 1.0
    m = fmvss126.sine_with_dwell_metrics(t, swa, np.zeros_like(t) + 1e-3 * swa,
                                         np.zeros_like(t), zero_before_s=START)
    assert m.bos_s == pytest.approx(bos, abs=2e-3)
    assert cos_ < m.cos_s < cos_ + 0.020
    right = fmvss126.timing_points(t, -swa)
    assert right[2] == -1.0 and right[0] == pytest.approx(bos, abs=1e-6)


def test_displacement_is_the_double_integral_from_bos() -> None:
    """a_y = a0 + k (t - BOS) from 0.9 s before BOS: the regulation's displacement at
    BOS + 1.07 s is a0 1.07^2 / 2 + k 1.07^3 / 6 (velocity and displacement zero at BOS).
    With a0 = 3.2 m/s^2, k = 0 that is 1.8318 m: just above the 1.83 m limit. (The sine starts
    at 2.5 s and the record is zeroed before 0.6 s: the phaseless 6 Hz filter smears the step
    of a_y both ways, and its ringing has decayed to e^-9 one second from the step.)"""
    start = 2.5
    t = np.arange(0.0, 8.0, DT)
    swa = swd_angle(t, 100 * DEG, start_s=start)
    bos = start + math.asin(0.05) / (2 * math.pi * F)
    tau = fmvss126.DISPLACEMENT_TIME_S
    for a0, k in ((3.2, 0.0), (2.0, 1.5)):
        ay = np.where(t >= bos - 0.9, a0 + k * (t - bos), 0.0)
        m = fmvss126.sine_with_dwell_metrics(t, swa, 1e-3 * swa, ay, zero_before_s=0.6,
                                             amplitude_factor=5.0)
        # BOS of the filtered angle is 1 ms before the ideal one: k shifts a_y there
        a_bos = a0 + k * (m.bos_s - bos)
        assert m.lateral_displacement_m == pytest.approx(a_bos * tau ** 2 / 2 + k * tau ** 3 / 6,
                                                         rel=1e-4)
        assert m.displacement_applies
    m32 = fmvss126.sine_with_dwell_metrics(
        t, swa, 1e-3 * swa, np.where(t >= bos - 0.9, 3.2, 0.0), zero_before_s=0.6,
        amplitude_factor=5.0)
    assert m32.lateral_displacement_m == pytest.approx(1.8318, abs=2e-4)
    assert m32.displacement_pass is True
    not_applied = fmvss126.sine_with_dwell_metrics(
        t, swa, 1e-3 * swa, np.where(t >= bos - 0.9, 3.2, 0.0), zero_before_s=0.6,
        amplitude_factor=4.5)
    assert not not_applied.displacement_applies and not_applied.displacement_pass is None


def test_yaw_rate_ratios_of_a_hand_computed_yaw_rate() -> None:
    """A smooth yaw rate: a first lobe, then the second peak -R at t_p (an alpha function
    (x/T) e^(1 - x/T) of x = t - t_p + T), decaying: the second peak and the ratios at
    COS + 1.00 s and COS + 1.75 s are its closed-form values (to 0.1 %; evaluated at the COS
    of the filtered angle, 14 ms after the ideal one, see above). By hand at the ideal COS
    (2.9286 s): T = 0.6 s, t_p = 2.2 s gives 0.218 and 0.082 (passes 0.35/0.20); T = 0.9 s,
    t_p = 2.8 s gives 0.643 and 0.383 (fails both)."""
    t = np.arange(0.0, 6.0, DT)
    swa = swd_angle(t, 100 * DEG)
    r_peak = 0.5
    first = 0.3 * np.sin(np.clip(np.pi * (t - START) / (0.5 / F), 0, np.pi))
    for t_p, tau, by_hand, passes in ((START + 1.2, 0.6, (0.2176, 0.0822), True),
                                      (START + 1.8, 0.9, (0.6433, 0.3833), False)):
        def alpha(x: np.ndarray, tau: float = tau) -> np.ndarray:  # peak 1 at x = tau
            x = np.maximum(x, 0.0)
            return (x / tau) * np.exp(1.0 - x / tau)
        yaw = first - r_peak * alpha(t - (t_p - tau))
        m = fmvss126.sine_with_dwell_metrics(t, swa, yaw, np.zeros_like(t),
                                             zero_before_s=START)
        assert m.peak_yaw_rate_radps == pytest.approx(-r_peak, rel=5e-4)
        assert m.peak_time_s == pytest.approx(t_p, abs=2 * DT)
        for at, ratio, hand in zip(fmvss126.YAW_RATIO_TIMES_S, m.yaw_ratios, by_hand):
            exact = float(alpha(np.array([m.cos_s + at - (t_p - tau)]))[0])
            assert ratio == pytest.approx(exact, rel=1e-3)
            assert ratio == pytest.approx(hand, rel=0.05)  # the 14 ms of COS
        assert m.yaw_ratio_pass == (passes, passes) and m.passed is passes


def test_law_verdicts_fail_a_law_with_one_failing_run() -> None:
    t = np.arange(0.0, 6.0, DT)
    swa = swd_angle(t, 100 * DEG)
    ok = fmvss126.sine_with_dwell_metrics(t, swa, 1e-3 * swa, np.zeros_like(t),
                                          zero_before_s=START)
    bad = dataclasses.replace(ok, yaw_ratio_pass=(True, False))
    verdicts = fmvss126.law_verdicts([("a", "a1", ok), ("b", "b1", ok), ("b", "b2", bad)])
    assert [(v.law, v.runs, v.failed, v.passed) for v in verdicts] == [
        ("a", 1, (), True), ("b", 2, ("b2",), False)]


# ------------------------------------------------------------------------ the series
def test_scenario_series_validation_and_run_names() -> None:
    """``series: regulation`` only for a type that has one; a list merges fields into the
    maneuver; series members of ``fourws run`` are named after them."""
    with pytest.raises(ParameterError) as err:
        scenario_from_mapping({"vehicle": "table_8_1", "maneuver": "step_steer_85kmh",
                               "series": REGULATION})
    assert err.value.field == "series"
    sc = scenario_from_mapping({"vehicle": "table_8_1", "maneuver": "step_steer_85kmh",
                                "series": [{"amplitude_rad": 0.01}, {"amplitude_rad": 0.02,
                                                                     "name": "big"}]})
    runs = scenario_runs(sc, "fws")
    assert [(m.name, m.params.amplitude_rad) for m in runs] == [
        ("step_steer_85kmh_1", 0.01), ("big", 0.02)]
    assert scenario_from_mapping(sc.to_dict()).series == sc.series
    with pytest.raises(ParameterError) as err:
        scenario_from_mapping({"vehicle": "table_8_1", "maneuver": "step_steer_85kmh",
                               "series": [{"amplitude_rad": "x"}]})
    assert err.value.field == "amplitude_rad"
    assert _run_name("x", "s", "fws", runs[1], True) == "x-fws-big"
    assert _run_name(None, "s", "fws", runs[1], False).startswith("s-fws-big-")


def test_shipped_scenario_runs_the_regulation_series_per_law() -> None:
    """``fmvss126_sine_with_dwell``: per law the slowly increasing steer left and right, then
    the sine with dwell from 1.5 A left, ..., the last right at 270 deg (A of table_8_1 with
    fws, 14.0 deg from the regression: 1.5 A = 21 deg, 37 runs per direction)."""
    sc = load_scenario("fmvss126_sine_with_dwell")
    runs = scenario_runs(sc, "fws")
    assert [m.type for m in runs[:2]] == ["slowly_increasing_steer"] * 2
    swd = runs[2:]
    a = swd[0].params.reference_amplitude_rad
    assert math.degrees(a) == pytest.approx(14.0, abs=0.05)
    assert len(swd) == 2 * len(series_factors(a))
    assert swd[0].params.amplitude_rad == pytest.approx(1.5 * a)
    assert swd[-1].params.direction == "right"
    assert swd[-1].params.amplitude_rad == pytest.approx(math.radians(270.0))
    assert all(m.params.reference_law == "fws" for m in swd)


def test_wet_road_series_fws_fails_the_yaw_ratio_and_rwc1_passes() -> None:
    """On a road of friction 0.5 the fws car (table_8_1: roll oversteer) keeps yawing after
    the steer: runs of its series fail the lateral-stability criterion (the first at 1.5 A
    already, ratio 0.59 > 0.35 at COS + 1.00 s); with the 3-DOF zero-sideslip feed-forward
    (rwc1_3dof, the paper's RWC 1 of ch. 8) every run of the whole series, both directions,
    meets both yaw-rate ratios. Which laws pass was found on this car: sol1, sol2, rwc4_3dof
    and lqr fail on this road too (their rear steer in phase with the front at large
    amplitudes, or saturating), rwc2_3dof misses one run by 10 %. The responsiveness
    criterion is not part of this test: 1.83 m in 1.07 s needs about 0.35 g more than a 0.5
    road gives (every law reaches 1.6 m here); the regulation tests on a dry surface."""
    sc = dataclasses.replace(load_scenario("fmvss126_sine_with_dwell"),
                             road_friction_coefficient=0.5, laws=("fws", "rwc1_3dof"))
    verdicts = {}
    for law in sc.laws:
        members = [m for m in scenario_runs(sc, law) if m.type == "sine_with_dwell"]
        if law == "fws":
            members = members[:2]  # its failure shows at once
        results = []
        for m, res in zip(members, run_series(sc, law, members)):
            assert res.end_reason == "duration"
            met = fmvss126.sine_with_dwell_metrics(
                res.time_s, res["steering_wheel_angle_rad"], res["yaw_rate_radps"],
                res["lateral_accel_mps2"], zero_before_s=m.params.start_s,
                amplitude_factor=m.params.amplitude_factor)
            results.append((law, m.name, met))
        verdicts[law] = results
    fws_first = verdicts["fws"][0][2]
    assert fws_first.yaw_ratios[0] > 0.35 and not all(fws_first.yaw_ratio_pass)
    rwc1 = [met for _, _, met in verdicts["rwc1_3dof"]]
    assert len(rwc1) == 26  # A = 38.4 deg: 13 amplitudes each way
    assert all(all(met.yaw_ratio_pass) for met in rwc1)
    assert max(met.yaw_ratios[0] for met in rwc1) < 0.35


def test_yaw_displacement_of_the_regulation_matches_the_track() -> None:
    """The regulation's displacement (lateral acceleration integrated twice in the body
    frame) approximates the CG's distance from its straight path: within 3 % on a 5 A run of
    table_8_1 with rwc1_3dof (the heading turns by a few degrees in 1.07 s)."""
    sc = load_scenario("fmvss126_sine_with_dwell")
    members = [m for m in scenario_runs(sc, "rwc1_3dof") if m.type == "sine_with_dwell"]
    five = [m for m in members if m.params.amplitude_factor == 5.0][0]
    res = run_series(sc, "rwc1_3dof", [five])[0]
    m = fmvss126.sine_with_dwell_metrics(
        res.time_s, res["steering_wheel_angle_rad"], res["yaw_rate_radps"],
        res["lateral_accel_mps2"], zero_before_s=five.params.start_s, amplitude_factor=5.0,
        x_m=res["x_m"], y_m=res["y_m"], heading_rad=res["heading_rad"],
        vehicle_mass_kg=load_vehicle("table_8_1").chassis.mass_kg)
    assert m.lateral_displacement_m == pytest.approx(m.path_displacement_m, rel=0.03)
    assert m.displacement_applies and m.displacement_pass and m.passed
