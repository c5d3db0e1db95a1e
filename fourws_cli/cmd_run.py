"""``fourws run [SCENARIO] [--law NAME ...] [--out DIR]``: run a scenario through the node graph.

Every law of the scenario (or each ``--law``) is one run of the real ROS 2 graph — simulator,
maneuver player, controller and recorder as separate processes on an isolated ROS domain —
recorded to a rosbag2 (MCAP) bag. Prints a summary per run with the bag path; the exit code is
non-zero if any run failed (the reason is printed).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HELP = "run a scenario (default: config/scenarios/default.yaml) through the ROS 2 node graph"

EXIT_RUN_FAILED = 1
EXIT_INTERRUPTED = 130


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``fourws run``."""
    parser.add_argument("scenario", nargs="?", default="default",
                        help="scenario name (config/scenarios) or YAML path (default: default)")
    parser.add_argument("--law", action="append", metavar="NAME",
                        help="run only this law (repeatable; default: the scenario's laws)")
    parser.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help="output folder (default: the scenario's recording.output_dir)")
    parser.add_argument("--clock", choices=("lockstep", "realtime"), default=None,
                        help="override the scenario's clock mode")


def run(args: argparse.Namespace) -> int:
    """Run the scenario; returns the exit code."""
    import dataclasses

    from fourws_ros.launcher import run_graph
    from fourws_sim.errors import UnknownNameError
    from fourws_sim.scenario import load_scenario

    scenario = load_scenario(args.scenario)
    if args.clock:
        scenario = dataclasses.replace(scenario, clock_mode=args.clock)
    laws = list(args.law) if args.law else list(scenario.laws)
    from fourws_control import available_laws
    for law in laws:
        if law not in available_laws():
            raise UnknownNameError("law", law, available_laws())
    out = args.out if args.out is not None else Path(scenario.recording.output_dir)
    results = []
    for law in laws:
        result = run_graph(scenario, law, out)
        results.append(result)
        print("\n".join(result.summary_lines()), flush=True)
        if result.interrupted:
            return EXIT_INTERRUPTED
    failed = [r for r in results if not r.ok]
    print(f"fourws run: {len(results) - len(failed)}/{len(results)} runs ok; bags:")
    for r in results:
        print(f"  {r.law:>12s}  {r.bag_path if r.bag_path else '(not recorded)'}"
              f"{'' if r.ok else '  FAILED'}")
    if failed:
        for r in failed:
            print(f"fourws run: {r.law} failed: {r.reason}", file=sys.stderr)
        return EXIT_RUN_FAILED
    return 0
