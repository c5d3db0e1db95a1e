# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Time of ``fourws identify`` on a 60 s record, per model level (a benchmark, not a test).

The record is the shipped ISO 7401 random steer (``config/maneuvers/random_steer.yaml``: 60 s
of 0.05-3 Hz steer at 85 km/h, 100 Hz) run by the offline twin on table_8_1 with its cornering
stiffnesses, yaw inertia and roll stiffness moved by 15-25 % (the linear tire, so that the
8-DOF's axle stiffnesses are the fitted ones); each level fits the moved fields from the
unchanged car, from the twin's model of that level. Printed: per level the wall time of the
identification, the model runs it took, and the largest error of a fitted value.

    .venv/bin/python bench/identify.py [--json] [--levels 2dof 3dof 8dof]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from fourws_analysis import bag as B
from fourws_analysis.fit import identify
from fourws_analysis.measured import load_log
from fourws_run.closed_loop import run_closed_loop
from fourws_sim.params import load_vehicle, vehicle_from_mapping

MOVED = {"axle_tires.cornering_stiffness_front_n_per_rad": 0.8,
         "axle_tires.cornering_stiffness_rear_n_per_rad": 1.15,
         "chassis.yaw_inertia_kgm2": 1.2,
         "roll.roll_stiffness_front_nm_per_rad": 1.25,
         "roll.roll_stiffness_rear_nm_per_rad": 1.25}
FIELDS = {
    "2dof": ["axle_tires.cornering_stiffness_front_n_per_rad",
             "axle_tires.cornering_stiffness_rear_n_per_rad", "chassis.yaw_inertia_kgm2"],
    "3dof": ["axle_tires.cornering_stiffness_front_n_per_rad",
             "axle_tires.cornering_stiffness_rear_n_per_rad", "chassis.yaw_inertia_kgm2",
             "roll.roll_stiffness_front_nm_per_rad,roll.roll_stiffness_rear_nm_per_rad"],
    "8dof": ["axle_tires.cornering_stiffness_front_n_per_rad",
             "axle_tires.cornering_stiffness_rear_n_per_rad", "chassis.yaw_inertia_kgm2",
             "roll.roll_stiffness_front_nm_per_rad,roll.roll_stiffness_rear_nm_per_rad",
             "tire.relaxation_length_m"],
}


def _vehicles():
    mapping = load_vehicle("table_8_1").to_dict()
    mapping["tire"]["model"] = "linear"
    base = vehicle_from_mapping(mapping, "base")
    for path, factor in MOVED.items():
        sub, key = path.split(".")
        mapping[sub][key] *= factor
    return base, vehicle_from_mapping(mapping, "truth")


def bench(levels: list[str]) -> dict:
    """Identify on a 60 s record at each level; returns the timings."""
    base, truth = _vehicles()
    out: dict = {"record": "random_steer (config/maneuvers), 60 s of steer, 100 Hz",
                 "levels": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for level in levels:
            model = level
            res = run_closed_loop(truth, "random_steer", "fws", model=model,
                                  dt_s=1e-3 if model == "8dof" else 1e-2)
            path = Path(tmp) / level
            B.write_run(path, res.time_s, res.outputs, res.config, driver=res.driver,
                        model=model)
            log = load_log(path)
            # (the twin's run loaded the 8-DOF's compiled kernels: the fit's time is its own)
            start = time.perf_counter()
            result = identify([log], base, level=level, fields=FIELDS[level])
            wall = time.perf_counter() - start
            worst = 0.0
            for v in result.values:
                sub, key = v.path.split(".")
                true = float(getattr(getattr(truth, sub), key))
                worst = max(worst, abs(v.value / true - 1.0))
            out["levels"][level] = {
                "record_s": log.duration_s, "samples": int(log.time_s.size),
                "fields": FIELDS[level], "wall_s": wall, "model_runs": result.evaluations,
                "s_per_model_run": wall / max(result.evaluations, 1),
                "largest_relative_error": worst}
    return out


def main() -> int:
    """Run the benchmark and print it."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument("--levels", nargs="+", default=["2dof", "3dof", "8dof"])
    args = parser.parse_args()
    result = bench(args.levels)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for level, row in result["levels"].items():
            print(f"{level}: {row['wall_s']:.2f} s for a {row['record_s']:.0f} s record "
                  f"({row['model_runs']} model runs, {row['s_per_model_run'] * 1e3:.1f} ms "
                  f"each), largest error {100 * row['largest_relative_error']:.3f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
