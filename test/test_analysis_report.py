"""`fourws analyze` end to end: report, metrics.json, bad input (fourws_analysis/report.py,
compare.py, fourws_cli/cmd_analyze.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fourws_analysis import bag as B
from fourws_cli.main import main
from fourws_sim.params import vehicle_from_mapping

from test_analysis_frequency import SET_1, simulate_2dof

SPEED = 20.0


def _config(maneuver: str) -> dict:
    return {"vehicle": SET_1, "maneuver": {"type": maneuver}, "law": "fws", "model": "2dof",
            "clock_mode": "lockstep", "speed_mps": SPEED}


def _step_bag(path: Path, maneuver: str = "step_steer") -> None:
    vehicle = vehicle_from_mapping(SET_1)
    dt = 2e-3
    t = np.arange(0.0, 6.0, dt)
    delta = np.where(t >= 1.0, math.radians(2.0), 0.0)
    B.write_run(path, t, simulate_2dof(vehicle, SPEED, t, delta), _config(maneuver),
                model="2dof")


def test_report_and_metrics_of_a_step_run(tmp_path: Path, capsys) -> None:
    """A step bag: index.html, PNGs and metrics.json written; the JSON's steady-state yaw
    gain equals the 2-DOF analytic U/(L + K_us U^2) within 0.1 %, the identified eigenvalues
    match the model's, and the frequency response is reported as unavailable with its reason."""
    _step_bag(tmp_path / "step")
    rc = main(["analyze", str(tmp_path / "step"), "--report", str(tmp_path / "rep"),
               "--quiet"])
    assert rc == 0
    assert (tmp_path / "rep" / "index.html").is_file()
    for png in ("time_histories_step_steer.png", "step.png", "eigenvalues.png"):
        assert (tmp_path / "rep" / png).stat().st_size > 10_000
    html = (tmp_path / "rep" / "index.html").read_text()
    assert "step.png" in html and "TB factor" in html
    metrics = json.loads((tmp_path / "rep" / "metrics.json").read_text())["runs"]["step"]
    vehicle = vehicle_from_mapping(SET_1)
    L = vehicle.chassis.wheelbase_m
    expected = SPEED / (L + vehicle.understeer_gradient_rad_per_mps2 * SPEED ** 2)
    yaw = metrics["iso7401_step"]["yaw_rate_radps"]
    gain = yaw["steady_state_gain_radps_per_rad_road_wheel"]
    assert gain == pytest.approx(expected, rel=1e-3)
    for pair in metrics["identified_vs_model"]["2dof"]:
        assert pair["relative_difference"] < 0.01
    assert "excitation band" in metrics["unavailable"]["frequency_response"]


def test_json_output_and_partial_results_with_a_missing_bag(tmp_path: Path, capsys) -> None:
    """One good and one missing bag: metrics of the good one printed, the missing one named
    on stderr, exit code 1 (partial), no traceback."""
    _step_bag(tmp_path / "step")
    rc = main(["analyze", str(tmp_path / "step"), str(tmp_path / "missing"), "--json",
               "--quiet"])
    out, err = capsys.readouterr()
    assert rc == 1
    data = json.loads(out)
    assert data["runs"]["step"]["iso7401_step"]["yaw_rate_radps"]["overshoot_fraction"] > 0.0
    assert "missing" in err and "does not exist" in err and "Traceback" not in err


def test_corrupt_bag_is_a_clear_error(tmp_path: Path, capsys) -> None:
    """Only a corrupt bag: exit code 2, one line naming the bag, no traceback."""
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 300)
    rc = main(["analyze", str(junk), "--quiet"])
    _, err = capsys.readouterr()
    assert rc == 2
    assert "junk.mcap" in err and "truncated or corrupt" in err and "Traceback" not in err


def test_bag_without_state_topic(tmp_path: Path, capsys) -> None:
    """A bag with only the run config: the missing /fourws/state is named."""
    with B.BagWriter(tmp_path / "empty") as bag:
        bag.write_run_config(_config("step_steer"))
    rc = main(["analyze", str(tmp_path / "empty"), "--quiet"])
    _, err = capsys.readouterr()
    assert rc == 2 and "/fourws/state" in err


def test_step_run_asked_for_frequency_metrics_gives_reason(tmp_path: Path) -> None:
    """A step run labelled swept_sine (wrong maneuver for its data) still gives a frequency
    response -- a step does excite a band -- while a constant-steer run gives none and says
    the input is constant."""
    from fourws_analysis.compare import analyze_run

    vehicle = vehicle_from_mapping(SET_1)
    t = np.arange(0.0, 10.0, 5e-3)
    delta = np.full(t.size, math.radians(1.0))
    B.write_run(tmp_path / "const", t, simulate_2dof(vehicle, SPEED, t, delta),
                _config("swept_sine"), model="2dof")
    res = analyze_run(B.resample(B.load_bag(tmp_path / "const")), eig_sweep=False)
    assert not res.frequency
    why = res.unavailable["frequency_response/yaw_rate_radps/front_wheel_angle_rad"]
    assert "constant (no excitation band)" in why
    # the linear-model overlays still exist: DC yaw gain U/(L + K_us U^2)
    L = vehicle.chassis.wheelbase_m
    assert res.models["2dof"].dc_gain("yaw_rate_radps") == pytest.approx(
        SPEED / (L + vehicle.understeer_gradient_rad_per_mps2 * SPEED ** 2), rel=1e-9)


def test_run_without_vehicle_still_gives_data_metrics(tmp_path: Path) -> None:
    """No vehicle in the config: the step metrics are computed, the model overlays are
    reported missing (partial results)."""
    from fourws_analysis.compare import analyze_run

    vehicle = vehicle_from_mapping(SET_1)
    t = np.arange(0.0, 6.0, 2e-3)
    delta = np.where(t >= 1.0, math.radians(2.0), 0.0)
    cfg = _config("step_steer")
    del cfg["vehicle"]
    B.write_run(tmp_path / "nv", t, simulate_2dof(vehicle, SPEED, t, delta), cfg)
    res = analyze_run(B.resample(B.load_bag(tmp_path / "nv")))
    assert "vehicle" in res.unavailable["model_overlays"]
    assert res.step is not None
    L = vehicle.chassis.wheelbase_m
    assert res.step.responses["yaw_rate_radps"].steady_state_gain == pytest.approx(
        SPEED / (L + vehicle.understeer_gradient_rad_per_mps2 * SPEED ** 2), rel=1e-3)
