# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""fourws study: points equal the offline twin, seeds reproduce, backends agree, a killed study
resumes exactly, the stability boundary agrees with the critical speeds, bad study files are
one-line errors, and a point rerun through the node graph gives the study's row.

Sources of the numbers: the offline twin :func:`fourws_run.closed_loop.run_closed_loop` (the
reference the node graph is tested against in ``test_ros_graph.py``); the analytic means of
the sampled distributions (scipy.stats); the critical speeds of
:func:`fourws_analysis.linear.critical_speed` (what ``fourws linear --critical-speed`` prints)
and of the 8-DOF linearized closed loop; analytic clearances of straight paths through the
ISO 3888-2 course.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import scipy.stats
import yaml

from compiled_twin import compiled_and_twin
from fourws_analysis import linear
from fourws_analysis.extremes import run_extremes
from fourws_analysis.lane_change import lane_change_metrics
from fourws_cli.main import main as fourws_main
from fourws_control import LAWS, compiled
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers import DoubleLaneChangeParams
from fourws_sim.outcome import DIVERGED, SPUN
from fourws_sim.tires import TIRES, get_tire
from fourws_study.execute import run_study
from fourws_study.kernel import (build_law, prepare_compiled, run_compiled,
                                 run_compiled_block, run_interpreted)
from fourws_study.point import law_for, run_point
from fourws_study.report import critical_speed_8dof_lin, write_study_report
from fourws_study.spec import load_study
from fourws_study.store import read_results

ROOT = Path(__file__).resolve().parent.parent
#: ISO 7401 step steer of the default scenario, 3 s (the shortest run whose hold after the
#: step gives the ISO 7401 steady window twice).
STEP = {"name": "step_3s", "type": "step_steer", "initial_speed_mps": 23.611111111111111,
        "duration_s": 3.0, "amplitude_rad": 0.0261799387799, "start_s": 0.5,
        "ramp_time_s": 0.1}
SINE = {"name": "sine_2s", "type": "sine", "initial_speed_mps": 23.611111111111111,
        "duration_s": 2.0, "amplitude_rad": 0.0261799387799, "frequency_hz": 1.0,
        "start_s": 0.3}
#: Columns that describe the computation, not the point.
NOT_ROW = ["wall_time_s", "engine", "fallback"]


def _scenario(maneuver=STEP, **extra):
    data = {"name": "test", "vehicle": "table_8_1", "maneuver": dict(maneuver),
            "laws": ["fws"], "model": "8dof"}
    data.update(extra)
    return data


def _write(tmp_path: Path, name: str, data: dict) -> Path:
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump({"name": name, **data}, sort_keys=False))
    return path


def _study(tmp_path: Path, name: str, **data):
    return load_study(_write(tmp_path, name, data))


def _table(path: Path):
    return pq.read_table(path).drop_columns(NOT_ROW)


# ------------------------------------------------------------------ points and the twin

#: Law options that select a gain function a law's default options do not (each registered
#: law runs with its defaults; test_the_law_cases_reach_every_compiled_gain_function checks that
#: these cases reach every gain function of fourws_control.compiled).
OPTION_CASES = {"ff_zero_sideslip": [{"ksf": 0.2}]}
#: (law, options) of every registered law, then the option cases.
LAW_CASES = [(law, {}) for law in LAWS] + [
    (law, options) for law, cases in OPTION_CASES.items() for options in cases]
#: The tires with lane kernels (the batch kernel in vector instructions).
LANE_TIRES = [t for t in TIRES if hasattr(get_tire(t), "forces_lane")]
#: Every tire with lane kernels, then the first without.
TIRE_CASES = LANE_TIRES + [t for t in TIRES if t not in LANE_TIRES][:1]
#: Recorded channels of the compiled record and where the twin's result has each.
TWIN_CHANNELS = {
    "steering_wheel_angle_rad": lambda twin: twin.driver["steering_wheel_angle_rad"],
    "front_wheel_angle_cmd_rad": lambda twin: twin.driver["front_wheel_angle_rad"],
    "rear_law_rad": lambda twin: twin.rear_law_rad,
    "rear_command_rad": lambda twin: twin.rear_angle_rad,
    "drive_torque_total_nm": lambda twin: _wheel_sum(twin.driver["drive_torque_nm"]),
    "brake_torque_total_nm": lambda twin: _wheel_sum(twin.driver["brake_torque_nm"]),
}


def _wheel_sum(torques: np.ndarray) -> np.ndarray:
    """FL + FR + RL + RR in that order (the kernel's sum)."""
    return torques[:, 0] + torques[:, 1] + torques[:, 2] + torques[:, 3]


def _law_case_id(case) -> str:
    law, options = case
    return law + "".join(f"-{k}={v}" for k, v in options.items())


def _case_config(tmp_path: Path, maneuver: dict, law: str, options: dict, tire: str):
    study = _study(tmp_path, f"twin_{maneuver['type']}",
                   scenario=_scenario(maneuver, laws=[law], law_options={law: options},
                                      tire=tire),
                   grid={"belief.cornering_stiffness_scale": [0.7]})
    (point,) = study.points()
    return study.config(point)


def test_the_law_cases_reach_every_compiled_gain_function(tmp_path):
    """The cases of the next test build laws whose gain functions are, together, exactly the
    compiled loop's (fourws_control.compiled, from the registry): a law added to the
    registry is a case by itself, and one with a second gain function fails here until an
    option case reaches it."""
    reached = set()
    for law, options in LAW_CASES:
        built = build_law(_case_config(tmp_path, STEP, law, options, TIRE_CASES[0]))
        reached.add(built.gain_function().function)
    assert reached == set(compiled.gain_functions())
    assert sorted(compiled.law_kind(f) for f in reached) == list(range(len(reached)))


@pytest.mark.parametrize("tire", TIRE_CASES)
@pytest.mark.parametrize("law, options", LAW_CASES, ids=[_law_case_id(c) for c in LAW_CASES])
def test_every_law_and_tire_compiled_equals_the_twin_bit_for_bit(tmp_path, law, options, tire):
    """For every registered law (and option case) with every tire that has lane kernels and
    one without, a belief 30 % off, a step steer and a sine: the compiled closed loop of a
    study point alone (the scalar kernel) gives run_closed_loop's arrays of the same
    RunConfig to the last bit -- every recorded channel, the driver's commands, the law's
    command and the actuator's angle at every tick, and the state after the last tick -- and
    the point in a block (in vector instructions where the tire has lane kernels) gives the
    same bits."""
    for maneuver in (STEP, SINE):
        config = _case_config(tmp_path, maneuver, law, options, tire)
        built = build_law(config)
        assert compiled.law_kind(built.gain_function().function) is not None
        single, block, twin, prep = compiled_and_twin(config, built)
        assert prep.lanes == (tire in LANE_TIRES)
        assert single.time_s.tobytes() == twin.time_s.tobytes()
        assert single.channels.keys() == block.channels.keys()
        for name, values in single.channels.items():
            want = TWIN_CHANNELS[name](twin) if name in TWIN_CHANNELS else twin[name]
            assert values.tobytes() == want.tobytes(), name
            assert block.channels[name].tobytes() == values.tobytes(), name
        assert single.final == block.final == {
            name: float(twin.final_outputs[name]) for name in single.final}
        # the law acts: its rear steer is not zero (else the test would prove little)
        assert law == "fws" or np.max(np.abs(twin.rear_angle_rad)) > 1e-4


#: A run past each of the vehicle limits (fourws_sim.outcome), on the step: (maneuver
#: changes, law, the maneuver end, words of its reason). fws at 130 km/h is past table_8_1's
#: critical speed (test_stability_boundary...) and spins (past 20 deg at 2.2 s, measured with
#: both tires); at 85 m/s (km/h meant) with a 2.9 deg step and the sideslip limit lifted
#: the car turns round and drives backwards (at 2.4-2.9 s of 5 s); a roll limit of 0.01 rad
#: is below the roll of the 1.5 deg step at 85 km/h (passed at 0.67 s).
LIMIT_CASES = {
    "sideslip": ({"initial_speed_mps": 130.0 / 3.6}, "fws", SPUN, "the car spun"),
    "reversing": ({"initial_speed_mps": 85.0, "amplitude_rad": 0.05, "duration_s": 5.0,
                   "vehicle_limits": {"max_sideslip_rad": 3.1}},
                  "fws", SPUN, "the car drives backwards"),
    "roll": ({"vehicle_limits": {"max_roll_rad": 0.01}}, "sol1", DIVERGED, "roll"),
}


@pytest.mark.parametrize("tire", TIRE_CASES)
@pytest.mark.parametrize("case", LIMIT_CASES)
def test_a_run_past_its_vehicle_limits_ends_at_the_twins_state_bit_for_bit(tmp_path, case,
                                                                           tire):
    """A run whose car breaks one of its maneuver's vehicle limits ends where the twin
    (Maneuver.done) ends it, at the first state past the limit: the compiled point alone and
    in a block (in vector instructions where the tire has lane kernels) give
    run_closed_loop's ticks, channels and final state to the last bit and its end reason
    word for word, for each limit (sideslip and reversing: spun; roll: diverged)."""
    changes, law, kind, words = LIMIT_CASES[case]
    config = _case_config(tmp_path, {**STEP, **changes}, law, {}, tire)
    single, block, twin, _ = compiled_and_twin(config)
    assert twin.end_kind == kind and words in twin.end_reason, twin.end_reason
    # it ended early, before the maneuver's last tick
    full = round(config.maneuver.duration_s / config.control_period_s)
    assert 0 < twin.time_s.size < full
    assert single.end_reason == block.end_reason == twin.end_reason
    assert single.time_s.tobytes() == twin.time_s.tobytes()
    for name, values in single.channels.items():
        want = TWIN_CHANNELS[name](twin) if name in TWIN_CHANNELS else twin[name]
        assert values.tobytes() == want.tobytes(), name
        assert block.channels[name].tobytes() == values.tobytes(), name
    assert single.final == block.final == {
        name: float(twin.final_outputs[name]) for name in single.final}
    # the final state is the first past the limit: every answered state is within it
    limits = config.maneuver.vehicle_limits
    assert limits.first_violation(twin.time_s, twin["sideslip_rad"], twin["speed_mps"],
                                  twin["roll_rad"]) is None
    breach = limits.violation(single.final["sim_time_s"], single.final)
    assert breach is not None and breach.kind == kind


def test_batch_kernel_equals_the_single_run_kernel_bit_for_bit(tmp_path):
    """One call of the batch kernel over a block mixing laws with gain functions of different
    parameter counts (closed form, 3-DOF fit, LQR table), speeds, a spinning point and two
    maneuvers of different lengths gives each point the arrays of its own single-run call to
    the last bit (the block pads steering and output rows; a point must read only its own;
    the vectorized integration of many points at once performs each point's scalar
    operations)."""
    preps, singles = [], []
    for maneuver, speeds in ((STEP, [60.0, 130.0]), (SINE, [90.0])):
        study = _study(tmp_path, f"block_{maneuver['type']}", scenario=_scenario(maneuver),
                       grid={"speed_kmh": speeds, "belief.cornering_stiffness_scale": [0.7],
                             "law": ["fws", "sol1", "rwc4_3dof", "lqr"]})
        for point in study.points():
            config = study.config(point)
            law = build_law(config)
            prep = prepare_compiled(config, law)
            assert not isinstance(prep, str), prep
            preps.append(prep)
            singles.append(run_compiled(config, law))
    assert len({p.front.size for p in preps}) == 2  # blocks of unequal runs
    # the STI tire of table_8_1 has lane kernels: the block runs in vector instructions
    # (closed_loop_lanes, 16 points at a time, here one full group and one of 4 lanes)
    assert all(p.lanes for p in preps)
    batch = run_compiled_block(preps)
    assert len(batch) == len(singles) == 12
    for got, want in zip(batch, singles):
        assert not isinstance(got, str) and not isinstance(want, str)
        assert got.channels.keys() == want.channels.keys()
        for name, values in want.channels.items():
            assert got.channels[name].tobytes() == values.tobytes(), name
        assert got.final == want.final and got.end_reason == want.end_reason
    # the block holds a point that spins (fws at 130 km/h is past the critical speed): its
    # neighbours are unaffected, as compared above
    assert max(np.max(np.abs(r.channels["sideslip_rad"])) for r in batch) > 0.2
    # a tire the vector kernel does not take (STI with G2 != 1 needs a power function) runs
    # in the scalar batch kernel beside the others, with the same result
    mixed = _study(tmp_path, "block_g2", scenario=_scenario(STEP), law="sol1",
                   grid={"vehicle.tire.sti.g2": [1.0, 1.3]})
    configs = [mixed.config(point) for point in mixed.points()]
    preps = [prepare_compiled(c, build_law(c)) for c in configs]
    assert [p.lanes for p in preps] == [True, False]
    for got, config in zip(run_compiled_block(preps), configs):
        want = run_compiled(config, build_law(config))
        assert not isinstance(got, str) and not isinstance(want, str)
        for name, values in want.channels.items():
            assert got.channels[name].tobytes() == values.tobytes(), name


def test_study_rows_do_not_depend_on_the_path(tmp_path):
    """A point's row is the same whether its run took the compiled path or the interpreted
    twin, and a lane change (the path-tracking driver) runs on the twin by itself."""
    study = _study(tmp_path, "paths", scenario=_scenario(),
                   grid={"speed_kmh": [60.0, 130.0], "law": ["fws", "rwc2_3dof"]})
    rows = {}
    for i in range(study.n_points):
        a, b = run_point(study, i), run_point(study, i, compiled=False)
        assert a["engine"] == "compiled" and b["engine"] == "twin"
        for key in set(a) - set(NOT_ROW):
            assert a[key] == b[key] or (a[key] != a[key] and b[key] != b[key]), key
        rows[(a["law"], a["speed_kmh"])] = a
    # fws at 130 km/h is past table_8_1's critical speed: the point spins (its status says
    # so, by the maneuver's vehicle limits, at the state its run ended at) and the study
    # goes on
    spun = rows[("fws", 130.0)]
    assert spun["status"] == "spun" and spun["status_reason"] == spun["end_reason"]
    assert spun["status_reason"].startswith("the car spun: |sideslip|")
    assert f"t = {spun['status_time_s']:.2f} s" in spun["status_reason"]
    assert spun["spin_time_s"] == spun["status_time_s"]
    assert spun["status_time_s"] == pytest.approx(spun["duration_s"] + 0.01, abs=1e-9)
    assert rows[("fws", 60.0)]["status"] == rows[("rwc2_3dof", 130.0)]["status"] == "ok"
    # the spun run's ISO 7401 metrics are not reported (absent: null in the table), and its
    # metrics say why; an ok run has them
    iso = [k for k in rows[("fws", 60.0)] if k.startswith("iso7401.")]
    assert len(iso) > 10 and all(rows[("fws", 60.0)][k] is not None for k in
                                 ("iso7401.yaw_rate_radps.steady_state_radps",
                                  "iso7401.yaw_rate_radps.response_time_s"))
    assert not any(k.startswith("iso7401.") for k in spun)
    everything = json.loads(spun["metrics_json"])
    assert everything["vehicle_limits"]["kind"] == "spun"
    # (the analysis reads the states stamped to the ns, as a bag holds them)
    assert everything["vehicle_limits"]["time_s"] == pytest.approx(spun["status_time_s"],
                                                                   abs=1e-9)
    assert spun["status_reason"] in everything["unavailable"]["iso7401_step"]
    lane = load_study(_write(tmp_path, "lane", {"scenario": "lane_change", "law": "sol1"}))
    config = lane.config(lane.point(0))
    assert isinstance(run_compiled(config, law_for(config)), str)
    assert run_interpreted(config).engine == "twin"


# ------------------------------------------------------------------ seeds and draws

def test_seeds_reproduce_and_draws_follow_their_distributions(tmp_path):
    """A point's draws come from its seed alone (the same on a fresh load), the points of
    one sample share them, and 2000 draws have the analytic means of their distributions
    (truncated normal, uniform, log-normal median) within 4 standard errors."""
    data = {"scenario": _scenario(), "grid": {"law": ["fws", "sol1"]},
            "monte_carlo": {"samples": 2000, "seed": 7, "fields": {
                "vehicle.chassis.mass_kg, vehicle.roll.sprung_mass_kg": {
                    "apply": "scale", "distribution": "normal", "mean": 1.0, "std": 0.05,
                    "truncate": [0.95, 1.2]},
                "vehicle.chassis.cg_to_front_axle_m, -vehicle.chassis.cg_to_rear_axle_m": {
                    "apply": "shift", "distribution": "uniform", "low": -0.1, "high": 0.1},
                "vehicle.chassis.yaw_inertia_kgm2": {
                    "apply": "scale", "distribution": "lognormal", "median": 1.1,
                    "sigma": 0.05}}}}
    study = load_study(_write(tmp_path, "mc", data))
    # a fresh load (of fewer samples: a sample's seed depends on the study seed and its number)
    again = load_study(_write(tmp_path, "mc", {
        **data, "monte_carlo": {**data["monte_carlo"], "samples": 1235}}))
    p, q = study.point(2 * 1234 + 1), again.point(2 * 1234 + 1)
    assert p == q and p.sample == 1234 and p.value("law") == "sol1"
    assert study.point(2 * 1234).values[1:] == p.values[1:]  # one sample, both laws
    assert study.point(2 * 1235).seed != p.seed
    assert study.draws(p.seed) == tuple(v for _, v in p.values[1:])
    config = study.config(p)
    c = config.vehicle.chassis
    mass, shift, inertia = study.draws(p.seed)
    assert c.mass_kg == 1298.857 * mass
    assert config.vehicle.roll.sprung_mass_kg == 1167.512 * mass
    assert c.cg_to_front_axle_m == 1.0 + shift and c.cg_to_rear_axle_m == 1.45 - shift
    assert config.belief.chassis.mass_kg == c.mass_kg  # the belief is the simulated car
    draws = np.array([study.draws(study.sample_seed(s)) for s in range(study.n_samples)])
    n = draws.shape[0]
    tn = scipy.stats.truncnorm(-1.0, 4.0, loc=1.0, scale=0.05)
    assert abs(draws[:, 0].mean() - tn.mean()) < 4 * tn.std() / math.sqrt(n)
    assert draws[:, 0].min() >= 0.95 and draws[:, 0].max() <= 1.2
    assert abs(draws[:, 1].mean()) < 4 * (0.2 / math.sqrt(12)) / math.sqrt(n)
    below = np.mean(draws[:, 2] < 1.1)  # the median of a log-normal
    assert abs(below - 0.5) < 4 * 0.5 / math.sqrt(n)


# ------------------------------------------------------------------ backends, kill, resume

@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    """Six points (three laws, two speeds), one per block, and their serial results."""
    tmp = tmp_path_factory.mktemp("study")
    path = _write(tmp, "small", {"scenario": _scenario(), "block_size": 1,
                                 "grid": {"speed_kmh": [70.0, 110.0],
                                          "law": ["fws", "sol1", "rwc2_3dof"]}})
    study = load_study(path)
    serial = tmp / "serial"
    run_study(study, serial, workers=1)
    return path, study, serial


def test_backends_give_identical_rows(small_study, tmp_path):
    """Serial, two local worker processes and a Dask LocalCluster of two workers write the
    same table (every column but the wall time)."""
    _, study, serial = small_study
    local = run_study(study, tmp_path / "local", workers=2)
    dask = run_study(study, tmp_path / "dask", workers=2, backend="dask")
    assert local.done == dask.done == study.n_points == 6
    ref = _table(serial / "results.parquet")
    assert ref.column("point").to_pylist() == list(range(6))
    assert _table(tmp_path / "local" / "results.parquet").equals(ref)
    assert _table(tmp_path / "dask" / "results.parquet").equals(ref)


def test_report_lists_the_worst_points_with_their_rerun(small_study):
    """The report has a section per law and ranks the points by peak sideslip: its first
    row is the point with the largest one, with the command that reruns it."""
    _, study, serial = small_study
    index = write_study_report(serial, study)
    text = index.read_text()
    table = read_results(serial, study)
    beta = np.array(table.column("max_abs_sideslip_rad").to_pylist())
    top = int(np.argmax(beta))
    worst = text[text.index("Worst points"):]
    assert f"fourws study rerun {serial} --point {top}<" in worst.split("</tr>")[1]
    for law in ("fws", "sol1", "rwc2_3dof"):
        assert f"<h2>Law {law}</h2>" in text
        assert (index.parent / f"stability_{law}.png").stat().st_size > 0


def test_killed_study_resumes_to_the_uninterrupted_table(small_study, tmp_path):
    """SIGKILL while a study runs leaves a readable partial table (complete blocks only);
    --resume runs the rest: every point once, none lost, and the table equals the
    uninterrupted run's."""
    path, study, serial = small_study
    out = tmp_path / "killed"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-m", "fourws_cli.main", "study", str(path),
                             "--out", str(out), "--workers", "1", "--no-report",
                             "--interpreted"], cwd=ROOT, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120.0
    try:
        while time.monotonic() < deadline and not any((out / "blocks").glob("block-*")):
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    partial = pq.read_table(out / "blocks")  # what the kill left, read by plain pyarrow
    points = partial.column("point").to_pylist()
    assert 1 <= len(points) < study.n_points, "the kill came after the study had finished"
    assert len(set(points)) == len(points)
    resumed = run_study(study, out, workers=1, resume=True)
    assert resumed.ran == study.n_points - len(points)
    final = _table(out / "results.parquet")
    assert final.column("point").to_pylist() == list(range(study.n_points))
    ref = _table(serial / "results.parquet")
    assert final.equals(ref)


def test_a_killed_worker_stops_the_study_loudly_and_resume_completes_it(
        small_study, tmp_path):
    """SIGKILL of a local worker process (the out-of-memory killer's way) ends the study at
    once with the worker named and how it died, never a wait for the lost block; the finished
    blocks stay, and --resume gives the uninterrupted table."""
    import multiprocessing

    path, study, serial = small_study
    out = tmp_path / "worker_killed"
    killed: list[int] = []

    def kill_a_worker(block: int) -> None:
        if not killed:
            workers = [p for p in multiprocessing.active_children() if p.pid]
            assert workers, "no worker process to kill"
            killed.append(workers[0].pid)
            os.kill(workers[0].pid, signal.SIGKILL)

    run = run_study(study, out, workers=2, on_block=kill_a_worker)
    assert killed and f"worker {killed[0]} killed by signal 9 (SIGKILL)" in run.failed
    assert not run.interrupted and 1 <= run.done < study.n_points
    assert "STOPPED (a worker died)" in run.summary_line(study.name)
    kept = pq.read_table(out / "blocks").column("point").to_pylist()
    assert len(kept) == run.done and len(set(kept)) == len(kept)
    resumed = run_study(study, out, workers=2, resume=True)
    assert not resumed.failed and resumed.ran == study.n_points - run.done
    assert _table(out / "results.parquet").equals(_table(serial / "results.parquet"))


def _flipped(path: Path, offset: int) -> None:
    data = bytearray(path.read_bytes())
    data[offset] ^= 0x10
    path.write_bytes(bytes(data))


def test_a_flipped_byte_in_a_block_is_an_error_never_another_number(small_study, tmp_path):
    """Every 97th byte of a block file flipped in turn (about 300 files): reading the study
    either gives exactly the original table (a byte Parquet does not use) or refuses in one
    line naming the file and the --resume that recomputes it; no flip gives other numbers.
    Measured on a block of 30 946 bytes: 39 of its 312 sampled flips gave other rows with
    plain Parquet; flipping every byte, 3 did with page checksums and the schema check
    alone (page headers), none with the rows' digest."""
    _, study, serial = small_study
    out = tmp_path / "flip"
    shutil.copytree(serial, out)
    block = out / "blocks" / "block-000002.parquet"
    pristine = block.read_bytes()
    ref = read_results(serial, study)
    outcomes = {"same": 0, "refused": 0}
    for offset in range(0, len(pristine), 97):
        block.write_bytes(pristine)
        _flipped(block, offset)
        try:
            table = read_results(out, study)
        except ParameterError as exc:
            msg = str(exc)
            assert "\n" not in msg and str(block) in msg and "--resume" in msg, msg
            outcomes["refused"] += 1
        else:
            assert table.equals(ref), offset
            outcomes["same"] += 1
    assert outcomes["refused"] > 0 and sum(outcomes.values()) == -(-len(pristine) // 97)


def test_a_damaged_block_is_one_line_and_resume_recomputes_it(small_study, tmp_path, capsys):
    """A byte flipped in a data page of block 2 (its last byte of the peak-sideslip column,
    covered by the page's CRC-32): ``fourws study report`` is exit 2 and one line naming
    the file (was a pyarrow.lib.ArrowInvalid traceback, or an unnamed OSError line);
    ``--resume`` runs that one block again and the table equals the uninterrupted one."""
    path, study, serial = small_study
    out = tmp_path / "damaged"
    shutil.copytree(serial, out)
    block = out / "blocks" / "block-000002.parquet"
    meta = pq.ParquetFile(block).metadata.row_group(0)
    chunk = next(meta.column(i) for i in range(meta.num_columns)
                 if meta.column(i).path_in_schema == "max_abs_sideslip_rad")
    _flipped(block, chunk.data_page_offset + chunk.total_compressed_size - 1)
    code = fourws_main(["study", "report", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err, err
    line, = err.strip().splitlines()
    assert line.startswith("fourws study: error: <file>: damaged Parquet block"), line
    assert str(block) in line and f"--out {out} --resume` recomputes it" in line, line
    resumed = run_study(study, out, workers=1, resume=True)
    assert resumed.ran == 1 and not resumed.failed
    assert _table(out / "results.parquet").equals(_table(serial / "results.parquet"))


@pytest.mark.parametrize("name", ["block-000099.parquet", "notes.txt"])
def test_a_stray_file_in_blocks_is_refused_before_anything_runs(small_study, tmp_path,
                                                                capsys, name):
    """A file that is no block of the study (a block number past its 6 blocks, any other
    file: ``read_table("DIR/blocks")`` would read it too) ends ``--resume`` and ``study
    report`` with exit 2 and one line naming it; --resume runs nothing."""
    path, study, serial = small_study
    out = tmp_path / "stray"
    shutil.copytree(serial, out)
    (out / "blocks" / "block-000004.parquet").unlink()
    stray = out / "blocks" / name
    shutil.copy(serial / "blocks" / "block-000000.parquet", stray)
    for argv in (["study", str(path), "--out", str(out), "--resume", "--no-report"],
                 ["study", "report", str(out)]):
        code = fourws_main(argv)
        err = capsys.readouterr().err
        assert code == 2 and "Traceback" not in err, err
        line, = [ln for ln in err.strip().splitlines() if "error" in ln]
        assert line.startswith("fourws study: error: <file>: is not a block of this study "
                               "(its blocks are block-000000.parquet to block-000005.parquet)")
        assert str(stray) in line, line
    assert not (out / "blocks" / "block-000004.parquet").exists()


# ------------------------------------------------------------------ stability boundary

def test_stability_boundary_agrees_with_the_critical_speeds(tmp_path):
    """sol2 designed on a belief with 40 % less front cornering stiffness (Solution 2 is
    unstable on an oversteer belief, chapter 4): along the speed axis the study's points turn
    unstable between two grid speeds that bracket (a) the critical speed of the 3-DOF closed
    loop at that belief -- ``fourws linear --critical-speed`` (linear.critical_speed) -- in
    the points' 3-DOF verdict, (b) that of the 8-DOF linearized closed loop in the points'
    8-DOF verdict, and (c) the nonlinear 8-DOF runs spin from the first grid speed past (b):
    the simulation and its linearization agree to within the grid step."""
    study = _study(tmp_path, "boundary", scenario=_scenario(
        {**STEP, "duration_s": 5.0}), law="sol2",
        grid={"belief.cornering_stiffness_scale_front": [0.6],
              "speed_mps": {"from": 10.0, "to": 22.5, "step": 2.5}})
    rows = [run_point(study, i) for i in range(study.n_points)]
    speeds = np.array([r["speed_mps"] for r in rows])
    config = study.config(study.point(0))
    law = law_for(config)
    v3 = linear.critical_speed("3dof", config.vehicle, law, (5.0, 60.0)).critical_speed_mps
    v8 = critical_speed_8dof_lin(config.vehicle, law, config.belief, config.law_options,
                                 5.0, 60.0)
    assert v3 is not None and v8 is not None
    for verdict, vc in ((np.array([r["stable_linear"] for r in rows]), v3),
                        (np.array([r["stable_8dof_lin"] for r in rows]), v8),
                        (np.array([r["status"] == "ok" for r in rows]), v8)):
        assert np.all(verdict[speeds < vc]) and not np.any(verdict[speeds >= vc]), (vc,
                                                                                    verdict)
        assert speeds[verdict].max() < vc <= speeds[~verdict].min() <= vc + 2.5


# ------------------------------------------------------------------ bad study files

BAD = [
    ({"grid": {"vehicle.chassis.mas_kg": [1000.0]}}, "vehicle.chassis.mas_kg"),
    ({"grid": {"speed_kmh": []}}, "grid.speed_kmh"),
    ({"grid": {"law": ["fws", "nope"]}}, "nope"),
    ({"grid": {"vehicle.chassis.mass_kg": [-5.0]}}, "chassis.mass_kg: must be > 0"),
    ({"grid": {"vehicle.chassis.mass_kg": {"scale": [0.5]}}}, "roll.sprung_mass_kg"),
    ({"monte_carlo": {"samples": 10, "fields": {"vehicle.chassis.mass_kg": {
        "distribution": "normal", "mean": 1300.0, "std": 0.0}}}}, "std"),
    ({"monte_carlo": {"samples": 10, "fields": {"vehicle.chassis.mass_kg": {
        "distribution": "normal", "mean": 1300.0, "std": 100.0}}}}, "truncate"),
    ({"monte_carlo": {"samples": 10, "fields": {"vehicle.chassis.mass_kg": {
        "distribution": "uniform", "low": 2.0, "high": 1.0}}}}, "high"),
    ({"grid": {"vehicle.chassis.mass_kg": {"shift": [10.0]}}, "grids": {}}, "grids"),
    ({"monte_carlo": {"samples": 1_000_001, "fields": {"vehicle.chassis.mass_kg": {
        "distribution": "uniform", "low": 1200.0, "high": 1400.0}}}}, "--force"),
    # the study's own spin threshold is gone: the maneuver's vehicle limits are the rule
    ({"spin_sideslip_rad": 0.3}, "vehicle_limits: {max_sideslip_rad"),
]


@pytest.mark.parametrize("data, names", BAD, ids=[b[1] for b in BAD])
def test_bad_study_files_are_one_line_errors(tmp_path, capsys, data, names):
    """Each bad study ends ``fourws study`` with exit code 2 and one line on stderr naming
    the field and the study file, before any point runs."""
    path = _write(tmp_path, "bad", {"scenario": _scenario(), **data})
    code = fourws_main(["study", str(path), "--out", str(tmp_path / "out"), "--no-report"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert names in err
    assert str(path) in err or "valid:" in err  # an unknown name lists the valid ones
    assert not (tmp_path / "out" / "blocks").exists() or not any(
        (tmp_path / "out" / "blocks").iterdir())


def _study_refused(tmp_path, capsys, path: Path, *needles: str) -> str:
    """``fourws study PATH`` ends with exit code 2 and one line naming ``path`` and the
    needles, with no traceback and no output folder."""
    code = fourws_main(["study", str(path), "--out", str(tmp_path / "out"), "--no-report"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    line, = err.strip().splitlines()
    assert line.startswith("fourws study: error: ") and str(path) in line, line
    for needle in needles:
        assert needle in line, line
    assert not (tmp_path / "out").exists()
    return line


def test_study_file_with_a_duplicate_key_is_refused(tmp_path, capsys):
    """YAML forbids duplicate keys (YAML 1.2, 3.2.1.1): ``block_size`` given twice (lines 3
    and 4 of the file) was read as its last value; it is refused naming both lines."""
    path = tmp_path / "twice.yaml"
    path.write_text("name: twice\nscenario: default\nblock_size: 8\nblock_size: 16\n")
    _study_refused(tmp_path, capsys, path, "block_size", "duplicate key at line 4",
                   "first at line 3")


@pytest.mark.parametrize("data, needle", [
    ("name: x\nscenario: default\ndescription: Fahrzeug f\u00fcr Tests\n".encode("latin-1"),
     "not UTF-8 text (byte 0xfc at offset 49)"),
    ("name: x\nscenario: default\n".encode("utf-16"), "UTF-16"),
], ids=["latin1", "utf16"])
def test_study_file_not_utf8_is_one_line(tmp_path, capsys, data, needle):
    """A Latin-1 study file (the u-umlaut is byte 0xfc, at offset 49 counted by hand: 'name:
    x' and its newline 8 bytes, 'scenario: default' and its newline 18, 'description:
    Fahrzeug f' 23) and a UTF-16 one were a UnicodeDecodeError traceback."""
    path = tmp_path / "encoded.yaml"
    path.write_bytes(data)
    _study_refused(tmp_path, capsys, path, needle)


@pytest.mark.parametrize("report, field", [
    ({"metrics": ["max_abs_sideslip_rad", "iso7401.yaw_rate_radps.overshot_fraction"]},
     "report.metrics"),
    ({"worst": {"metric": "sideslip"}}, "report.worst.metric"),
    ({"metrics": ["status"]}, "report.metrics"),
], ids=["misspelt", "worst", "not_numeric"])
def test_unknown_report_metric_is_refused_listing_the_valid_names(tmp_path, capsys, report,
                                                                  field):
    """A report metric that is no numeric column of the study's results (a misspelt one, a
    string column) drew nothing without a word; it is refused, listing every numeric
    column (the float, integer and boolean columns of fourws_study.point.columns)."""
    from fourws_study.point import columns

    path = _write(tmp_path, "bad", {"scenario": _scenario(), "report": report})
    bad = (report.get("metrics") or [report["worst"]["metric"]])[-1]
    line = _study_refused(tmp_path, capsys, path,
                          f"{field}: {bad!r} is not a numeric result column (valid: ")
    ok = _study(tmp_path, "ok", scenario=_scenario())
    numeric = [n for n, kind in columns(ok) if kind in ("float64", "int64", "bool")]
    assert f"(valid: {', '.join(numeric)}) in {path}" in line
    assert "iso7401.yaw_rate_radps.overshoot_fraction" in numeric and "status" not in numeric


# ------------------------------------------------------------------ metrics

def test_lane_change_clearance_of_straight_paths():
    """ISO 3888-2 course with W = 1.7 m: driving straight along y = 0 clears sections 1 and 5
    by (w1 - W) / 2 but misses section 3 by its whole offset, y3_right + W/2; a path inside
    every gate with 5 cm to spare passes with clearance 0.05 m."""
    p = DoubleLaneChangeParams()
    sections = p.sections
    x = np.arange(0.0, 100.0, 0.25)
    straight = lane_change_metrics(x, np.zeros_like(x), sections, 1.7)
    assert straight.clearance_m == pytest.approx(-(sections[1][2] + 0.85), abs=1e-12)
    assert not straight.passed and straight.sections_driven == 3
    y = np.zeros_like(x)
    for x0, x1, y_right, _ in sections:
        y[(x >= x0 - 1e-9) & (x <= x1 + 1e-9)] = y_right + 0.85 + 0.05
    ok = lane_change_metrics(x, y, sections, 1.7)
    assert ok.passed and ok.clearance_m == pytest.approx(0.05, abs=1e-12)
    short = lane_change_metrics(x[x < 50.0], y[x < 50.0], sections, 1.7)
    assert not short.passed and short.sections_driven == 1


def test_run_extremes_count_the_actuator_limits():
    """A rear actuator ramping at its rate limit (30 deg/s, 10 ms ticks: 5.24 mrad a tick)
    for 16 ticks, then reaching its 5-deg angle limit with a shorter move and holding it for
    7 ticks in all: 0.16 s at the rate limit, 0.07 s at the angle limit; sideslip beyond
    20 deg from t = 0.03 s is a spin from then."""
    rate, limit, period = math.radians(30.0), math.radians(5.0), 0.01
    rear = np.concatenate([np.arange(1, 17) * rate * period, np.full(7, limit)])
    assert limit - 16 * rate * period < rate * period  # the last move is a short one
    t = np.arange(rear.size) * period
    beta = np.where(t >= 0.03, math.radians(25.0), 0.0)
    ex = run_extremes(t, beta, beta, beta, beta, rear, period, limit, rate)
    assert ex.time_at_rear_rate_limit_s == pytest.approx(16 * period)
    assert ex.time_at_rear_angle_limit_s == pytest.approx(7 * period)
    assert ex.spin_time_s == pytest.approx(0.03)
    assert ex.max_abs_sideslip_rad == pytest.approx(math.radians(25.0))


# ------------------------------------------------------------------ the node graph

def test_rerun_through_the_graph_equals_the_study_row(tmp_path):
    """A point of a finished study run through the real node graph (run_graph with the
    point's RunConfig) records a bag whose row -- the same metric functions on its ticks --
    equals the study's row in every compared column; and ``fourws analyze``'s ISO 7401
    numbers of that bag equal the study's exactly (the study hands the analysis its run as
    the bag holds it)."""
    from fourws_analysis.bag import resample
    from fourws_analysis.compare import analyze_run
    from fourws_ros.graph_run import run_graph
    from fourws_study.rerun import bag_row, compare_rows, study_of, study_row

    path = _write(tmp_path, "one", {"scenario": _scenario(), "law": "sol1",
                                    "grid": {"belief.cornering_stiffness_scale": [0.8],
                                             "vehicle.chassis.mass_kg": {"scale": [1.05]}}})
    run_study(load_study(path), tmp_path / "study", workers=1)
    study = study_of(tmp_path / "study")
    config = study.config(study.point(0))
    record = run_graph(config, tmp_path / "graph", run_name="point-0")
    assert record.ok, record.reason
    graph = bag_row(study, 0, config, record.bag_path)
    row = study_row(tmp_path / "study", study, 0)
    diffs = compare_rows(row, graph)
    assert len(diffs) > 40
    assert max(d[3] for d in diffs) == 0.0, [d for d in diffs if d[3] > 0.0]
    analysed = analyze_run(resample(load_bag_of(record.bag_path)), eig_sweep=False,
                           models=False).metrics()["iso7401_step"]
    compared = 0
    for channel in ("yaw_rate_radps", "lateral_accel_mps2"):
        for key, value in analysed[channel].items():
            if isinstance(value, float):
                assert row[f"iso7401.{channel}.{key}"] == value, (channel, key)
                compared += 1
    assert compared >= 10


def load_bag_of(path):
    from fourws_analysis.bag import load_bag

    return load_bag(path)


def test_metric_columns_come_from_the_result_definitions(tmp_path):
    """A result class gives its study columns by its field types alone (a field added to a
    metric needs no placeholder written by hand): a dataclass of every kind of field the
    analysis results use gets, by hand, True, 0, 0.0 (also for float | None), (0.0, 0.0),
    [], {} and '', and the given fields keep their values; the study's columns of the ISO
    7401 steady yaw gain, settling and the ISO 3888 sections driven are float64, bool and
    int64 (the fields' types in iso7401 and lane_change)."""
    import dataclasses

    from fourws_study import point

    @dataclasses.dataclass
    class Result:
        settled: bool
        count: int
        value: float
        maybe: float | None
        span: tuple[float, float]
        notes: list[str]
        curves: dict[str, np.ndarray]
        label: str = "x"

    got = point._placeholder(Result, count=7)
    assert dataclasses.astuple(got) == (True, 7, 0.0, 0.0, (0.0, 0.0), [], {}, "")
    columns = dict(point.columns(_study(tmp_path, "cols", scenario=_scenario(STEP),
                                        grid={"speed_kmh": [60.0]})))
    assert columns["iso7401.yaw_rate_radps.steady_state_gain_radps_per_rad_road_wheel"] \
        == "float64"
    assert columns["iso7401.yaw_rate_radps.settled"] == "bool"
    assert columns["iso3888.sections_driven"] == "int64"
