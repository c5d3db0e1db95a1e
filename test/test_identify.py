# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws identify``: output-error fits recover the parameters of fourws's own runs.

Source of every expected number: the vehicle the offline twin ran (a copy of table_8_1 with
cornering stiffnesses, yaw inertia and roll stiffness moved by 15-25 %); the fit starts from
the unchanged table_8_1 and must find the moved values again -- within 2 % from noiseless
records (the model levels are the twin's own models, so only integration error remains), and
within the reported 95 % interval from records with realistic sensor noise and bias (the noise
levels are written below with their source). Refusals: analytic facts of the models (a steady
state does not depend on the yaw inertia; the 3-DOF carries only the sum of the front and rear
roll stiffness; the 8-DOF's STI tire does not read the axle cornering stiffnesses).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fourws_analysis import bag as B
from fourws_analysis.fit import ExcitationError, identify, vehicle_yaml
from fourws_analysis.measured import MeasuredLog, load_log, write_table
from fourws_cli.main import main
from fourws_run.closed_loop import run_closed_loop
from fourws_sim.params import load_vehicle, vehicle_from_mapping

CF = "axle_tires.cornering_stiffness_front_n_per_rad"
CR = "axle_tires.cornering_stiffness_rear_n_per_rad"
IZ = "chassis.yaw_inertia_kgm2"
KPHI = "roll.roll_stiffness_front_nm_per_rad,roll.roll_stiffness_rear_nm_per_rad"
SIGMA = "tire.relaxation_length_m"
#: Truth = base with these factors (10-30 % off, as the issue asks; the car stays stable).
MOVED = {CF: 0.8, CR: 1.15, IZ: 1.2, "roll.roll_stiffness_front_nm_per_rad": 1.25,
         "roll.roll_stiffness_rear_nm_per_rad": 1.25}
DEG = math.pi / 180.0
#: Sensor noise (rms, bias) of a test vehicle: a MEMS/fibre-optic inertial platform
#: (0.1 deg/s, 0.05 m/s^2 noise at 100 Hz; biases after zeroing 0.3 deg/s, 0.01 g), an optical
#: or GNSS/INS sideslip sensor (0.1 deg, 0.2 deg), the platform's roll (0.05 deg, 0.1 deg) and
#: roll rate, the speed of a wheel-speed or GNSS sensor (0.05 m/s); the steering robot's
#: encoder quantizes the hand-wheel angle at 0.1 deg.
NOISE = {"yaw_rate_radps": (0.1 * DEG, 0.3 * DEG), "lateral_accel_mps2": (0.05, 0.1),
         "sideslip_rad": (0.1 * DEG, 0.2 * DEG), "roll_rad": (0.05 * DEG, 0.1 * DEG),
         "roll_rate_radps": (0.1 * DEG, 0.2 * DEG), "speed_mps": (0.05, 0.0)}
STEER_QUANTUM_RAD = 0.1 * DEG


def _vehicles(tire: str = "linear"):
    """(base, truth): table_8_1 with ``tire`` (linear: the axle cornering stiffnesses are the
    8-DOF's too) and its copy with :data:`MOVED` applied."""
    mapping = load_vehicle("table_8_1").to_dict()
    mapping["tire"]["model"] = tire
    base = vehicle_from_mapping(mapping, "base")
    for path, factor in MOVED.items():
        sub, key = path.split(".")
        mapping[sub][key] *= factor
    return base, vehicle_from_mapping(mapping, "truth")


def _random_steer(length_s: float) -> dict:
    """ISO 7401 random steer (config/maneuvers/random_steer.yaml), shortened."""
    return {"type": "random_steer", "name": "random_steer", "initial_speed_mps": 23.6,
            "duration_s": length_s + 2.0, "steer_input": "road_wheel", "rms_rad": 0.0087,
            "f_low_hz": 0.05, "f_high_hz": 3.0, "length_s": length_s, "seed": 1,
            "start_s": 1.0, "fade_s": 1.0, "sample_rate_hz": 200.0}


def _bag(vehicle, maneuver, model: str, path: Path) -> Path:
    """The twin's run written as a bag; the linear models integrated at the control period
    (RK4 over 10 ms: their fastest mode is 0.05 s)."""
    dt = 1e-3 if model == "8dof" else 1e-2
    res = run_closed_loop(vehicle, maneuver, "fws", model=model, dt_s=dt)
    B.write_run(path, res.time_s, res.outputs, res.config, driver=res.driver, model=model)
    return path


def _true(truth, path: str) -> float:
    sub, key = path.split(".")
    return float(getattr(getattr(truth, sub), key))


@pytest.fixture(scope="module")
def linear_bag(tmp_path_factory) -> Path:
    """12 s of random steer on the 3-DOF model of the moved car."""
    _, truth = _vehicles()
    return _bag(truth, _random_steer(10.0), "3dof", tmp_path_factory.mktemp("id") / "rs3")


def test_linear_level_recovers_moved_parameters(linear_bag) -> None:
    """3-DOF level, noiseless: every moved value within 2 % (found within 0.01 %: the fit's
    zero-order-hold model is exact, the twin's RK4 at 1 ms is not quite)."""
    base, truth = _vehicles()
    result = identify([load_log(linear_bag)], base, level="3dof", fields=[CF, CR, IZ, KPHI])
    assert len(result.values) == 5
    for v in result.values:
        assert v.value == pytest.approx(_true(truth, v.path), rel=0.02), v.path
        assert v.value == pytest.approx(_true(truth, v.path), rel=2e-4), v.path
    assert result.vehicle.roll.roll_damping_front_nms_per_rad \
        == base.roll.roll_damping_front_nms_per_rad


def test_eightdof_level_recovers_moved_parameters(tmp_path) -> None:
    """8-DOF level (linear tire), noiseless, 6 s: the moved values and the unmoved relaxation
    length within 2 %; the model's speed follows the recorded speed through the speed-hold
    driver, so only that small difference to the twin's driver remains."""
    base, truth = _vehicles()
    log = load_log(_bag(truth, _random_steer(4.0), "8dof", tmp_path / "rs8"))
    result = identify([log], base, level="8dof", fields=[CF, CR, IZ, KPHI, SIGMA])
    for v in result.values:
        assert v.value == pytest.approx(_true(truth, v.path), rel=0.02), v.path
    assert {c.channel for c in result.channels} == {
        "yaw_rate_radps", "lateral_accel_mps2", "sideslip_rad", "roll_rad", "roll_rate_radps"}


def _noisy(log: MeasuredLog, seed: int) -> MeasuredLog:
    rng = np.random.default_rng(seed)
    channels = dict(log.channels)
    for name, (rms, bias) in NOISE.items():
        channels[name] = channels[name] + bias + rms * rng.standard_normal(log.time_s.size)
    q = STEER_QUANTUM_RAD
    channels["steering_wheel_angle_rad"] = np.round(channels["steering_wheel_angle_rad"] / q) * q
    return MeasuredLog(log.name, log.source, log.time_s, log.dt_s, channels)


def test_noisy_csv_values_inside_their_intervals(linear_bag, tmp_path) -> None:
    """Realistic noise and bias, written as CSV and read back: every true value inside its 95 %
    interval, each interval within 3 % of the value (the record pins them), and the fitted
    yaw-rate and lateral-acceleration biases equal the added ones within 3 noise rms over
    sqrt(N) (the standard error of a mean)."""
    base, truth = _vehicles()
    csv = write_table(_noisy(load_log(linear_bag), seed=3), tmp_path / "noisy.csv", "csv")
    log = load_log(csv)
    result = identify([log], base, level="3dof", fields=[CF, CR, IZ, KPHI])
    for v in result.values:
        true = _true(truth, v.path)
        assert abs(v.value - true) <= v.ci95, (v.path, v.value, true, v.ci95)
        assert v.relative_ci95 < 0.03, v.path
    n = log.time_s.size
    for c in result.channels:
        if c.channel in ("yaw_rate_radps", "lateral_accel_mps2"):
            rms, bias = NOISE[c.channel]
            assert c.bias == pytest.approx(bias, abs=3.0 * rms / math.sqrt(n) + 0.05 * bias)
            assert c.rms_residual == pytest.approx(rms, rel=0.1)


def _engineer_csv(log: MeasuredLog, path: Path) -> Path:
    """The log as a test engineer's file: comment lines, columns in another order and in the
    units they are logged in (deg, deg/s, km/h), and columns fourws does not read."""
    cols = {"speed_kmh": log.channels["speed_mps"] * 3.6,
            "yaw_rate_degps": log.channels["yaw_rate_radps"] / DEG,
            "time_s": log.time_s,
            "lateral_accel_mps2": log.channels["lateral_accel_mps2"],
            "gps_altitude_m": np.full(log.time_s.size, 512.0),
            "steering_wheel_angle_deg": log.channels["steering_wheel_angle_rad"] / DEG,
            "roll_deg": log.channels["roll_rad"] / DEG}
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# test track log, car 7, run 12\n# units in the column names\n")
        fh.write(",".join(cols) + "\n")
        for row in zip(*cols.values()):
            fh.write(",".join(f"{v:.12g}" for v in row) + "\n")
    return path


def test_engineer_csv_gives_the_bags_answer(linear_bag, tmp_path) -> None:
    """The same run from a CSV in degrees and km/h with extra columns: the same fitted values
    as from the bag's channels (to the CSV's 12 digits), from the same channels."""
    base, _ = _vehicles()
    bag_log = load_log(linear_bag)
    keep = ("steering_wheel_angle_rad", "speed_mps", "yaw_rate_radps", "lateral_accel_mps2",
            "roll_rad")
    bag_log.channels = {k: v for k, v in bag_log.channels.items() if k in keep}
    csv_log = load_log(_engineer_csv(bag_log, tmp_path / "track.csv"))
    assert sorted(csv_log.channels) == sorted(keep)
    assert any("yaw_rate_degps converted" in n for n in csv_log.notes)
    assert any("gps_altitude_m" in n for n in csv_log.notes)
    fields = [CF, CR, IZ, KPHI]
    from_bag = identify([bag_log], base, level="3dof", fields=fields)
    from_csv = identify([csv_log], base, level="3dof", fields=fields)
    for a, b in zip(from_bag.values, from_csv.values):
        assert b.value == pytest.approx(a.value, rel=1e-6), a.path


def test_cli_writes_a_vehicle_file_and_report(linear_bag, tmp_path, capsys) -> None:
    """``fourws identify --out --report``: the vehicle file loads (load_vehicle), holds the
    fitted values and the base's others, comments each fitted value with its interval;
    identification.json has the same values; index.html the tables and plots."""
    out, report = tmp_path / "fitted.yaml", tmp_path / "report"
    base = tmp_path / "base.yaml"
    mapping = load_vehicle("table_8_1").to_dict()
    mapping["tire"]["model"] = "linear"
    base.write_text(json.dumps(mapping))  # JSON is YAML
    code = main(["identify", str(linear_bag), "--vehicle", str(base), "--level", "3dof",
                 "--fit", CF, CR, IZ, KPHI, "--out", str(out), "--report", str(report),
                 "--quiet"])
    stdout = capsys.readouterr().out
    assert code == 0
    fitted = load_vehicle(out)
    data = json.loads((report / "identification.json").read_text())
    values = {v["path"]: v for v in data["values"]}
    for path, v in values.items():
        sub, key = path.split(".")
        assert getattr(getattr(fitted, sub), key) == v["value"]
    assert fitted.chassis.mass_kg == mapping["chassis"]["mass_kg"]
    assert fitted.roll.roll_damping_rear_nms_per_rad \
        == mapping["roll"]["roll_damping_rear_nms_per_rad"]
    text = out.read_text()
    line = next(ln for ln in text.splitlines() if ln.strip().startswith("yaw_inertia_kgm2:"))
    assert "# fitted:" in line and "(95 %)" in line and "rs3" in line
    html = (report / "index.html").read_text()
    assert "Fitted values" in html and "histories_1.png" in html
    assert (report / "histories_1.png").stat().st_size > 10_000
    assert "frequency_response.png" in html  # random steer: broadband
    assert f"{values[IZ]['value']:.6g}" in stdout


def _steady_csv(tmp_path: Path) -> Path:
    """Steady circular driving: the last 2 s of a 10 s step steer on the 3-DOF (the transient
    has died out: yaw-rate change below 0.1 % of its level)."""
    base, _ = _vehicles()
    man = {"type": "step_steer", "name": "steady", "initial_speed_mps": 23.6,
           "duration_s": 10.0, "steer_input": "road_wheel", "amplitude_rad": 0.01,
           "start_s": 0.5, "ramp_time_s": 0.1}
    log = load_log(_bag(base, man, "3dof", tmp_path / "step"))
    keep = log.time_s >= 8.0
    r = log.channels["yaw_rate_radps"][keep]
    assert np.ptp(r) < 1e-3 * abs(np.mean(r))
    steady = MeasuredLog(log.name, log.source, log.time_s[keep], log.dt_s,
                         {k: v[keep] for k, v in log.channels.items()})
    return write_table(steady, tmp_path / "steady.csv", "csv")


def _cli(capsys, *args: str) -> tuple[int, list[str]]:
    """Exit code and stderr lines of ``fourws identify ARGS``."""
    code = main(["identify", *args, "--quiet"])
    return code, capsys.readouterr().err.strip().splitlines()


def test_steady_record_refuses_the_yaw_inertia(tmp_path, capsys) -> None:
    """A steady state does not depend on I_z: asked for it with the cornering stiffnesses
    (sensors taken as zeroed, so the steady levels carry the stiffnesses), the fit is refused
    in one line naming the yaw inertia alone, exit code 2; with biases fitted, a constant
    record pins nothing and every field is named."""
    csv = _steady_csv(tmp_path)
    code, lines = _cli(capsys, str(csv), "--vehicle", "table_8_1", "--level", "3dof",
                       "--no-bias", "--fit", CF, CR, IZ)
    assert code == 2
    assert len(lines) == 1 and "too little excitation" in lines[0]
    named = lines[0].split(": too little excitation")[0]
    assert named == "fourws identify: error: chassis.yaw_inertia_kgm2"
    with pytest.raises(ExcitationError) as exc:
        identify([load_log(csv)], _vehicles()[0], level="3dof", fields=[CF, CR, IZ])
    assert set(exc.value.fields) == {CF, CR, IZ}


def test_degenerate_and_absent_fields_are_named(linear_bag, tmp_path, capsys) -> None:
    """The 3-DOF carries only K_phi,f + K_phi,r (roll3dof): the two fitted apart are refused as
    not to be told apart; a roll field with no roll channel is refused as such; the 8-DOF with
    its STI tire does not read the axle cornering stiffness (a structural refusal with the way
    out, naming it alone: the yaw inertia beside it is pinned)."""
    base, _ = _vehicles()
    log = load_log(linear_bag)
    with pytest.raises(ExcitationError) as exc:
        identify([log], base, level="3dof", fields=["roll.roll_stiffness_front_nm_per_rad",
                                                    "roll.roll_stiffness_rear_nm_per_rad"])
    assert "cannot be told apart from roll.roll_stiffness_rear_nm_per_rad" in str(exc.value)
    no_roll = MeasuredLog(log.name, log.source, log.time_s, log.dt_s,
                          {k: v for k, v in log.channels.items() if not k.startswith("roll")})
    with pytest.raises(ExcitationError) as exc:
        identify([no_roll], base, level="3dof", fields=[CF, KPHI])
    assert exc.value.fields == (KPHI,) and "no roll signal" in str(exc.value)
    short = _bag(load_vehicle("table_8_1"), _random_steer(1.0), "8dof", tmp_path / "sti")
    code, lines = _cli(capsys, str(short), "--vehicle", "table_8_1", "--level", "8dof",
                       "--fit", CR, IZ)
    assert code == 2 and len(lines) == 1
    assert lines[0].startswith(f"fourws identify: error: {CR}: too little excitation")
    assert "does not enter the 8dof model" in lines[0] and "--tire linear" in lines[0]


def test_step_steer_cannot_tell_front_from_rear(tmp_path) -> None:
    """A step steer on the 2-DOF pins C_f, C_r and I_z each (within 3 %, instrument-level
    noise) but C_f and C_r mostly through the steady-state gain, which depends on
    b/C_f - a/C_r: the two are flagged as not to be told apart (|rho| > 0.95; the fit finds
    +0.98), the values are still found."""
    base, truth = _vehicles()
    man = {"type": "step_steer", "name": "step", "initial_speed_mps": 23.6, "duration_s": 5.0,
           "steer_input": "road_wheel", "amplitude_rad": 0.01, "start_s": 0.5,
           "ramp_time_s": 0.1}
    result = identify([load_log(_bag(truth, man, "2dof", tmp_path / "step2"))], base,
                      level="2dof", fields=[CF, CR, IZ])
    assert [(a, b) for a, b, _ in result.indistinguishable] == [(CF, CR)]
    assert result.indistinguishable[0][2] > 0.95
    assert result.correlation[0, 1] == pytest.approx(result.correlation[1, 0])
    assert result.correlation[0, 0] == pytest.approx(1.0)
    for v in result.values:
        assert v.value == pytest.approx(_true(truth, v.path), rel=0.02)


def test_vehicle_file_reloads_every_value(tmp_path) -> None:
    """The written vehicle file, read by load_vehicle, is the fitted vehicle: every subsystem,
    the nested tire coefficients (STI, a TMeasy block) and the unchecked-fields list equal
    (source: the fitted Vehicle's own mapping)."""
    mapping = load_vehicle("table_8_1").to_dict()
    mapping["tire"]["tmeasy"] = {"nominal_load_n": 4000.0, "unloaded_radius_m": 0.3}
    mapping["chassis"]["mass_kg"] = 1.5e5  # a heavy truck beyond the plausible 1e5 kg ...
    mapping["roll"]["sprung_mass_kg"] = 1.2e5
    mapping["unchecked_fields"] = ["chassis.mass_kg", "roll.sprung_mass_kg"]  # ... accepted
    base = vehicle_from_mapping(mapping, "truck")
    man = {"type": "step_steer", "name": "step", "initial_speed_mps": 23.6, "duration_s": 3.0,
           "steer_input": "road_wheel", "amplitude_rad": 0.005, "start_s": 0.5,
           "ramp_time_s": 0.1}
    log = load_log(_bag(base, man, "2dof", tmp_path / "truck"))
    result = identify([log], base, level="2dof", fields=[CR])
    path = tmp_path / "fitted.yaml"
    path.write_text(vehicle_yaml(result))
    loaded = load_vehicle(path).to_dict()
    expected = result.vehicle.to_dict()
    assert loaded.pop("description") == ("table_8_1 fitted on the 2dof level to truck (3.0 s, "
                                         "step_steer)")
    expected.pop("description")
    assert loaded == expected
    assert loaded["tire"]["tmeasy"] == {"nominal_load_n": 4000.0, "unloaded_radius_m": 0.3}
