# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The verdict of graph runs at the edges: a spun car is never ok, a realtime controller that
stops answering or sends unusable commands fails the run naming it, a user's controller is
labelled with the law its commands name. Each run goes through the real node graph."""

from __future__ import annotations

import dataclasses
import json
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fourws_analysis.bag import load_bag
from fourws_ros import graph_run, topics
from fourws_run.closed_loop import run_twin
from fourws_run.config import USER_LAW, ControllerSpec, RunConfig
from fourws_run.record import Outcome
from fourws_run.scenario import load_scenario
from fourws_sim.maneuvers import maneuver_spec_from_mapping
from fourws_sim.outcome import SPUN

CONTROLLER = Path(__file__).with_name("contract_controller.py")


def _scenario(**maneuver):
    sc = load_scenario("default")
    spec = {**sc.maneuver.to_dict(), **maneuver}
    return dataclasses.replace(sc, maneuver=maneuver_spec_from_mapping(spec))


def test_a_step_steer_at_85_mps_spins_and_the_run_says_so(tmp_path):
    """initial_speed_mps 85 (km/h meant): the car spins. The graph run ends SPUN (exit
    code 3) at the first state beyond 20 deg of sideslip -- the same tick as the offline
    twin's end -- with a complete bag; the run is not ok."""
    sc = _scenario(initial_speed_mps=85.0, duration_s=3.0)
    config = RunConfig.from_scenario(sc, "fws")
    run = graph_run.run_graph(config, tmp_path, run_name="spin")
    assert run.outcome == Outcome.SPUN and run.exit_code == 3 and not run.ok, run.reason
    assert run.reason.startswith("the car spun: |sideslip|")
    assert run.complete
    twin = run_twin(config)
    assert twin.end_kind == SPUN and twin.end_reason in run.reason
    state = load_bag(run.bag_path).topics[topics.STATE]
    n = twin.time_s.size
    assert len(state) == n + 1  # every answered state, and the one that broke the rule
    np.testing.assert_array_equal(state.fields["sideslip_rad"][:n], twin["sideslip_rad"])
    assert abs(state.fields["sideslip_rad"][n]) > np.radians(20.0)


def _user_run(tmp_path: Path, name: str, clock: str, extra: tuple[str, ...] = (),
              on_running=None, **overrides):
    sc = dataclasses.replace(_scenario(duration_s=3.0), clock_mode=clock, state_period_s=0.005
                             if clock == "realtime" else 0.01)
    ctrl = ControllerSpec((sys.executable, str(CONTROLLER), *extra))
    config = RunConfig.from_scenario(sc, USER_LAW, ctrl)
    return graph_run.run_graph(config, tmp_path, run_name=name, on_running=on_running,
                               node_overrides=overrides or None)


def test_realtime_nan_commands_fail_the_run_naming_the_controller(tmp_path):
    """Realtime, a controller whose commands are NaN from t = 1 s: every one is refused
    (impossible values); the held command goes stale and the run fails, naming the
    controller node -- never ok with two thirds of the commands refused."""
    run = _user_run(tmp_path, "nan", "realtime", ("--nan-from", "1.0"))
    assert run.outcome == Outcome.FAILED, run.reason
    assert "the controller node (fourws_controller)" in run.reason
    assert "refused as unusable" in run.reason or "without a fresh command" in run.reason
    refused = sum(n for k, n in run.rejections.items() if "impossible values" in k)
    assert refused > 100  # 2 of the 3 s at 200 Hz states


def test_realtime_stopped_controller_fails_the_run(tmp_path):
    """Realtime, the controller stopped (SIGSTOP) once the run is going: the simulator runs
    on with zero rear steer (it cannot wait), counts every stale tick, and the run fails
    naming the controller."""
    def freeze(group):
        group.child("fourws_controller").proc.send_signal(signal.SIGSTOP)

    run = _user_run(tmp_path, "stopped", "realtime", on_running=freeze)
    assert run.outcome == Outcome.FAILED, run.reason
    assert "fourws_controller" in run.reason and "without a fresh command" in run.reason
    assert run.stale_commands > 0.5 * run.control_ticks


def test_a_user_controller_run_takes_the_law_its_commands_name(tmp_path):
    """The contract: the run's label is the law the commands name, in the record and in
    run.json (the folder keeps its given name)."""
    run = _user_run(tmp_path, "label", "lockstep")
    assert run.ok, run.reason
    assert run.law == "contract_zero_sideslip"
    saved = json.loads((run.run_dir / "run.json").read_text())
    assert saved["law"] == "contract_zero_sideslip"


@pytest.mark.parametrize("args", [["--controller", "python /no/such/controller.py"],
                                  ["--controller", "no-such-program-here"]])
def test_a_missing_controller_is_refused_before_anything_runs(tmp_path, args):
    """A --controller whose script or program does not exist: one line naming it, exit
    code 2, no run folder."""
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "run", *args,
                          "--out", str(tmp_path / "o")], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 2, res.stdout + res.stderr
    assert "controller.command" in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
