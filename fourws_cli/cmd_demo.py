# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws demo``: the default scenario through the real node graph, then the report.

Runs ``config/scenarios/default.yaml`` (step steer at 85 km/h on the 8-DOF ``table_8_1`` car)
once per law of the scenario (FWS and two 4WS laws) through the ROS 2 node graph, each run
recorded to a rosbag2 MCAP bag, then analyses the bags together into an HTML report. This is
what ``make demo`` runs. The analysis runs in a process of its own
(:mod:`fourws_cli.background_analysis`), each bag while the next law runs; should that process
fail, the demo analyses the bags itself.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from fourws_cli import cmd_analyze
from fourws_cli.background_analysis import BackgroundAnalysis

HELP = "run the default scenario for FWS and two 4WS laws through the node graph, then report"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``fourws demo``."""
    parser.add_argument("--scenario", default="default",
                        help="scenario name or YAML path (default: default)")
    parser.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help="output folder (default: runs/demo-<UTC time>)")


def run(args: argparse.Namespace) -> int:
    """Run the scenario's laws, analyse the bags, print where everything is."""
    from fourws_ros.domains import domain_for_run  # fourws_ros: not for --help
    from fourws_ros.graph_run import run_graph  # rclpy: not for --help
    from fourws_ros.node_params import dumps_config  # rclpy: not for --help
    from fourws_run.config import RunConfig  # rosbags, mcap: not for --help
    from fourws_run.scenario import load_scenario  # rosbags, mcap: not for --help

    scenario = load_scenario(args.scenario)
    domain_for_run().release()  # a bad ROS_DOMAIN_ID is exit 2 before the output folder
    out = args.out or Path("runs") / time.strftime("demo-%Y%m%dT%H%M%SZ", time.gmtime())
    out.mkdir(parents=True, exist_ok=True)
    print(f"fourws demo: scenario {scenario.name!r}, laws {', '.join(scenario.laws)}, "
          f"output {out}", flush=True)
    report_dir = out / "report"
    # the analyze command's own options and defaults; the bags are the runs' that succeed
    analyze_argv = [*(str(out / law / "bag") for law in scenario.laws), "--report",
                    str(report_dir), "--timing"]
    report = BackgroundAnalysis([*analyze_argv, "--quiet"])
    configs = {law: RunConfig.from_scenario(scenario, law) for law in scenario.laws}
    for config in configs.values():  # each law's critical speeds while the first law runs
        report.prepare(dumps_config(config.to_dict()))
    try:
        bags: list[str] = []
        failed: list[str] = []
        for law, config in configs.items():
            result = run_graph(config, out, run_name=law)
            print("\n".join(result.summary_lines()), flush=True)
            if result.interrupted:
                return 130
            if result.ok and result.bag_path is not None:
                bags.append(str(result.bag_path))
                report.add(str(result.bag_path))  # analysed while the next law runs
            else:
                failed.append(f"{law}: {result.reason}")
        if not bags:
            print("fourws demo: no run succeeded: " + "; ".join(failed))
            return 1
        code = report.finish()
    finally:
        report.close()
    if code is None:  # the report's own process could not: here, as `fourws analyze` does
        print(f"fourws demo: {report.problem}; analysing the bags here", flush=True)
        parser = argparse.ArgumentParser()
        cmd_analyze.add_arguments(parser)
        code = cmd_analyze.run(parser.parse_args([*bags, *analyze_argv[len(scenario.laws):]]))
    print("fourws demo: bags:")
    for bag in bags:
        print(f"  {bag}")
    print(f"fourws demo: report: {report_dir / 'index.html'}")
    if failed:
        print("fourws demo: failed runs: " + "; ".join(failed))
        return 1
    return code
