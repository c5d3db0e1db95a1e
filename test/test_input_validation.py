# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Bad input from files and command lines: one test per class of error.

Every bad input ends in one line naming the field and the file (a
:class:`~fourws_sim.errors.FourwsError` in the core, ``fourws CMD: error: ...`` with exit code
2 on the command line, ``[node] error: ...`` with exit code 2 from a node), never a traceback,
and well-formed but physically absurd values are refused before anything runs. The numbers
asserted come from the YAML 1.2 specification (core schema), the plausibility bounds as
declared next to each field (read back from the declarations, so the test and the code share
one fact), RK4's stability bound, and the files themselves.
"""

from __future__ import annotations

import dataclasses
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from fourws_cli.main import main
from fourws_sim import config_yaml
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers import (MANEUVER_TYPES, MAX_DURATION_S, MAX_PATH_POINTS,
                                  MAX_RANDOM_SAMPLES, MAX_ROAD_WHEEL_ANGLE_RAD,
                                  MAX_STEER_FREQUENCY_HZ, load_maneuver_spec, make_maneuver)
from fourws_sim.params import (MAX_SPEED_MPS, UNCHECKED_KEY, VEHICLE_DIR, available_vehicles,
                               load_vehicle)
from fourws_run.scenario import load_scenario

SHIPPED = Path(VEHICLE_DIR).parent


def _field(cls: type, name: str) -> dataclasses.Field:
    return next(f for f in dataclasses.fields(cls) if f.name == name)


def _bounds(cls: type, name: str) -> tuple[float, float]:
    return _field(cls, name).metadata["bounds"]


def _write(tmp_path: Path, data: dict | str | bytes, name: str = "bad.yaml") -> Path:
    path = tmp_path / name
    if isinstance(data, bytes):
        path.write_bytes(data)
    else:
        path.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    return path


def _refused(loader, path: Path, field: str, *needles: str) -> str:
    """``loader(path)`` raises a one-line ParameterError on ``field`` naming ``path``."""
    with pytest.raises(ParameterError) as info:
        loader(path)
    msg = str(info.value)
    assert info.value.field == field, msg
    assert "\n" not in msg and str(path) in msg
    for needle in needles:
        assert needle in msg, msg
    return msg


def _vehicle(name: str = "table_8_1") -> dict:
    return yaml.safe_load((VEHICLE_DIR / f"{name}.yaml").read_text())


def _maneuver(name: str) -> dict:
    return yaml.safe_load((SHIPPED / "maneuvers" / f"{name}.yaml").read_text())


def _cli(capsys, *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    return code, capsys.readouterr().err


def _one_line_error(code: int, err: str, command: str, *needles: str) -> None:
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith(f"fourws {command}: error: "), err
    assert "Traceback" not in err
    for needle in needles:
        assert needle in lines[0], lines[0]


# ------------------------------------------------------------------------- strict YAML

def test_duplicate_key_named_with_both_lines(tmp_path):
    """YAML forbids duplicate keys (1.2 spec, 3.2.1.1); PyYAML kept the last value."""
    text = (VEHICLE_DIR / "table_5_1.yaml").read_text()
    lines = text.splitlines()
    first = next(i for i, line in enumerate(lines) if line.strip().startswith("mass_kg:"))
    lines.insert(first + 1, "  mass_kg: 1.0")
    path = _write(tmp_path, "\n".join(lines) + "\n")
    _refused(load_vehicle, path, "mass_kg", "duplicate key",
             f"line {first + 2}", f"first at line {first + 1}")


def test_yaml_1_2_numbers_are_floats(tmp_path):
    """YAML 1.2 core schema floats (1e-3, 1E5, 2.0e3, .5) load as the numbers Python reads
    from the same text; quoted, they stay strings; dates are strings."""
    forms = ["1e-3", "1E5", "2.0e3", ".5", "-1.5e-2", "+3e0", "6.02e+23"]
    text = "\n".join(f"k{i}: {f}" for i, f in enumerate(forms)) + "\nq: '1e-3'\nd: 2024-01-01\n"
    data = config_yaml.parse_yaml(text)
    assert [data[f"k{i}"] for i in range(len(forms))] == [float(f) for f in forms]
    assert data["q"] == "1e-3" and data["d"] == "2024-01-01"
    # a vehicle written with exponents loads the numbers of the shipped file
    body = (VEHICLE_DIR / "table_5_1.yaml").read_text()
    body = body.replace("mass_kg: 1298.9", "mass_kg: 1.2989e3")
    body = body.replace("relaxation_length_m: 0.414", "relaxation_length_m: 414e-3")
    v = load_vehicle(_write(tmp_path, body))
    assert v.chassis.mass_kg == 1298.9 and v.tire.relaxation_length_front_m == 0.414


def test_shipped_files_load_as_plain_yaml_1_1_reads_them():
    """Every shipped config file gives the strict reader exactly what PyYAML's safe_load
    gives (they use no form where YAML 1.1 and 1.2 differ): the paper's vehicles load
    unchanged."""
    files = sorted(SHIPPED.glob("*/*.yaml"))
    assert len(files) >= 20
    for path in files:
        assert config_yaml.read_yaml(path) == yaml.safe_load(path.read_text()), path


def test_alias_bomb_refused(tmp_path):
    """Nine nested anchors of nine aliases each ("billion laughs", 9^9 strings) in a file of
    under 1.5 kB: refused at the expansion bound, not expanded."""
    text = 'name: x\nl0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]\n'
    for k in range(1, 9):
        text += f"l{k}: &l{k} [" + ", ".join([f"*l{k - 1}"] * 9) + "]\n"
    assert len(text) < 1500
    path = _write(tmp_path, text)
    _refused(config_yaml.read_yaml, path, "<file>",
             f"more than {config_yaml.MAX_NODES} values once aliases are expanded")
    # a few aliases that share a value are fine: each use is the same number
    ok = config_yaml.parse_yaml("a: &u 23.6\nb: *u\nc: [*u, *u]\n")
    assert ok == {"a": 23.6, "b": 23.6, "c": [23.6, 23.6]}
    with pytest.raises(ParameterError, match="recursive alias"):
        config_yaml.parse_yaml("a: &a [1, *a]\n")
    with pytest.raises(ParameterError, match="aliases"):
        config_yaml.parse_yaml("a: &a 1\nb: [" + ", ".join(["*a"] * 101) + "]\n")


@pytest.mark.parametrize("kind", ["binary", "utf16", "latin1", "nul"])
def test_not_utf8_text_is_one_line(tmp_path, kind):
    """Binary, UTF-16, Latin-1 and NUL-carrying files: one line naming the file (was a
    UnicodeDecodeError traceback)."""
    text = (VEHICLE_DIR / "table_5_1.yaml").read_text()
    data = {"binary": b"\x89PNG\r\n\x1a\n" + bytes(range(256)),
            "utf16": text.encode("utf-16"),
            "latin1": ("# r\u00e9glage\n" + text).encode("latin-1"),
            "nul": text.encode()[:100] + b"\x00" + text.encode()[100:]}[kind]
    _refused(load_vehicle, _write(tmp_path, data), "<file>")


def test_utf8_byte_order_mark_accepted(tmp_path):
    text = (VEHICLE_DIR / "table_5_1.yaml").read_text()
    path = _write(tmp_path, "\ufeff".encode() + text.encode())
    assert load_vehicle(path).to_dict() == load_vehicle("table_5_1").to_dict()


def test_size_depth_and_key_limits(tmp_path):
    big = "name: x\n" + "#" * config_yaml.MAX_FILE_BYTES + "\n"
    _refused(config_yaml.read_yaml, _write(tmp_path, big), "<file>",
             f"larger than {config_yaml.MAX_FILE_BYTES} bytes")
    deep = "a: " + "[" * (config_yaml.MAX_DEPTH + 1) + "]" * (config_yaml.MAX_DEPTH + 1)
    _refused(config_yaml.read_yaml, _write(tmp_path, deep), "<file>",
             f"deeper than {config_yaml.MAX_DEPTH} levels")
    _refused(config_yaml.read_yaml, _write(tmp_path, "name: x\n1: y\n"), "<file>",
             "key '1' is not a string", "line 2")
    # a device that never ends is read only up to the bound
    with pytest.raises(ParameterError, match="larger than"):
        config_yaml.read_yaml("/dev/zero")


def test_invalid_yaml_is_one_line_with_position(tmp_path):
    path = _write(tmp_path, "name: x\nchassis: {mass_kg: 1\n  yaw: [\n")
    msg = _refused(load_vehicle, path, "<file>", "not valid YAML", "line ")
    assert "column" in msg


@pytest.mark.parametrize("key", ["chassis", "axle_tires"])
def test_null_required_subsystem(tmp_path, key):
    data = _vehicle("table_5_1")
    data[key] = None
    _refused(load_vehicle, _write(tmp_path, data), key, "null")


def test_null_optional_subsystem_is_absent(tmp_path):
    data = _vehicle("table_8_1")
    data["roll"] = None
    v = load_vehicle(_write(tmp_path, data))
    assert v.roll is None and v.chassis == load_vehicle("table_8_1").chassis


@pytest.mark.parametrize("key,value", [("description", ["a", "list"]), ("name", 7),
                                       ("tire", "sti")])
def test_wrong_type_is_one_line(tmp_path, key, value):
    data = _vehicle("table_8_1")
    data[key] = value
    _refused(load_vehicle, _write(tmp_path, data), key)


TOOLS_WITH_A_VEHICLE = [
    ("linear", "--model", "3dof", "--law", "sol1", "--speed-kmh", "85"),
    ("handling", "--law", "sol1"),
    ("lqr-gains", "--model", "2dof"),
    ("equilibria", "--speed-mps", "20"),
    ("tire-curves",),
]


@pytest.mark.parametrize("group, key, valid", [
    ("sti", "bogus_key", "(valid: a0, a1, a2, a3, a4, b1, b3, b4, c1, c2, c3, c4, cs_per_fz, "
                         "fzt_lb, g1, g2, k1, ka, kmu, snt, tp_psi, tw_in)"),
    ("magic_formula", "PKY9", "(valid: FNOMIN, R0, "),
], ids=["sti", "magic_formula"])
def test_unknown_tire_coefficient_is_refused_by_every_tool(tmp_path, capsys, group, key,
                                                           valid):
    """An unknown key of the vehicle's tire coefficients (a typo the tire would have run
    without) was accepted by ``fourws linear`` and ``handling`` and refused by ``fourws run``
    only once its simulator node started, with exit code 1: the vehicle loader refuses it,
    so every tool (and a scenario naming the vehicle) ends with exit code 2 and the same one
    line naming the key, the valid names (Table C.1's 22 STI coefficients) and the file."""
    from fourws_sim.tires import sti

    assert len(sti.TABLE_C1) == 22
    data = _vehicle("table_8_1")
    data["tire"].setdefault(group, {})[key] = 1.0
    path = _write(tmp_path, data, "bad_tire.yaml")
    _refused(load_vehicle, path, f"tire.{group}.{key}", valid)
    scenario = _write(tmp_path, {**yaml.safe_load((SHIPPED / "scenarios" / "default.yaml")
                                                  .read_text()), "vehicle": str(path)},
                      "scenario.yaml")
    for command, *rest in [*TOOLS_WITH_A_VEHICLE, ("run",)]:
        argv = [command, str(scenario), "--out", str(tmp_path / "runs")] \
            if command == "run" else [command, "--vehicle", str(path), *rest]
        code, err = _cli(capsys, *argv)
        _one_line_error(code, err, command, f"tire.{group}.{key}: unknown", valid, str(path))
    assert not (tmp_path / "runs").exists()


# ---------------------------------------------------------------- plausibility: vehicles

ABSURD_VEHICLE = [  # issue 9's list
    ("chassis", "mass_kg", 1e300),
    ("tire", "friction_coefficient", 1e9),
    ("body", "wheel_radius_m", 1e-9),
    ("body", "cg_height_m", 1000.0),
    ("body", "wheel_spin_inertia_kgm2", 1e-12),
]


@pytest.mark.parametrize("sub,name,value", ABSURD_VEHICLE)
def test_absurd_vehicle_value_refused_with_its_bounds(tmp_path, sub, name, value):
    from fourws_sim import params

    cls = params._SUBSYSTEMS[sub]
    low, high = _bounds(cls, name)
    assert not low <= value <= high
    data = _vehicle("table_8_1")
    data[sub][name] = value
    _refused(load_vehicle, _write(tmp_path, data), f"{sub}.{name}",
             f"plausible range [{low:g}, {high:g}]", UNCHECKED_KEY)


def test_unchecked_fields_lift_a_bound_and_round_trip(tmp_path):
    """A 250-t mining truck is beyond the 100-t bound: listing the field accepts it (and the
    list travels with the vehicle into a run record); sign checks still apply."""
    data = _vehicle("table_5_1")
    data["chassis"]["mass_kg"] = 2.5e5
    data["chassis"]["yaw_inertia_kgm2"] = 1.5e6
    path = _write(tmp_path, data)
    _refused(load_vehicle, path, "chassis.mass_kg", "plausible range")
    data[UNCHECKED_KEY] = ["chassis.mass_kg"]
    v = load_vehicle(_write(tmp_path, data))
    assert v.chassis.mass_kg == 2.5e5
    assert v.to_dict()[UNCHECKED_KEY] == ["chassis.mass_kg"]
    from fourws_sim.params import vehicle_from_mapping
    assert vehicle_from_mapping(v.to_dict()).to_dict() == v.to_dict()
    data["chassis"]["mass_kg"] = -1.0
    _refused(load_vehicle, _write(tmp_path, data), "chassis.mass_kg", "must be > 0")
    data["chassis"]["mass_kg"] = 2.5e5
    data[UNCHECKED_KEY] = ["chassis.mass_lb"]
    _refused(load_vehicle, _write(tmp_path, data), UNCHECKED_KEY, "chassis.mass_lb")


def test_every_number_field_declares_its_bounds():
    """Each number field of every vehicle subsystem, maneuver type and driver has its
    plausibility range declared next to it, and every shipped file lies inside."""
    from fourws_sim import drivers, params

    classes = [*params._SUBSYSTEMS.values(), params.TMeasy, *MANEUVER_TYPES.values(),
               drivers.SpeedHoldSpec,
               drivers.PathDriverSpec, drivers.TrackingDriverSpec]
    checked = 0
    for cls in classes:
        for f in dataclasses.fields(cls):
            if "check" in f.metadata:
                low, high = f.metadata["bounds"]
                assert low <= high, (cls.__name__, f.name)
                checked += 1
    assert checked > 100
    for name in available_vehicles():
        assert not load_vehicle(name).unchecked_fields


def test_scale_car_and_heavy_truck_are_plausible(tmp_path):
    """The bounds span a 1:10 scale car (3 kg, 5 cm wheels, I_w 1e-4 kg m^2) and a 40-t
    truck; the loaded values are the file's and the understeer gradient the analytic
    m/L (b/Cf - a/Cr)."""
    cars = {
        "scale": {"chassis": {"mass_kg": 3.0, "yaw_inertia_kgm2": 0.05,
                              "cg_to_front_axle_m": 0.15, "cg_to_rear_axle_m": 0.18},
                  "axle_tires": {"cornering_stiffness_front_n_per_rad": 60.0,
                                 "cornering_stiffness_rear_n_per_rad": 70.0},
                  "body": {"track_front_m": 0.25, "track_rear_m": 0.25, "cg_height_m": 0.06,
                           "roll_centre_height_front_m": 0.02,
                           "roll_centre_height_rear_m": 0.02, "unsprung_cg_height_m": 0.05,
                           "wheel_radius_m": 0.05, "wheel_spin_inertia_kgm2": 1e-4}},
        "truck": {"chassis": {"mass_kg": 40000.0, "yaw_inertia_kgm2": 4.5e5,
                              "cg_to_front_axle_m": 3.0, "cg_to_rear_axle_m": 2.5},
                  "axle_tires": {"cornering_stiffness_front_n_per_rad": 5e5,
                                 "cornering_stiffness_rear_n_per_rad": 1.2e6},
                  "steering": {"ratio": 25.0}},
    }
    for name, data in cars.items():
        v = load_vehicle(_write(tmp_path, {"name": name, **data}, f"{name}.yaml"))
        c, t = data["chassis"], data["axle_tires"]
        length = c["cg_to_front_axle_m"] + c["cg_to_rear_axle_m"]
        k_us = c["mass_kg"] / length * (
            c["cg_to_rear_axle_m"] / t["cornering_stiffness_front_n_per_rad"]
            - c["cg_to_front_axle_m"] / t["cornering_stiffness_rear_n_per_rad"])
        assert v.understeer_gradient_rad_per_mps2 == pytest.approx(k_us, rel=1e-12)


def test_sprung_mass_above_total_mass_refused(tmp_path):
    data = _vehicle("table_8_1")
    data["roll"]["sprung_mass_kg"] = data["chassis"]["mass_kg"] * 1.01
    _refused(load_vehicle, _write(tmp_path, data), "roll.sprung_mass_kg", "exceeds")


# --------------------------------------------------------------- plausibility: maneuvers

def test_steer_amplitude_bounds(tmp_path):
    data = _maneuver("step_steer_85kmh")
    data["amplitude_rad"] = 1e300
    _refused(load_maneuver_spec, _write(tmp_path, data), "amplitude_rad", "plausible")
    data["amplitude_rad"] = 1.2 * MAX_ROAD_WHEEL_ANGLE_RAD  # road-wheel input
    _refused(load_maneuver_spec, _write(tmp_path, data), "amplitude_rad",
             f"plausible {MAX_ROAD_WHEEL_ANGLE_RAD:g} rad")
    # a hand-wheel angle: plausible as such, but on table_8_1 (ratio 16.3) 18 rad is 1.10 rad
    # at the road wheels
    data.update(steer_input="steering_wheel", amplitude_rad=18.0)
    spec = load_maneuver_spec(_write(tmp_path, data))
    car = load_vehicle("table_8_1")
    with pytest.raises(ParameterError, match=f"{18.0 / car.steering.ratio:.4g} rad"):
        make_maneuver(spec, car)
    data["amplitude_rad"] = 3.14  # the slow ramp's half turn: 0.19 rad at the road wheels
    make_maneuver(load_maneuver_spec(_write(tmp_path, data)), car)


def test_frequency_bounds_and_control_rate_nyquist(tmp_path):
    """A 1 MHz sine is refused by the maneuver bound; below it, the scenario refuses a sine
    at or above the control rate's Nyquist frequency 1/(2 Tc) (hard: unchecked_fields does
    not lift it) and accepts one just below."""
    data = _maneuver("sine")
    data["frequency_hz"] = 1e6
    _refused(load_maneuver_spec, _write(tmp_path, data), "frequency_hz",
             f"[0.001, {MAX_STEER_FREQUENCY_HZ:g}]")
    scenario = yaml.safe_load((SHIPPED / "scenarios" / "default.yaml").read_text())
    scenario["control_period_s"] = 0.05  # 20 Hz control: Nyquist 10 Hz
    scenario["state_period_s"] = 0.05
    for f_hz, ok in ((10.0, False), (9.9, True)):
        data.update(frequency_hz=f_hz, start_s=0.5, duration_s=2.0)
        scenario["maneuver"] = data
        path = _write(tmp_path, scenario, "scenario.yaml")
        if ok:
            assert load_scenario(path).maneuver.params.frequency_hz == f_hz
        else:
            _refused(load_scenario, path, "maneuver.frequency_hz", "Nyquist frequency 10 Hz")
    data["frequency_hz"] = 60.0  # beyond the 20 Hz bound, lifted; above 100 Hz's Nyquist
    data[UNCHECKED_KEY] = ["frequency_hz"]
    scenario.update(control_period_s=0.01, state_period_s=0.01, maneuver=data)
    _refused(load_scenario, _write(tmp_path, scenario, "scenario.yaml"),
             "maneuver.frequency_hz", "Nyquist frequency 50 Hz")


def test_duration_grid_and_sample_limits(tmp_path):
    data = _maneuver("step_steer_85kmh")
    data["duration_s"] = 1e9
    _refused(load_maneuver_spec, _write(tmp_path, data), "duration_s", f"{MAX_DURATION_S:g}")
    data["duration_s"] = 5.0
    data["start_s"] = 6.0  # after the end: the step would never be applied
    _refused(load_maneuver_spec, _write(tmp_path, data), "start_s", "never be applied")
    dlc = _maneuver("double_lane_change")
    dlc["path_step_m"] = 1e-5
    _refused(load_maneuver_spec, _write(tmp_path, dlc), "path_step_m", "plausible")
    dlc[UNCHECKED_KEY] = ["path_step_m"]  # the grid limit is hard
    points = (dlc["approach_m"] + 61.0 + dlc["path_runout_m"]) / 1e-5
    _refused(load_maneuver_spec, _write(tmp_path, dlc), "path_step_m",
             f"{points:.3g} points", str(MAX_PATH_POINTS))
    rnd = _maneuver("random_steer")
    rnd.update(length_s=3000.0, sample_rate_hz=5000.0, duration_s=3001.0)
    _refused(load_maneuver_spec, _write(tmp_path, rnd), "length_s",
             f"{3000.0 * 5000.0:.3g} samples", str(MAX_RANDOM_SAMPLES))
    speedy = _maneuver("step_steer_85kmh")
    speedy["initial_speed_mps"] = 1e6
    _refused(load_maneuver_spec, _write(tmp_path, speedy), "initial_speed_mps",
             f"{MAX_SPEED_MPS:g}")


def test_scenario_step_count_limit(tmp_path):
    scenario = yaml.safe_load((SHIPPED / "scenarios" / "default.yaml").read_text())
    man = _maneuver("step_steer_85kmh")
    man["duration_s"] = 3000.0
    scenario.update(maneuver=man, integration_step_s=1e-5, control_period_s=1e-4,
                    state_period_s=1e-4)
    from fourws_run.scenario import MAX_RUN_STEPS
    _refused(load_scenario, _write(tmp_path, scenario), "maneuver.duration_s",
             f"{3000.0 / 1e-5:.3g} integration steps", str(MAX_RUN_STEPS))


# ------------------------------------------------------------------------- command line

@pytest.mark.parametrize("speed", ["1e6", "0", "-85", "nan", "inf"])
def test_linear_speed_bounds(capsys, speed):
    code, err = _cli(capsys, "linear", "--vehicle", "table_4_4", "--model", "2dof", "--law",
                     "sol1", f"--speed-kmh={speed}")
    _one_line_error(code, err, "linear", "--speed-kmh", f"{MAX_SPEED_MPS * 3.6:g}] km/h")


def test_unwritable_outputs_are_one_line(capsys, tmp_path):
    """A plot path under a regular file (ENOTDIR, whatever the user's rights: tests may run as
    root, for whom a read-only folder is writable) and a full disk (a .png link to /dev/full,
    ENOSPC)."""
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    base = ["linear", "--vehicle", "table_4_4", "--model", "2dof", "--law", "sol1",
            "--speed-kmh", "60"]
    code, err = _cli(capsys, *base, "--bode-plot", str(blocker / "bode.png"))
    _one_line_error(code, err, "linear", str(blocker / "bode.png"), "Not a directory")
    if os.path.exists("/dev/full"):
        full = tmp_path / "full.png"
        full.symlink_to("/dev/full")
        code, err = _cli(capsys, *base, "--bode-plot", str(full))
        _one_line_error(code, err, "linear", "No space left on device", str(full))
    code, err = _cli(capsys, "tire-curves", "--vehicle", "table_8_1", "--png",
                     str(blocker / "c.png"))
    _one_line_error(code, err, "tire-curves", "Not a directory")


@pytest.fixture(scope="module")
def small_bag(tmp_path_factory) -> Path:
    """A recorded-like bag of 200 states at 10 ms (2 s)."""
    from fourws_analysis import bag as B

    path = tmp_path_factory.mktemp("bag") / "run"
    store = B.typestore()
    mt = B.TOPIC_TYPES[B.TOPIC_STATE]
    with B.BagWriter(path) as bag:
        bag.write_run_config({"maneuver": {"type": "step_steer"}, "law": "fws"})
        for i in range(200):
            t = 0.01 * i
            msg = B.make_message(mt, header={"stamp": B.stamp(t), "frame_id": "base_link"},
                                 step=i, model="2dof", yaw_rate_radps=math.sin(t))
            bag.write_raw(B.TOPIC_STATE, store.serialize_cdr(msg, mt), int(t * 1e9) + 1000)
    return path


@pytest.mark.parametrize("where,factor,ok", [("low", 1e-5, False), ("low", 0.99, False),
                                             ("low", 1.01, True), ("high", 0.99, True),
                                             ("high", 1.01, False), ("high", 1e6, False)])
def test_resampling_step_bounds(small_bag, where, factor, ok):
    """dt within [state period / MAX_UPSAMPLING, span / (MIN_RESAMPLED_POINTS - 1)], with the
    period and span of the bag's stamps (10 ms over 1.99 s)."""
    from fourws_analysis import bag as B

    run = B.load_bag(small_bag)
    t = run.topics[B.TOPIC_STATE].time_s
    bounds = {"low": float(np.median(np.diff(t))) / B.MAX_UPSAMPLING,
              "high": float(t[-1] - t[0]) / (B.MIN_RESAMPLED_POINTS - 1)}
    dt = bounds[where] * factor
    if ok:
        uni = B.resample(run, dt)
        assert uni.time_s.size == int(math.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    else:
        with pytest.raises(ParameterError, match="dt_s.*outside"):
            B.resample(run, dt)


_WRITER = """
import signal, sys
from fourws_analysis import bag as B
store = B.typestore()
mt = B.TOPIC_TYPES[B.TOPIC_STATE]
writer = B.BagWriter(sys.argv[1]).open()
for i in range(50):
    msg = B.make_message(mt, header={"stamp": B.stamp(0.01 * i)}, step=i, model="2dof")
    writer.write_raw(B.TOPIC_STATE, store.serialize_cdr(msg, mt), 10_000_000 * i)
writer.flush()
print("recording", flush=True)
sys.stdin.readline()
writer.close()
print("closed", flush=True)
sys.stdin.readline()
"""


def _writer_process(bag: Path) -> subprocess.Popen:
    proc = subprocess.Popen([sys.executable, "-c", _WRITER, str(bag)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline() == "recording\n"
    return proc


def test_bag_being_recorded_is_not_repaired_or_verified(capsys, tmp_path):
    """A bag whose writer is alive (it holds the flock of the bag's lock file): ``fourws bag
    repair`` rewrote its file under the writer, it now refuses, as ``verify`` does, exit 2
    and one line naming the bag and the writer's process; the file is untouched. Once the
    writer closed the bag, its lock file is gone and verify reads it (50 states)."""
    from fourws_run.bagfile import LOCK_FILE

    bag = tmp_path / "live"
    proc = _writer_process(bag)
    try:
        mcap = bag / "live.mcap"
        before = mcap.read_bytes()
        for action in ("repair", "verify"):
            code, err = _cli(capsys, "bag", action, str(bag))
            _one_line_error(code, err, "bag", f"bag {str(bag)!r} is being recorded (process "
                            f"{proc.pid} holds {LOCK_FILE}); wait until its recording has "
                            "ended")
        assert mcap.read_bytes() == before and sorted(p.name for p in bag.iterdir()) == [
            LOCK_FILE, "live.mcap"]
        proc.stdin.write("\n")
        proc.stdin.flush()
        assert proc.stdout.readline() == "closed\n"
        assert not (bag / LOCK_FILE).exists()
        code = main(["bag", "verify", str(bag)])
        out = capsys.readouterr().out
        assert code == 1, out  # the verdict on a bag that carries no recording accounting
        assert out == f"{bag}: readable, checksums ok, completeness unknown (the bag " \
            "carries no recording accounting)\n", out
    finally:
        proc.kill()
        proc.wait()


def test_bag_of_a_killed_writer_is_repaired_and_loses_its_stale_lock(capsys, tmp_path):
    """SIGKILL releases the writer's flock (the kernel closes its files): the lock file left
    in the folder does not stop ``repair``, which recovers the 50 flushed states and removes
    it."""
    from fourws_run.bagfile import LOCK_FILE

    bag = tmp_path / "killed"
    proc = _writer_process(bag)
    proc.kill()
    proc.wait()
    assert (bag / LOCK_FILE).exists()
    code = main(["bag", "repair", str(bag)])
    out = capsys.readouterr().out
    assert code == 1, out  # repaired: a bag without final status counts is incomplete
    assert f"{bag}: repaired; recovered 50 messages (/fourws/state 50)" in out, out
    assert not (bag / LOCK_FILE).exists()


@pytest.mark.parametrize("dt", ["1e-9", "1e6", "nan", "-1"])
def test_analyze_dt_bounds_one_line(capsys, small_bag, dt):
    code, err = _cli(capsys, "analyze", str(small_bag), "--quiet", "--no-sweep", f"--dt={dt}")
    _one_line_error(code, err, "analyze")


@pytest.mark.parametrize("cut", [0, 8, 9, 100])
def test_truncated_bag_one_line(capsys, small_bag, tmp_path, cut):
    import shutil

    bag = tmp_path / "cut"
    shutil.copytree(small_bag, bag)
    mcap = next(bag.glob("*.mcap"))
    mcap.write_bytes(mcap.read_bytes()[:cut])
    code, err = _cli(capsys, "analyze", str(bag), "--quiet", "--no-sweep")
    _one_line_error(code, err, "analyze", "truncated or corrupt", str(bag))


@pytest.mark.parametrize("damage", ["count", "binary", "custom", "cut"])
def test_damaged_bag_metadata_one_line(capsys, small_bag, tmp_path, damage):
    """A metadata.yaml that is not what rosbag2 writes (a count that is not a number, binary,
    custom_data not a mapping, cut short): the bag is damaged, one line (was a KeyError,
    TypeError or ValueError traceback)."""
    import shutil

    bag = tmp_path / "bag"
    shutil.copytree(small_bag, bag)
    meta = bag / "metadata.yaml"
    text = meta.read_text()
    assert "message_count: 200" in text and "custom_data:" in text
    meta.write_bytes({"count": text.replace("message_count: 200", "message_count: abc").encode(),
                      "binary": bytes(range(256)),
                      "custom": text.replace("custom_data:", "custom_data: [1, 2]\nx_data:")
                      .encode(),
                      "cut": text.encode()[:text.index("topic_metadata") + 20]}[damage])
    code, err = _cli(capsys, "analyze", str(bag), "--quiet", "--no-sweep")
    _one_line_error(code, err, "analyze", str(bag))


def test_report_folder_unwritable_one_line(capsys, small_bag, tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    code, err = _cli(capsys, "analyze", str(small_bag), "--quiet", "--no-sweep", "--report",
                     str(blocker / "report"))
    _one_line_error(code, err, "analyze", "Not a directory")


@pytest.mark.parametrize("domain, needle", [
    ("300", "ROS_DOMAIN_ID='300' is not a ROS domain ID (0..232)"),
    ("-1", "ROS_DOMAIN_ID='-1' is not a ROS domain ID (0..232)"),
    ("busy", "(from ROS_DOMAIN_ID) is used by another fourws run on this machine"),
], ids=["300", "negative", "busy"])
@pytest.mark.parametrize("command", ["run", "demo"])
def test_unusable_ros_domain_is_bad_input_before_anything_is_created(
        capsys, monkeypatch, tmp_path, domain, needle, command):
    """``ROS_DOMAIN_ID=300`` (above ROS 2's 232 on Linux) left a FAILED run folder and exit
    code 1: the environment is checked as domain_for_run checks it (the same function),
    before the output folder exists; a domain another fourws run holds (here this test's
    own lease) likewise."""
    from fourws_ros.domains import reserve_domain_id

    lease = reserve_domain_id() if domain == "busy" else None
    try:
        monkeypatch.setenv("ROS_DOMAIN_ID", str(lease.domain_id) if lease else domain)
        code, err = _cli(capsys, command, "--out", str(tmp_path / "runs"))
    finally:
        if lease is not None:
            lease.release()
    _one_line_error(code, err, command, needle)
    assert not (tmp_path / "runs").exists()


def test_a_law_given_twice_is_refused(capsys, tmp_path):
    """``--law fws --law fws`` ran fws twice (two run folders of one law), and so did a
    scenario listing it twice: one line each, exit 2, before anything runs."""
    code, err = _cli(capsys, "run", "--law", "fws", "--law", "sol1", "--law", "fws", "--out",
                     str(tmp_path / "runs"))
    _one_line_error(code, err, "run", "--law: 'fws' is given 2 times; each law runs once")
    data = yaml.safe_load((SHIPPED / "scenarios" / "default.yaml").read_text())
    data["laws"] = ["sol1", "sol1", "fws", "sol1"]
    path = _write(tmp_path, data, "twice.yaml")
    _refused(load_scenario, path, "laws", "'sol1' is listed 3 times; each law runs once")
    code, err = _cli(capsys, "run", str(path), "--out", str(tmp_path / "runs"))
    _one_line_error(code, err, "run", "laws: 'sol1' is listed 3 times", str(path))
    assert not (tmp_path / "runs").exists()


# ---------------------------------------------------------------------------------- nodes

def _node(name: str, *ros_args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "fourws_cli.main", "node", name, "--ros-args",
                           *ros_args], capture_output=True, text=True, errors="replace",
                          timeout=120, env=dict(os.environ))


@pytest.mark.usefixtures("ros_domain")
def test_node_params_file_missing_binary_or_duplicate(tmp_path):
    """A --params-file that is missing, binary (was an RCLError traceback) or has a key twice
    (rcl keeps the last one without a word): exit 2 and one error line naming the file (and
    the key), before rcl reads it."""
    binary = _write(tmp_path, b"\x89PNG\r\n\x1a\n" + bytes(range(256)), "params.yaml")
    twice = _write(tmp_path, "fourws_controller:\n  ros__parameters:\n    law: sol1\n"
                             "    law: fws\n", "twice.yaml")
    for path, needle in ((tmp_path / "missing.yaml", "cannot be read"),
                         (binary, "not a text file"), (twice, "law: duplicate key at line 4")):
        res = _node("controller", "--params-file", str(path))
        ours = [line for line in res.stderr.splitlines() if line.startswith("[fourws_")]
        assert res.returncode == 2, res.stderr
        assert "Traceback" not in res.stderr
        assert len(ours) == 1 and str(path) in ours[0] and needle in ours[0], ours


PARAMS = SHIPPED / "params" / "lockstep.yaml"


@pytest.mark.usefixtures("ros_domain")
def test_node_params_file_unknown_parameter_empty_or_without_section(tmp_path):
    """rclpy ignores a file's parameters a node does not declare, and starts a node on an
    empty file or one with no section for it: the simulator ran on with defaults. Each is
    exit 2 and one error line naming the parameter (or the sections) and the file; other
    nodes' sections of a shared file are not the simulator's business (the shipped file
    holds four, and the misspelt key below sits in the simulator's own)."""
    text = PARAMS.read_text()
    assert text.count("    integrator: rk4\n") == 1
    typo = _write(tmp_path, text.replace("    integrator: rk4\n", "    integrater: rk4\n"),
                  "typo.yaml")
    empty = _write(tmp_path, "# nothing here\n", "empty.yaml")
    other = _write(tmp_path, "fourws_controller:\n  ros__parameters:\n    law: fws\n"
                             "/**/fourws_maneuver:\n  ros__parameters:\n    vehicle: x\n",
                   "other.yaml")
    for path, needle in (
            (typo, "integrater: not a parameter of node /fourws_simulator (under "
                   "'fourws_simulator'; valid: answer_timeout_s, autostart, clock_mode, "),
            (empty, "<file>: is empty or not a ROS 2 parameter file"),
            (other, "<file>: has no section for node /fourws_simulator (its sections: "
                    "fourws_controller, /**/fourws_maneuver; /** is read by every node)")):
        res = _node("simulator", "--params-file", str(path))
        ours = [line for line in res.stderr.splitlines() if line.startswith("[fourws_")]
        assert res.returncode == 2, res.stderr
        assert "Traceback" not in res.stderr
        assert len(ours) == 1 and ours[0].startswith("[fourws_simulator] error: ") \
            and needle in ours[0] and ours[0].endswith(f" in {path}"), ours


@pytest.mark.usefixtures("ros_domain")
def test_node_params_file_wildcard_sections_still_work(tmp_path):
    """The sections rcl applies by wildcard (``/**`` every node, ``/**/NAME`` a node in any
    namespace) are this node's: the controller's shipped parameters under either start it
    (as does the shipped file, whose other sections belong to the other nodes)."""
    from config_mutation import classify_node

    own = yaml.safe_load(PARAMS.read_text())["fourws_controller"]
    for key in ("/**", "/**/fourws_controller"):
        path = _write(tmp_path, {key: own}, "wildcard.yaml")
        assert classify_node("controller", path, dict(os.environ), 60.0) == ("ok", ""), key
    assert classify_node("controller", PARAMS, dict(os.environ), 60.0) == ("ok", "")
    typo = _write(tmp_path, {"/**": {"ros__parameters": {**own["ros__parameters"],
                                                         "belief_scale_frnt": 1.0}}},
                  "wildcard_typo.yaml")
    res = _node("controller", "--params-file", str(typo))
    ours = [line for line in res.stderr.splitlines() if line.startswith("[fourws_")]
    assert res.returncode == 2 and len(ours) == 1, res.stderr
    assert "belief_scale_frnt: not a parameter of node /fourws_controller (under '/**'; " \
        "valid: " in ours[0], ours


@pytest.mark.parametrize("section, node, applies", [
    ("/**", "/fourws_simulator", True), ("/**", "/ns/deep/fourws_simulator", True),
    ("fourws_simulator", "/fourws_simulator", True),
    ("/fourws_simulator", "/fourws_simulator", True),
    ("/**/fourws_simulator", "/ns/fourws_simulator", True),
    ("/**/fourws_simulator", "/fourws_simulator", True),
    ("/*", "/fourws_simulator", True), ("/*", "/ns/fourws_simulator", False),
    ("/ns/*", "/ns/fourws_simulator", True), ("fourws_simulator", "/ns/fourws_simulator", False),
    ("fourws_controller", "/fourws_simulator", False), ("/fourws", "/fourws_simulator", False),
])
def test_params_file_sections_match_as_rcl_matches_them(section, node, applies):
    """ROS 2 design article "ROS command line arguments": ``*`` matches one token between
    slashes, ``**`` zero or more, no partial matches; a name without a leading slash is from
    the root namespace."""
    from fourws_ros.runtime import _section_matches

    assert _section_matches(section, node) is applies


@pytest.mark.usefixtures("ros_domain")
def test_live_belief_vehicle_binary_or_utf16_is_rejected(tmp_path):
    """A live ``belief_vehicle`` naming a binary or UTF-16 file is refused by the controller's
    on-set callback (a FourwsError) and the running law is kept: same gains as before."""
    import rclpy
    from rclpy.context import Context
    from rclpy.parameter import Parameter

    from fourws_ros.controller_node import ControllerNode

    ctx = Context()
    rclpy.init(args=[], context=ctx)
    original = rclpy.node.Node.__init__

    def init(self, name, **kwargs):
        kwargs.setdefault("context", ctx)
        original(self, name, **kwargs)

    rclpy.node.Node.__init__ = init
    try:
        node = ControllerNode()
    finally:
        rclpy.node.Node.__init__ = original
    try:
        gains = np.array(node.law.gains(23.6))
        text = (VEHICLE_DIR / "table_5_1.yaml").read_text()
        for name, data in (("bin.yaml", bytes(range(256))), ("u16.yaml", text.encode("utf-16"))):
            path = _write(tmp_path, data, name)
            res = node.set_parameters([Parameter("belief_vehicle", value=str(path))])[0]
            assert not res.successful and str(path) in res.reason
            assert node.get_parameter("belief_vehicle").value == ""
            np.testing.assert_array_equal(node.law.gains(23.6), gains)
    finally:
        node.destroy_node()
        ctx.try_shutdown()


@pytest.mark.parametrize("component,value", [("V", 1e150), ("PHI", 1e200)])
def test_diverging_8dof_state_is_a_non_finite_error(component, value):
    """A state that overflows inside an RK4 stage: NonFiniteError (the reference tire code
    that names the component raised a bare 'math domain error' before), and the simulator
    keeps the last finite state, short of the 10 steps asked for."""
    from fourws_sim.errors import NonFiniteError
    from fourws_sim.models.eightdof import STATE
    from fourws_sim.simulator import Inputs, Simulator

    sim = Simulator("table_8_1")
    sim.reset(speed_mps=10.0)
    x = sim.state
    x[STATE[component]] = value
    sim.state = x
    with pytest.raises(NonFiniteError, match="became non-finite"):
        sim.step(Inputs(), 10)
    assert np.all(np.isfinite(sim.state)) and sim.outputs()["step"] < 10
