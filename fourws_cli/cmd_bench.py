# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws bench [--json]``: speed of the 8-DOF real-time simulator (RK4, 1 ms, one core)."""

from __future__ import annotations

import argparse
import json

from fourws_cli._bounds import bounded

HELP = "benchmark the 8-DOF simulator (STI tire, RK4 1 ms, one core): real-time factor"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the sub-parser."""
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("--vehicle", default="table_8_1", help="vehicle name or YAML path")
    parser.add_argument("--tire", default=None, help="tire model (default: the vehicle's)")
    parser.add_argument("--seconds", type=float, default=20.0, metavar="S",
                        help="simulated seconds per repetition (default 20)")
    parser.add_argument("--repeats", type=int, default=5, help="repetitions (default 5)")
    parser.add_argument("--no-cold", action="store_true",
                        help="skip the empty-cache compile measurement (a subprocess)")
    parser.add_argument("--study", action="store_true",
                        help="benchmark studies instead: closed-loop vehicle-steps/s of the "
                             "compiled loop, of whole points, of a study on 1 and 2 local "
                             "workers and on Dask (fourws_study.bench)")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark and print its results."""
    # the simulator and the maneuvers: 0.1 s that `fourws --help` does not need
    from fourws_sim.bench import format_text, run_benchmark, to_json
    from fourws_sim.maneuvers import MAX_DURATION_S

    if args.study:
        from fourws_study.bench import run_study_benchmark  # numba, pyarrow: not for --help

        repeats = int(bounded("--repeats", args.repeats, 1, 1000))
        result = run_study_benchmark(repeats=repeats)
        print(json.dumps(result, indent=2) if args.json else "\n".join(
            f"{k}: {v}" for k, v in result.items()))
        return 0

    seconds = bounded("--seconds", args.seconds, 0.0, MAX_DURATION_S, " s", low_open=True)
    bounded("--repeats", args.repeats, 1, 1000)
    result = run_benchmark(vehicle=args.vehicle, sim_seconds=seconds,
                           repeats=args.repeats, tire=args.tire, cold=not args.no_cold)
    print(to_json(result) if args.json else format_text(result))
    return 0
