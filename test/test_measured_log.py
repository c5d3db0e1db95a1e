# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Measured logs: ``fourws export`` writes the column set, the reader reads it back, bad data
is one line naming the column and the file (exit code 2).

Sources: the bag's own arrays (an export is exact: 17 significant digits); unit factors by
hand (pi/180, 1/3.6); the refusals by construction (each bad log differs from a good one in one
column, by a unit factor or a broken time stamp).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fourws_analysis import bag as B
from fourws_analysis.measured import (COLUMNS, REQUIRED_COLUMNS, TIME_COLUMN, columns_markdown,
                                      load_log, log_from_run)
from fourws_cli.main import main
from fourws_run.closed_loop import run_closed_loop
from fourws_sim.params import load_vehicle

README = Path(__file__).resolve().parent.parent / "README.md"


@pytest.fixture(scope="module")
def bag(tmp_path_factory) -> Path:
    """A 3-s step steer of the 8-DOF table_8_1 (twin run written as a bag)."""
    man = {"type": "step_steer", "name": "step", "initial_speed_mps": 23.6, "duration_s": 3.0,
           "steer_input": "road_wheel", "amplitude_rad": 0.01, "start_s": 0.5,
           "ramp_time_s": 0.1}
    res = run_closed_loop(load_vehicle("table_8_1"), man, "fws")
    path = tmp_path_factory.mktemp("log") / "step"
    B.write_run(path, res.time_s, res.outputs, res.config, driver=res.driver, model="8dof")
    return path


def test_export_round_trip_is_exact(bag, tmp_path, capsys) -> None:
    """CSV and Parquet exports read back equal to the bag's log bit for bit; --topics adds the
    state's per-wheel fields equal to the bag's (FL..RR)."""
    run = B.load_bag(bag)
    ref = log_from_run(run)
    for fmt in ("csv", "parquet"):
        assert main(["export", str(bag), "--format", fmt, "--out", str(tmp_path / fmt),
                     "--topics", "/fourws/state"]) == 0
        path = tmp_path / fmt / f"step.{fmt}"
        assert str(path) in capsys.readouterr().out
        log = load_log(path)
        np.testing.assert_array_equal(log.time_s, ref.time_s)
        assert sorted(log.channels) == sorted(ref.channels)
        for name, values in ref.channels.items():
            np.testing.assert_array_equal(log.channels[name], values, err_msg=name)
    header = (tmp_path / "csv" / "step.csv").read_text().splitlines()[0].split(",")
    assert header[:len(REQUIRED_COLUMNS) + 1] == [TIME_COLUMN, *REQUIRED_COLUMNS]
    assert "state.normal_load_n_rl" in header
    table = np.genfromtxt(tmp_path / "csv" / "step.csv", delimiter=",", names=True)
    np.testing.assert_array_equal(table["statenormal_load_n_rl"],
                                  run.topics["/fourws/state"].fields["normal_load_n"][:, 2])


def _write(path: Path, columns: dict[str, np.ndarray]) -> Path:
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(",".join(columns) + "\n")
        for row in zip(*columns.values()):
            fh.write(",".join(repr(float(v)) for v in row) + "\n")
    return path


def _good(n: int = 400, dt: float = 0.01) -> dict[str, np.ndarray]:
    """A plausible 4-s log: a sine steer at 20 m/s, yaw rate and a_y = U r in phase."""
    t = dt * np.arange(n)
    swa = 0.5 * np.sin(2 * math.pi * 0.5 * t)
    r = 0.1 * np.sin(2 * math.pi * 0.5 * t)
    return {TIME_COLUMN: t, "steering_wheel_angle_rad": swa, "speed_mps": np.full(n, 20.0),
            "yaw_rate_radps": r, "lateral_accel_mps2": 20.0 * r,
            "roll_rad": 0.004 * np.sin(2 * math.pi * 0.5 * t)}


def test_alternate_units_are_converted(tmp_path) -> None:
    """Columns in deg, deg/s and km/h equal the SI log times pi/180 and 1/3.6."""
    good = _good()
    si = load_log(_write(tmp_path / "si.csv", good))
    alt = dict(good)
    alt["steering_wheel_angle_deg"] = np.degrees(alt.pop("steering_wheel_angle_rad"))
    alt["yaw_rate_degps"] = np.degrees(alt.pop("yaw_rate_radps"))
    alt["speed_kmh"] = 3.6 * alt.pop("speed_mps")
    log = load_log(_write(tmp_path / "alt.csv", alt))
    for name in si.channels:
        np.testing.assert_allclose(log.channels[name], si.channels[name], rtol=1e-14,
                                   err_msg=name)


def _bad(name: str) -> dict[str, np.ndarray]:
    cols = _good()
    if name == "missing":
        del cols["yaw_rate_radps"]
    elif name == "backwards":
        cols[TIME_COLUMN] = cols[TIME_COLUMN].copy()
        cols[TIME_COLUMN][100] = cols[TIME_COLUMN][98]
    elif name == "gap":
        cols[TIME_COLUMN] = np.where(cols[TIME_COLUMN] > 2.0, cols[TIME_COLUMN] + 1.0,
                                     cols[TIME_COLUMN])
    elif name == "short":
        cols = {k: v[:40] for k, v in cols.items()}
    elif name == "nan":
        cols["lateral_accel_mps2"] = cols["lateral_accel_mps2"].copy()
        cols["lateral_accel_mps2"][7] = math.nan
    elif name == "yaw_degps":  # 5.7 deg/s peak written as rad/s: a_y is no longer U r
        cols["yaw_rate_radps"] = np.degrees(cols["yaw_rate_radps"])
    elif name == "speed_kmh":  # 72 km/h written as m/s
        cols["speed_mps"] = 3.6 * cols["speed_mps"]
    elif name == "roll_deg":
        cols["roll_rad"] = np.degrees(cols["roll_rad"])
    elif name == "swa_huge":
        cols["steering_wheel_angle_rad"] = np.degrees(cols["steering_wheel_angle_rad"])
    return cols


@pytest.mark.parametrize(("case", "field", "words"), [
    ("missing", "yaw_rate_radps", "missing column"),
    ("backwards", TIME_COLUMN, "does not increase at line 102 (0.98 s after 0.99 s)"),
    ("gap", TIME_COLUMN, "a gap of 1.01 s"),
    ("short", TIME_COLUMN, "40 samples"),
    ("nan", "lateral_accel_mps2", "line 9: nan"),
    ("yaw_degps", "lateral_accel_mps2", "yaw rate in deg/s"),
    ("speed_kmh", "lateral_accel_mps2", "speed in km/h"),
    ("roll_deg", "roll_rad", "in degrees"),
    ("swa_huge", "steering_wheel_angle_rad", "the unit cannot be right"),
])
def test_bad_data_is_one_line(tmp_path, capsys, case, field, words) -> None:
    """Each bad log: exit code 2 from identify and validate, one stderr line naming the column
    and the file, the reason in words, no traceback."""
    path = _write(tmp_path / f"{case}.csv", _bad(case))
    for argv in (["identify", str(path), "--vehicle", "table_8_1", "--quiet"],
                 ["validate", str(path), str(path)]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1, err
        assert err[0].startswith(f"fourws {argv[0]}: error: {field}: ")
        assert words in err[0] and str(path) in err[0]


def test_steering_in_degrees_is_refused_by_the_fit(tmp_path, capsys) -> None:
    """10 deg of hand wheel written as 10 "rad" stays inside the column's limit (6 pi) but the
    fit compares it with the kinematic steer L r/U: 57 times too large, refused."""
    cols = _good()
    cols["steering_wheel_angle_rad"] = cols["steering_wheel_angle_rad"] * math.degrees(1.0) / 3
    cols["yaw_rate_radps"] = cols["yaw_rate_radps"] / 3.0
    cols["lateral_accel_mps2"] = cols["lateral_accel_mps2"] / 3.0
    path = _write(tmp_path / "swa.csv", cols)
    load_log(path)  # a plausible log on its own
    assert main(["identify", str(path), "--vehicle", "table_8_1", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("fourws identify: error: steering_wheel_angle_rad: ")
    assert "in degrees" in err


def test_readme_lists_the_column_set() -> None:
    """The README's table is the one :func:`columns_markdown` makes from COLUMNS."""
    assert columns_markdown() in README.read_text()
    assert len(COLUMNS) == len({c.name for c in COLUMNS})
