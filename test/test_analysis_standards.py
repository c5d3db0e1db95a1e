"""`fourws analyze` of FMVSS No. 126 and ISO 17288 runs: metrics from the bag equal those of
the arrays, pass/fail per run and per law in metrics.json and the report, the graders' plots.

Sources: the regulation's metrics computed directly on the offline twin's arrays
(fourws_analysis.fmvss126, tested on closed forms in test_fmvss126); A of the run layer (the
same regression on the twin).
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import pytest

from fourws_analysis import bag as B
from fourws_analysis import fmvss126
from fourws_cli.main import main
from fourws_run.closed_loop import run_closed_loop
from fourws_run.scenario import load_scenario
from fourws_run.series import run_series, scenario_runs
from fourws_sim.params import load_vehicle


def _write(result, path: Path) -> Path:
    B.write_run(path, result.time_s, result.outputs, result.config, driver=result.driver,
                model=result.model)
    return path


@pytest.fixture(scope="module")
def bags(tmp_path_factory) -> tuple[Path, list[Path], dict]:
    """Per law (fws, rwc1_3dof) of the shipped FMVSS 126 scenario on a 0.5 road: its slowly
    increasing steer left and its first two sine-with-dwell runs; and a steering release of
    ISO 17288-1 (8dof-free) with fws. Offline twin runs written as bags."""
    root = tmp_path_factory.mktemp("standards")
    sc = load_scenario("fmvss126_sine_with_dwell")
    sc = dataclasses.replace(sc, road_friction_coefficient=0.5, laws=("fws", "rwc1_3dof"))
    paths, twin = [], {}
    for law in sc.laws:
        members = scenario_runs(sc, law)
        pick = [members[0]] + [m for m in members if m.type == "sine_with_dwell"][:2]
        for spec, res in zip(pick, run_series(sc, law, pick)):
            paths.append(_write(res, root / f"{law}-{spec.name}"))
            twin[paths[-1].name] = (spec, res)
    rel = run_closed_loop(load_vehicle("table_8_1"), "steering_release", "fws",
                          model="8dof-free")
    paths.append(_write(rel, root / "fws-steering_release"))
    return root, paths, twin


def test_report_gives_fmvss126_and_iso17288_metrics(bags, capsys) -> None:
    """metrics.json holds each sine-with-dwell run's yaw ratios and displacement as computed on
    the twin's arrays (the bag's grid is the twin's), A of each slowly-increasing-steer bag
    equals the run layer's (within the 0.1-deg rounding), each law's verdict (fws fails,
    rwc1_3dof passes these runs), the release's metrics; index.html has the tables, the
    verdicts and the graders' plot."""
    root, paths, twin = bags
    rep = root / "rep"
    rc = main(["analyze", *map(str, paths), "--report", str(rep), "--quiet", "--no-sweep"])
    assert rc == 0
    data = json.loads((rep / "metrics.json").read_text())
    runs = data["runs"]
    for name, (spec, res) in twin.items():
        got = runs[name]
        if spec.type == "sine_with_dwell":
            ref = fmvss126.sine_with_dwell_metrics(
                res.time_s, res["steering_wheel_angle_rad"], res["yaw_rate_radps"],
                res["lateral_accel_mps2"], zero_before_s=spec.params.start_s,
                amplitude_factor=spec.params.amplitude_factor,
                reference_amplitude_rad=spec.params.reference_amplitude_rad).to_dict()
            m = got["fmvss126_sine_with_dwell"]
            for key in ("yaw_ratio_1_00", "yaw_ratio_1_75", "lateral_displacement_m",
                        "bos_s", "cos_s"):
                assert m[key] == pytest.approx(ref[key], rel=1e-9, abs=1e-9), (name, key)
            assert m["passed"] == ref["passed"]
        else:
            a = got["fmvss126_slowly_increasing_steer"]["steering_wheel_angle_at_0_3g_deg"]
            swd = [s for s, _ in twin.values() if s.type == "sine_with_dwell"
                   and s.params.reference_law == name.split("-")[0]][0]
            assert a == pytest.approx(math.degrees(swd.params.reference_amplitude_rad),
                                      abs=0.05)
    verdicts = {v["law"]: v["passed"] for v in data["fmvss126_law_verdicts"]}
    assert verdicts == {"fws": False, "rwc1_3dof": True}
    release = runs["fws-steering_release"]["iso17288_1_steering_release"]
    assert release["lateral_accel_initial_mps2"] == pytest.approx(4.0, rel=0.015)
    html = (rep / "index.html").read_text()
    assert "FMVSS No. 126 sine with dwell (per run)" in html
    assert "Law fws: FAILS" in html and "Law rwc1_3dof: PASSES" in html
    assert "ISO 17288-1 steering release" in html
    for png in ("sine_with_dwell.png", "free_steer.png"):
        assert (rep / png).stat().st_size > 10_000
