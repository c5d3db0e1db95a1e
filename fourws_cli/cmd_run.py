# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws run [SCENARIO] [--law NAME ...] [--controller CMD] [--out DIR]``: run a scenario
through the node graph.

Every law of the scenario (or each ``--law``) is one run of the real ROS 2 graph (a scenario
with a ``series`` runs each member of the law's series, :mod:`fourws_run.series`) -- simulator,
maneuver player, controller and recorder as separate processes on a ROS domain of their own
-- recorded to a rosbag2 (MCAP) bag that the recorder checks for completeness. With
``--controller CMD`` (or a scenario's ``controller:``) your own controller node answers the
states instead of fourws's (one run). Prints a summary per run; the run record is
``<run>/run.json``.

Exit code: 0 every run completed with a complete bag; 1 a run failed (a node, a stall, an
incomplete recording -- the reason names it); 3 a run ended early for a vehicle-dynamics
reason (the maneuver was aborted or the simulation diverged; its bag is complete); 130
interrupted.
"""

from __future__ import annotations

import argparse
import dataclasses
import shlex
import socket
import sys
import time
from pathlib import Path
from typing import Any

from fourws_control import available_laws
from fourws_sim.errors import ParameterError, UnknownNameError

HELP = "run a scenario (default: config/scenarios/default.yaml) through the ROS 2 node graph"
#: Default port of ``--live`` (the Foxglove app's default WebSocket connection).
LIVE_PORT = 8765


def check_port_free(port: int, host: str = "127.0.0.1") -> None:
    """Refuse a port that is in use (before anything of the run is created).

    Raises
    ------
    ParameterError
        Out of range or in use (names ``--live``).
    """
    if not 1 <= port <= 65535:
        raise ParameterError("--live", f"port must be 1-65535, got {port}")
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        try:
            probe.bind((host, port))
        except OSError as exc:
            raise ParameterError("--live", f"port {port} on {host} is in use "
                                 f"({exc.strerror or exc}); give another: --live PORT") from None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``fourws run``."""
    parser.add_argument("scenario", nargs="?", default="default",
                        help="scenario name (config/scenarios) or YAML path (default: default)")
    parser.add_argument("--law", action="append", metavar="NAME",
                        help="run only this law (repeatable; default: the scenario's laws)")
    parser.add_argument("--controller", metavar="CMD", default=None,
                        help="your own controller node instead of fourws's: an executable or "
                             "'python my_controller.py' (quoted), started with the run's ROS "
                             "environment and --ros-args; see docs/controller-contract.md")
    parser.add_argument("--controller-name", metavar="NAME", default=None,
                        help="ROS node name of --controller (default fourws_controller; the "
                             "launcher remaps the node to it)")
    parser.add_argument("--driver", metavar="CMD", default=None,
                        help="drive from outside instead of the maneuver's driver: 'ackermann' "
                             "(ackermann_msgs/AckermannDriveStamped on /drive, e.g. an F1TENTH "
                             "stack), 'joy' (sensor_msgs/Joy on /joy: a gamepad, or fourws node "
                             "keyboard_driver), or your own driver node (a command, quoted); "
                             "see docs/driver-contract.md")
    parser.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help="output folder (default: the scenario's recording.output_dir)")
    parser.add_argument("--name", default=None, metavar="RUN",
                        help="run folder name (default <scenario>-<law>-<UTC time>; with "
                             "several laws, <RUN>-<law>)")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace a run folder of the same name")
    parser.add_argument("--clock", choices=("lockstep", "realtime"), default=None,
                        help="override the scenario's clock mode")
    parser.add_argument("--live", nargs="?", type=int, const=LIVE_PORT, default=None,
                        metavar="PORT",
                        help=f"watch the run live in Foxglove: a Foxglove WebSocket server on "
                             f"127.0.0.1:PORT (default {LIVE_PORT}) serving the car, its markers "
                             "and the state while the run goes on")


def run(args: argparse.Namespace) -> int:
    """Run the scenario; returns the exit code."""
    from fourws_ros.domains import domain_for_run  # fourws_ros: not for --help
    from fourws_ros.graph_run import run_graph  # rclpy: not for --help
    # rosbags, mcap: not for --help
    from fourws_run.config import INPUT_DRIVERS, USER_LAW, ControllerSpec, RunConfig
    from fourws_run.record import EXIT_CODES, Outcome  # rosbags, mcap: not for --help
    from fourws_run.scenario import load_scenario  # rosbags, mcap: not for --help
    from fourws_run.series import scenario_runs  # rosbags, mcap: not for --help

    scenario = load_scenario(args.scenario)
    if args.clock:
        scenario = dataclasses.replace(scenario, clock_mode=args.clock)
    controller = scenario.controller
    if args.controller is not None:
        command = tuple(shlex.split(args.controller))
        if not command:
            raise ParameterError("--controller", "must be a command")
        controller = ControllerSpec(command, controller.node_name)
    if args.controller_name is not None:
        controller = ControllerSpec.from_mapping({"command": list(controller.command),
                                                  "name": args.controller_name},
                                                 "--controller-name")
    controller.check_runnable("--controller" if args.controller is not None
                              else scenario.source)
    if not controller.builtin:
        if args.law:
            raise ParameterError("--law", "a user controller (--controller) runs its own law; "
                                 "leave --law out")
        laws = [USER_LAW]
    else:
        laws = list(args.law) if args.law else list(scenario.laws)
        for law in laws:
            if law not in available_laws():
                raise UnknownNameError("law", law, available_laws())
        for law in laws:
            if laws.count(law) > 1:  # it would run (and be recorded) as often
                raise ParameterError("--law", f"{law!r} is given {laws.count(law)} times; "
                                     "each law runs once")
    if args.live is not None:
        check_port_free(args.live)
    driver: tuple[str, ...] = ()
    if args.driver is not None:
        driver = tuple(shlex.split(args.driver))
        if not driver:
            raise ParameterError("--driver", "must be ackermann, joy or a command")
        if driver[0] not in INPUT_DRIVERS or len(driver) > 1:
            ControllerSpec(driver).check_runnable("--driver")
    out = args.out if args.out is not None else Path(scenario.recording.output_dir)
    # the environment is input too: a ROS_DOMAIN_ID no run can use (not a domain ID, or held
    # by another fourws run) is exit 2 before any run folder exists (run_graph leases it)
    domain_for_run().release()
    records = []
    for law in laws:
        # a series: every member is a run of its own (fourws_run.series)
        members: list[Any] = [None]
        if scenario.series is not None and controller.builtin:
            members = scenario_runs(scenario, law)
        elif isinstance(scenario.series, tuple):
            members = list(scenario.series)  # a user controller: nothing found per law
        elif scenario.series is not None:
            raise ParameterError("series", "the regulation series is found per law (A of the "
                                 "slowly increasing steer); a user controller (--controller) "
                                 "has no law fourws can run offline: run its members as "
                                 "maneuvers of their own")
        for member in members:
            config = RunConfig.from_scenario(scenario, law, controller, maneuver=member)
            if driver:
                config = config.replace(driver=driver)
            name = _run_name(args.name, scenario.name, law, member, len(laws) > 1)
            record = run_graph(config, out, run_name=name, overwrite=args.overwrite,
                               live_port=args.live)
            records.append(record)
            print("\n".join(record.summary_lines()), flush=True)
            if record.interrupted:
                return EXIT_CODES[Outcome.INTERRUPTED]
    bad = [r for r in records if not r.ok]
    print(f"fourws run: {len(records) - len(bad)}/{len(records)} runs ok; bags:")
    for r in records:
        print(f"  {r.law:>12s}  {r.bag_path if r.bag_path else '(not recorded)'}"
              f"{'' if r.ok else '  ' + r.outcome.value.upper()}")
    for r in bad:
        print(f"fourws run: {r.law} {r.outcome.value}: {r.reason}", file=sys.stderr)
    return max((r.exit_code for r in records), default=0) if bad else 0


def _run_name(name: str | None, scenario: str, law: str, member: Any,
              several_laws: bool) -> str | None:
    """The run folder name: ``--name`` (with ``-<law>`` for several laws), or the default
    ``<scenario>-<law>-<UTC time>`` of the graph run; a series member adds its maneuver's
    name (``<scenario>-<law>-<member>-<UTC time>``)."""
    if member is None:
        return name if name is None or not several_laws else f"{name}-{law}"
    stamp = time.strftime("%Y%m%d-%H%M%S", time.gmtime())
    base = f"{scenario}-{law}" if name is None else (f"{name}-{law}" if several_laws
                                                     else name)
    return f"{base}-{member.name}" + ("" if name is not None else f"-{stamp}")
