# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws validate``: tolerance bands around a reference.

Sources: a run against itself lies on its reference (band distance 0, every curve 100 %
inside); the 3-DOF's steady-state yaw-rate gain from its state matrices
(:func:`fourws_analysis.frequency.dc_gain` of :func:`fourws_analysis.linear.linear_system`),
which a front cornering stiffness 20 % low lowers by far more than the 5 % band; the band
numbers of a synthetic steady-state log computed by hand in the test from the band's
definition (module docstring of :mod:`fourws_analysis.validate`); the FMVSS 126 metrics of
:mod:`fourws_analysis.fmvss126` (tested against the regulation in test_fmvss126).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fourws_analysis import bag as B
from fourws_analysis import fmvss126
from fourws_analysis.frequency import dc_gain
from fourws_analysis.linear import linear_system
from fourws_analysis.measured import TIME_COLUMN, load_log
from fourws_analysis.validate import CROSS_PLOTS, validate
from fourws_cli.main import main
from fourws_run.closed_loop import run_closed_loop
from fourws_sim.params import load_vehicle, vehicle_from_mapping

GAIN_BAND = next(p.band for p in CROSS_PLOTS if p.key == "yaw_rate_gain")
SWA_BAND = next(p.band for p in CROSS_PLOTS if p.key == "steering_wheel_angle")


def _soft_front() -> object:
    mapping = load_vehicle("table_8_1").to_dict()
    mapping["axle_tires"]["cornering_stiffness_front_n_per_rad"] *= 0.8
    return vehicle_from_mapping(mapping, "front cornering stiffness -20 %")


def _bag(vehicle, maneuver, path: Path) -> Path:
    """The twin's 3-DOF run (RK4 at the 10 ms control period) written as a bag."""
    res = run_closed_loop(vehicle, maneuver, "fws", model="3dof", dt_s=0.01)
    B.write_run(path, res.time_s, res.outputs, res.config, driver=res.driver, model="3dof")
    return path


@pytest.fixture(scope="module")
def ramps(tmp_path_factory) -> tuple[Path, Path]:
    """The shipped ISO 4138 slow ramp steer (5 deg/s hand wheel, 85 km/h) on the 3-DOF
    table_8_1 and on its copy with C_f 20 % low."""
    root = tmp_path_factory.mktemp("val")
    return (_bag(load_vehicle("table_8_1"), "slow_ramp_steer", root / "base"),
            _bag(_soft_front(), "slow_ramp_steer", root / "soft"))


def test_run_against_itself_passes(ramps, tmp_path, capsys) -> None:
    """The ISO 19364 cross-plots of a run against itself: 100 % of every curve in its band,
    exit code 0; the report and validation.json say so."""
    base, _ = ramps
    assert main(["validate", str(base), str(base), "--report", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "iso19364, PASSED" in out
    data = json.loads((tmp_path / "r" / "validation.json").read_text())
    assert data["standard"] == "iso19364" and data["passed"] is True
    assert set(data["curves"]) == {"steering_wheel_angle", "sideslip", "roll", "yaw_rate_gain"}
    for curve in data["curves"].values():
        assert curve["share_inside"] == 1.0
        assert max(curve["simulation"]["distance"]) == 0.0
        assert len(curve["reference"]["x"]) >= 8
    html = (tmp_path / "r" / "index.html").read_text()
    assert "curves.png" in html and "Riedmaier" in html


def test_front_stiffness_20_percent_low_fails_the_gain(ramps, capsys) -> None:
    """C_f 20 % low: the yaw-rate gain curve leaves its band everywhere and fails, so does the
    validation (exit code 1). The 3-DOF steady-state gains of the two cars differ by half
    (the band allows 5 %); the soft (understeering, fast) car's curve reaches its steady gain
    within 3 % at the top of the ramp, the base car's stays below its own (the ramp's lag
    behind the slow mode of this near-critical roll-oversteer car lowers a quasi-steady
    gain: the hand wheel leads)."""
    base, soft = ramps
    result = validate(load_log(soft), load_log(base))
    gain = next(c for c in result.curves if c.key == "yaw_rate_gain")
    assert not gain.passed and gain.share_inside == 0.0
    assert not result.passed
    speed = 23.611111111111111
    ratio = load_vehicle("table_8_1").steering.ratio
    steady = {name: dc_gain(linear_system(v, "3dof", speed), "yaw_rate_radps") / ratio
              for name, v in (("base", load_vehicle("table_8_1")), ("soft", _soft_front()))}
    assert gain.y[-1] == pytest.approx(steady["soft"], rel=0.03)
    assert gain.reference_y[-1] < steady["base"]
    assert steady["soft"] / steady["base"] < 0.55
    assert main(["validate", str(soft), str(base)]) == 1
    out = capsys.readouterr().out
    assert "FAILED" in out and "yaw-rate gain r/δH: 0.0 % inside" in out
    # a band of 0.4 1/s holds the soft car's gain (at most 0.35 1/s off, the numbers above)
    assert main(["validate", str(soft), str(base), "--json",
                 "--band", "yaw_rate_gain=0.1,0.06,0.4,0"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["curves"]["yaw_rate_gain"]["share_inside"] == 1.0
    assert data["curves"]["yaw_rate_gain"]["band"]["y_offset"] == 0.4
    assert main(["validate", str(soft), str(base), "--band", "yaw_gain=1,1,1,1"]) == 2
    assert "unknown curve 'yaw_gain'" in capsys.readouterr().err


def _plateaus(path: Path, gains: tuple[float, ...]) -> Path:
    """A synthetic steady-state log: 4-s plateaus of a_y = 1.6, 2.6, 3.6 m/s^2 (bins 6, 10,
    14 of 0.25 m/s^2) at U = 36/pi m/s, hand wheel 10 deg per m/s^2, yaw rate
    gain * hand wheel, so that a_y = U r where the gain is 0.5 1/s."""
    dt, hold = 0.01, 400
    ay_levels = (1.6, 2.6, 3.6)
    speed = 36.0 / math.pi  # U r = a_y at a gain of 0.5 1/s: U = 1 / (0.5 * 10 * pi / 180)
    ay = np.repeat(ay_levels, hold)
    swa = np.radians(10.0 * ay)
    yaw = np.repeat(gains, hold) * swa
    t = dt * np.arange(ay.size)
    cols = {TIME_COLUMN: t, "steering_wheel_angle_rad": swa,
            "speed_mps": np.full(t.size, speed), "yaw_rate_radps": yaw,
            "lateral_accel_mps2": ay}
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(",".join(cols) + "\n")
        for row in zip(*cols.values()):
            fh.write(",".join(repr(float(v)) for v in row) + "\n")
    return path


def test_band_numbers_equal_a_hand_computation(tmp_path, capsys) -> None:
    """Reference: yaw-rate gain 0.5 1/s on three plateaus, the simulation's 0.52, 0.54, 0.56.
    By hand: eps_y = 0.02 + 0.05 * 0.5 = 0.045 1/s on the horizontal reference, so the
    distances are 0.02, 0.04, 0.06 over 0.045 (the nearest point is straight below), 2 of 3
    inside; the edges are y +- 0.045 at the points, eps_x = 0.1 + 0.06 |a_y|. The hand-wheel
    curve is the line 10 a_y deg in both: distance 0; its middle point's edge by the
    formula, D = sqrt((dx eps_y)^2 + (dy eps_x)^2) with (dx, dy) = (1, 10)."""
    ref = _plateaus(tmp_path / "ref.csv", (0.5, 0.5, 0.5))
    sim = _plateaus(tmp_path / "sim.csv", (0.52, 0.54, 0.56))
    assert main(["validate", str(sim), str(ref), "--standard", "iso19364", "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    gain = data["curves"]["yaw_rate_gain"]
    x = [1.6, 2.6, 3.6]
    np.testing.assert_allclose(gain["reference"]["x"], x, rtol=1e-12)
    np.testing.assert_allclose(gain["reference"]["y"], [0.5] * 3, rtol=1e-12)
    np.testing.assert_allclose(gain["simulation"]["y"], [0.52, 0.54, 0.56], rtol=1e-12)
    eps_y = 0.02 + 0.05 * 0.5
    np.testing.assert_allclose(gain["reference"]["eps_y"], [eps_y] * 3, rtol=1e-12)
    np.testing.assert_allclose(gain["reference"]["eps_x"], [0.1 + 0.06 * v for v in x],
                               rtol=1e-12)
    np.testing.assert_allclose(gain["reference"]["upper_y"], [0.5 + eps_y] * 3, rtol=1e-12)
    np.testing.assert_allclose(gain["reference"]["lower_y"], [0.5 - eps_y] * 3, rtol=1e-12)
    np.testing.assert_allclose(gain["reference"]["upper_x"], x, rtol=1e-12)
    np.testing.assert_allclose(gain["simulation"]["distance"],
                               [0.02 / eps_y, 0.04 / eps_y, 0.06 / eps_y], rtol=1e-9)
    assert gain["simulation"]["inside"] == [True, True, False]
    assert gain["share_inside"] == pytest.approx(2.0 / 3.0) and gain["passed"] is False
    assert gain["band"] == {**GAIN_BAND.to_dict()}
    swa = data["curves"]["steering_wheel_angle"]
    assert swa["share_inside"] == 1.0 and max(swa["simulation"]["distance"]) == 0.0
    xm, ym = 2.6, 26.0
    ex, ey = 0.1 + 0.06 * xm, 5.0 + 0.03 * ym
    d = math.hypot(1.0 * ey, 10.0 * ex)
    assert swa["reference"]["upper_x"][1] == pytest.approx(xm - 10.0 * ex ** 2 / d, rel=1e-9)
    assert swa["reference"]["upper_y"][1] == pytest.approx(ym + 1.0 * ey ** 2 / d, rel=1e-9)
    assert swa["reference"]["lower_y"][1] == pytest.approx(ym - 1.0 * ey ** 2 / d, rel=1e-9)
    assert set(data["skipped"]) == {"sideslip", "roll"}


def test_sine_with_dwell_against_itself(tmp_path) -> None:
    """A sine with dwell (FMVSS 126, 2.5x a 20 deg A) against itself: ISO 19365 style by its
    maneuver, three time histories 100 % inside, the metrics side by side equal those of
    fourws_analysis.fmvss126 on the same arrays, differences 0."""
    man = {"type": "sine_with_dwell", "name": "swd", "initial_speed_mps": 22.2,
           "duration_s": 5.0, "steer_input": "steering_wheel", "amplitude_rad": 0.87,
           "start_s": 1.0, "frequency_hz": 0.7, "dwell_s": 0.5, "direction": "left"}
    path = _bag(load_vehicle("table_8_1"), man, tmp_path / "swd")
    log = load_log(path)
    result = validate(log, log)
    assert result.standard == "iso19365" and result.passed
    assert [c.key for c in result.curves] == ["steering_wheel_angle_rad", "yaw_rate_radps",
                                              "lateral_accel_mps2"]
    assert all(c.share_inside == 1.0 for c in result.curves)
    own = fmvss126.sine_with_dwell_metrics(
        log.time_s, log.channels["steering_wheel_angle_rad"], log.channels["yaw_rate_radps"],
        log.channels["lateral_accel_mps2"], zero_before_s=log.time_s[0] + 1.0).to_dict()
    for m in result.metrics:
        assert m.simulation == m.reference == own[m.key]
        assert m.passed
