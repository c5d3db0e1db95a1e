# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws bench-graph [--json]``: speed of the real node graph (lockstep and realtime).

* lockstep: the default scenario's step steer stretched to ``--lockstep-seconds`` with law
  ``sol1`` at 100 Hz control / 1 kHz RK4 integration, recorded — the real-time factor is
  simulated time over the wall time of the running phase (start-up excluded).
* realtime: the same maneuver for ``--realtime-seconds`` (default 60 s) at 1 kHz integration
  with the state at 200 Hz — the simulator's step lateness (99th percentile and max, from its
  histogram) and overruns, and the recorded state rate.

* start-up: ``--startups`` short lockstep runs (1 s simulated): the wall time from the
  nodes' launch to the start of the simulation (``RunRecord.startup_s``: processes started,
  imported, configured, kernels loaded, discovered and matched) and of the whole run
  (launch to the verified bag), median, min and max;
* commands: as many default runs as a user starts them, ``fourws run --law fws`` in a new
  process each (its own node starter): launch of the command to the simulation's start (its
  "graph up" line) and to its exit, median, min and max;
* the demo: ``--demo`` times ``fourws demo`` (three laws of the default scenario through the
  graph, then the report) as a user runs it.

Both runs report their recording accounting: every topic's published and stored counts
(``*_recording``; published = stored is what a complete bag means). A 10-minute realtime soak
is ``fourws bench-graph --lockstep-seconds 0 --realtime-seconds 600``.

The machine's load average is reported alongside: the graph shares the CPU with everything
else running.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fourws_cli._bounds import bounded
from fourws_sim.errors import FourwsError

HELP = "benchmark the ROS 2 node graph (lockstep real-time factor, realtime step lateness)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``fourws bench-graph``."""
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--lockstep-seconds", type=float, default=30.0,
                        help="simulated duration of the lockstep run, s (default 30; 0 skips "
                             "it)")
    parser.add_argument("--realtime-seconds", type=float, default=60.0,
                        help="duration of the realtime run, s (default 60; 0 skips it)")
    parser.add_argument("--state-rate-hz", type=float, default=200.0,
                        help="realtime state rate, Hz (default 200)")
    parser.add_argument("--startups", type=int, default=5,
                        help="short lockstep runs timing the graph's start-up (default 5; 0 "
                             "skips them)")
    parser.add_argument("--demo", action="store_true",
                        help="also time `fourws demo` (wall time, s)")
    parser.add_argument("--keep", type=Path, default=None, metavar="DIR",
                        help="keep the runs (bags, logs) in DIR")
    parser.add_argument("--no-scene", action="store_true",
                        help="without the car in 3D: the simulator publishes no /tf, "
                             "/tf_static, /robot_description, /fourws/markers (the graph "
                             "before them, for comparison)")
    parser.add_argument("--live", nargs="?", type=int, const=8765, default=None,
                        metavar="PORT", help="with a live view serving both runs (as "
                                             "fourws run --live)")


def _scenario(duration_s: float, **changes):
    from fourws_run.scenario import load_scenario  # rosbags, mcap: not for --help
    from fourws_sim.maneuvers import maneuver_spec_from_mapping  # 0.04 s: not for --help

    sc = load_scenario("default")
    spec = sc.maneuver.to_dict()
    spec["duration_s"] = float(duration_s)
    return dataclasses.replace(sc, maneuver=maneuver_spec_from_mapping(spec), **changes)


def _recording(record) -> dict[str, object]:
    """Published and stored per topic, and whether they agree everywhere."""
    if record.account is None:
        return {"complete": False, "why": record.reason}
    return {"complete": record.account.complete,
            "topics": {t: {"published": a.expected, "stored": a.stored, "lost": a.gaps}
                       for t, a in sorted(record.account.topics.items())}}


def _overrun_times(bag_path) -> list[float]:
    """Simulation times of every realtime overrun, as the bag holds them."""
    from fourws_analysis.bag import load_bag  # scipy, control: not for --help
    from fourws_run.interface import SIM_STATUS  # rosbags: not for --help

    status = load_bag(bag_path, [SIM_STATUS], allow_incomplete=True).topics.get(SIM_STATUS)
    if status is None or "overrun_times_s" not in status.fields:
        return []
    return [float(t) for row in status.fields["overrun_times_s"] for t in row]


def _spread(result: dict, name: str, values: list[float]) -> None:
    """``name``'s median, min and max into ``result`` (nothing without values)."""
    if values:
        result.update({f"{name}_median": statistics.median(values),
                       f"{name}_min": min(values), f"{name}_max": max(values)})


def _startups(n: int, config, out: Path, quiet, extra: dict, result: dict) -> bool:
    """``n`` short lockstep runs: start-up and whole-run wall times into ``result``."""
    from fourws_ros.graph_run import run_graph  # rclpy: not for --help

    startup, whole, ok = [], [], True
    for k in range(n):
        t0 = time.monotonic()
        rec = run_graph(config(_scenario(1.0)), out, run_name=f"startup{k}", echo=quiet,
                        **extra)
        whole.append(time.monotonic() - t0)
        ok &= rec.ok
        if rec.startup_s > 0:
            startup.append(rec.startup_s)
    _spread(result, "startup_s", startup)
    _spread(result, "startup_run_wall_s", whole)
    result["startup_runs"] = n
    result["startup_runs_ok"] = ok
    return ok


#: What ``fourws run`` prints once the simulation has started (fourws_ros.graph_run).
GRAPH_UP = "graph up after"


def _commands(n: int, out: Path, result: dict) -> bool:
    """``n`` default runs as a user starts them (``fourws run --law fws``, a new process and
    node starter each): from the launch of the command to its "graph up" line (the
    simulation's start) and to its exit, median, min and max."""
    up, whole, ok = [], [], True
    for k in range(n):
        t0 = time.monotonic()
        proc = subprocess.Popen([sys.executable, "-m", "fourws_cli.main", "run", "--law", "fws",
                                 "--out", str(out / f"command{k}")], stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True, errors="replace")
        for line in proc.stderr:  # type: ignore[union-attr]
            if GRAPH_UP in line and len(up) == k:
                up.append(time.monotonic() - t0)
        ok &= proc.wait() == 0
        whole.append(time.monotonic() - t0)
    _spread(result, "command_startup_s", up)
    _spread(result, "command_wall_s", whole)
    result["command_runs_ok"] = ok and len(up) == n
    return ok and len(up) == n


def _demo(out: Path, result: dict) -> bool:
    """Wall time of ``fourws demo`` into ``result``."""
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "fourws_cli.main", "demo", "--out",
                           str(out / "demo")], stdout=subprocess.DEVNULL,
                          stderr=subprocess.DEVNULL, check=False)
    result["demo_wall_s"] = time.monotonic() - t0
    result["demo_ok"] = proc.returncode == 0
    return proc.returncode == 0


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; returns the exit code."""
    from fourws_analysis.bag import load_bag  # scipy, control: not for --help
    from fourws_ros import topics  # rclpy: not for --help
    from fourws_ros.graph_run import run_graph  # rclpy: not for --help
    from fourws_run.config import RunConfig  # rosbags, mcap: not for --help
    from fourws_sim.maneuvers import MAX_DURATION_S  # 0.04 s: not for --help

    bounded("--lockstep-seconds", args.lockstep_seconds, 0.0, MAX_DURATION_S, " s")
    bounded("--realtime-seconds", args.realtime_seconds, 0.0, MAX_DURATION_S, " s")
    bounded("--state-rate-hz", args.state_rate_hz, 1.0, 1e4, " Hz")
    bounded("--startups", args.startups, 0, 1000, "")
    out = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="fourws-bench-"))
    quiet = (lambda _text: None) if args.json else None
    result: dict[str, object] = {"load_average_before": os.getloadavg()[0],
                                 "scene": not args.no_scene, "live_view": args.live is not None}
    scene_topics = (topics.TF, topics.TF_STATIC, topics.ROBOT_DESCRIPTION, topics.MARKERS)
    extra: dict[str, object] = {"live_port": args.live}
    if args.no_scene:
        extra["node_overrides"] = {topics.NODE_NAMES[topics.Role.SIMULATOR]:
                                   {"publish_scene": False}}

    def config(scenario):
        cfg = RunConfig.from_scenario(scenario, "sol1")
        if args.no_scene:
            cfg = dataclasses.replace(cfg, recorded_topics=tuple(
                t for t in cfg.recorded_topics if t not in scene_topics))
        return cfg

    ok = True
    try:
        if args.startups > 0:
            ok &= _startups(args.startups, config, out, quiet, extra, result)
            ok &= _commands(args.startups, out, result)
        if args.demo:
            ok &= _demo(out, result)
        if args.lockstep_seconds > 0:
            lock = run_graph(config(_scenario(args.lockstep_seconds)), out,
                             run_name="lockstep", echo=quiet, **extra)
            ok &= lock.ok
            result.update({
                "lockstep_ok": lock.ok, "lockstep_reason": lock.reason,
                "lockstep_sim_s": lock.sim_time_s,
                "lockstep_wall_s": lock.wall_time_s,
                "lockstep_realtime_factor": lock.realtime_factor,
                "lockstep_ticks_per_s": lock.sim_time_s / 0.01 / max(lock.wall_time_s, 1e-9),
                "lockstep_messages": sum(lock.message_counts.values()),
                "lockstep_recording": _recording(lock),
            })
        if args.realtime_seconds > 0:
            period = 1.0 / args.state_rate_hz
            rt = run_graph(config(_scenario(args.realtime_seconds, clock_mode="realtime",
                                            state_period_s=period)),
                           out, run_name="realtime", echo=quiet, **extra)
            ok &= rt.ok
            # what the bag holds, also when the run failed on it: the numbers and the reason
            # are the benchmark's result then (a 10-minute soak lost /tf messages once)
            try:
                state = load_bag(rt.bag_path, topics=[topics.STATE],
                                 allow_incomplete=True).topics[topics.STATE]
                n_states = len(state)
                span = float(state.time_s[-1] - state.time_s[0]) if n_states > 1 else 0.0
            except (FourwsError, OSError, KeyError):  # no bag at all: the reason says why
                n_states, span = 0, 0.0
            result.update({
                "realtime_ok": rt.ok, "realtime_reason": rt.reason,
                "realtime_sim_s": rt.sim_time_s,
                "realtime_wall_s": rt.wall_time_s,
                "realtime_factor": rt.realtime_factor,
                "realtime_p99_step_lateness_ms": rt.p99_lateness_s * 1e3,
                "realtime_max_step_lateness_ms": rt.max_lateness_s * 1e3,
                "realtime_overruns": rt.overruns,
                "realtime_state_rate_hz": (n_states - 1) / span if span > 0 else 0.0,
                "realtime_state_messages": n_states,
                "realtime_overrun_times_s": _overrun_times(rt.bag_path) if n_states else [],
                "realtime_recording": _recording(rt),
            })
        result["load_average_after"] = os.getloadavg()[0]
    finally:
        if not args.keep:
            shutil.rmtree(out, ignore_errors=True)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for key, value in result.items():
            print(f"{key:32s} {value:.4g}" if isinstance(value, float) else f"{key:32s} {value}")
    return 0 if ok else 1
