# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A graph started by hand, node by node with the shipped parameter file (what a ROS 2 user
does with `ros2 run`), gives a bag as good as `fourws run`'s: complete, self-describing, and
analysable with the right law's name; the run ends by itself when the maneuver is done."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np

from fourws_analysis.bag import load_bag
from fourws_ros import topics
from fourws_run.closed_loop import run_scenario
from fourws_run.scenario import load_scenario
from fourws_sim.params import CONFIG_DIR

PARAMS = CONFIG_DIR / "params" / "lockstep.yaml"


def _node(name: str, *args: str, env: dict) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "fourws_cli.main", "node", name,
                             "--ros-args", "--params-file", str(PARAMS), *args],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                            start_new_session=True)


def _outputs(procs: dict[str, subprocess.Popen], timeout_s: float) -> dict[str, str]:
    """Each node's output once it ended; a node still running ``timeout_s`` after the one
    before it ended fails the test with every node's last lines (which one waits for what)."""
    outs: dict[str, str] = {}
    late = ""
    try:
        for name, proc in procs.items():
            late = name
            outs[name] = proc.communicate(timeout=timeout_s)[0].decode(errors="replace")
        late = ""
    except subprocess.TimeoutExpired:
        pass
    finally:
        for proc in procs.values():
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
    if late:
        for name, proc in procs.items():
            if name not in outs:
                outs[name] = proc.communicate()[0].decode(errors="replace")
        tails = "\n".join(f"--- {name} (exit {procs[name].returncode}):\n"
                          + "\n".join(out.splitlines()[-8:]) for name, out in outs.items())
        raise AssertionError(f"node {late} still running after {timeout_s:g} s\n{tails}")
    return outs


def test_hand_started_lockstep_graph_ends_by_itself_with_a_complete_described_bag(
        tmp_path, ros_domain):
    bag = tmp_path / "bag"
    env = dict(os.environ)
    procs = {
        "recorder": _node("recorder", "-p", f"bag_path:={bag}", env=env),
        "controller": _node("controller", env=env),
        "maneuver": _node("maneuver", env=env),
        "simulator": _node("simulator", env=env),
    }
    outs = _outputs(procs, 180.0)
    for name, proc in procs.items():
        assert proc.returncode == 0, f"{name}: {outs[name]}"
    assert "complete" in outs["recorder"]
    run = load_bag(bag)
    assert run.complete is True
    # no launcher: the run description comes from the nodes themselves
    assert topics.RUN_CONFIG not in run.topics
    assert run.config["law"] == "sol1"
    assert run.maneuver == "step_steer"
    assert run.config["vehicle"]["name"] == "table_8_1"
    # and the states are those of the same run through fourws run / its offline twin
    sc = load_scenario("default")
    ref = run_scenario(sc, "sol1")
    state = run.topics[topics.STATE]
    np.testing.assert_array_equal(state.fields["yaw_rate_radps"][:ref.time_s.size],
                                  ref["yaw_rate_radps"])
    # fourws analyze computes the ISO 7401 step metrics and names the law right
    out = tmp_path / "report"
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "analyze", str(bag),
                          "--report", str(out), "--json", "--quiet"], capture_output=True,
                         text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    metrics = json.loads((out / "metrics.json").read_text())
    (entry,) = metrics["runs"].values()
    assert entry["law"] == "sol1"
    assert entry["iso7401_step"]


def test_hand_started_graph_whose_recorder_refuses_its_bag_ends_with_its_reason(
        tmp_path, ros_domain):
    """The README recipe run a second time: the bag folder exists, the recorder refuses it
    (exit 2) and says why on /fourws/node_config; the simulator, the maneuver and the
    controller stop with the recorder's reason instead of waiting -- every process is gone
    well within the start-up timeout (120 s). A node that read the announcement gave up on a
    peer (exit 5); one that heard of it first in the simulator's final status ends as at the
    end of a run (exit 0), saying the simulation ended first, with that reason."""
    bag = tmp_path / "bag"
    bag.mkdir()  # what the first run left
    env = dict(os.environ)
    procs = {
        "recorder": _node("recorder", "-p", f"bag_path:={bag}", env=env),
        "controller": _node("controller", env=env),
        "maneuver": _node("maneuver", env=env),
        "simulator": _node("simulator", env=env),
    }
    outs = {}
    try:
        for name, proc in procs.items():
            outs[name] = proc.communicate(timeout=100)[0].decode(errors="replace")
    finally:
        for proc in procs.values():
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
    assert procs["recorder"].returncode == 2, outs["recorder"]
    assert "exists" in outs["recorder"]
    assert procs["simulator"].returncode == 5, outs["simulator"]
    for name in ("simulator", "maneuver", "controller"):
        assert procs[name].returncode in (0, 5), f"{name}: {outs[name]}"
        assert "Traceback" not in outs[name]
    for name in ("simulator", "maneuver"):
        assert "fourws_recorder refused its configuration" in outs[name], outs[name]
