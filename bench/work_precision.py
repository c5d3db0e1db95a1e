#!/usr/bin/env python3
# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Work-precision of the 8-DOF integrators: error against an adaptive reference per cost.

For each maneuver (the default step steer, 85 km/h; an FMVSS 126 sine with dwell at 80 km/h,
steering-wheel amplitude 120 deg, the ESC test's most violent input) and each fixed-step
integrator (``rk4``, ``euler``, ``semi_implicit_euler``) at each step that divides the 10-ms
control period, the closed loop (fws: the front steer is the maneuver's, so every integrator
sees the same input) is run offline and compared with the same loop integrated by
``solve_ivp`` (DOP853, rtol = atol = 1e-10, :mod:`fourws_sim.integrators`):

* error: the largest deviation over the run of the yaw rate (rad/s) and of the sideslip angle
  (rad) at the control ticks, and the lateral position at the end (m);
* cost: the compiled kernel's CPU time per step and per simulated second (``Simulator.step``
  of one control period at a time, the graph's call, on the recorded inputs, best of
  ``--repeat``).

Usage (about 2 min on two cores)::

    .venv/bin/python bench/work_precision.py [--json FILE] [--repeat 5]

A benchmark, not part of ``make test``: the integrators' orders are asserted by
test/test_integrators.py and test/test_eightdof_integrators.py.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from fourws_run.closed_loop import run_closed_loop  # noqa: E402
from fourws_sim.params import load_vehicle  # noqa: E402
from fourws_sim.simulator import Simulator  # noqa: E402

CONTROL_PERIOD_S = 0.01
STEPS_S = (0.25e-3, 0.5e-3, 1e-3, 2e-3, 2.5e-3, 5e-3)
INTEGRATORS = ("rk4", "semi_implicit_euler", "euler")
MANEUVERS = {
    "step steer 85 km/h": {"type": "step_steer", "initial_speed_mps": 85 / 3.6,
                           "amplitude_rad": 0.02, "duration_s": 5.0},
    "sine with dwell 80 km/h, 120 deg": {
        "type": "sine_with_dwell", "initial_speed_mps": 80 / 3.6,
        "amplitude_rad": math.radians(120.0) / 17.0, "duration_s": 4.5},
}


def _errors(run, ref) -> dict[str, float]:
    n = min(run.time_s.size, ref.time_s.size)
    out = {}
    for name in ("yaw_rate_radps", "sideslip_rad"):
        out[name] = float(np.max(np.abs(run[name][:n] - ref[name][:n])))
    out["y_end_m"] = abs(float(run["y_m"][n - 1] - ref["y_m"][n - 1]))
    return out


def _kernel_cost(vehicle, run, integrator: str, dt: float, repeat: int) -> float:
    """CPU seconds of the compiled kernel per step (best of ``repeat``), on ``run``'s inputs."""
    per_tick = int(round(CONTROL_PERIOD_S / dt))
    inputs = []
    probe = Simulator(vehicle, integrator=integrator, dt_s=dt)
    for k in range(run.time_s.size):
        u = np.zeros(probe._n_input)
        u[0] = run.driver["front_wheel_angle_rad"][k]
        u[1] = run.rear_angle_rad[k]
        inputs.append(u)
    best = math.inf
    for _ in range(repeat):
        sim = Simulator(vehicle, integrator=integrator, dt_s=dt,
                        speed_mps=float(run["speed_mps"][0]))
        t0 = time.process_time()
        for u in inputs:
            sim.step(u, per_tick)
        best = min(best, time.process_time() - t0)
    return best / (len(inputs) * per_tick)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, help="write the table as JSON")
    parser.add_argument("--repeat", type=int, default=5, help="timing repeats (best taken)")
    args = parser.parse_args(argv)
    vehicle = load_vehicle("table_8_1")
    rows = []
    for label, spec in MANEUVERS.items():
        ref = run_closed_loop(vehicle, dict(spec), "fws", integrator="solve_ivp",
                              dt_s=CONTROL_PERIOD_S)
        print(f"{label}: reference solve_ivp ({ref.end_reason})", flush=True)
        for integrator in INTEGRATORS:
            for dt in STEPS_S:
                try:
                    run = run_closed_loop(vehicle, dict(spec), "fws", integrator=integrator,
                                          dt_s=dt)
                except Exception as exc:  # a step the model refuses (sub-step bound)
                    print(f"  {integrator:20s} {dt * 1e3:5.2f} ms: {exc}", flush=True)
                    continue
                err = _errors(run, ref)
                cost = _kernel_cost(vehicle, run, integrator, dt, args.repeat)
                row = {"maneuver": label, "integrator": integrator, "step_ms": dt * 1e3,
                       "end": run.end_kind, **err, "us_per_step": cost * 1e6,
                       "ms_per_simulated_s": cost / dt * 1e3}
                rows.append(row)
                print(f"  {integrator:20s} {dt * 1e3:5.2f} ms: yaw rate "
                      f"{err['yaw_rate_radps']:.2e} rad/s, sideslip "
                      f"{err['sideslip_rad']:.2e} rad, y(end) "
                      f"{err['y_end_m']:.2e} m; {row['us_per_step']:.2f} us/step, "
                      f"{row['ms_per_simulated_s']:.2f} ms per simulated s", flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
