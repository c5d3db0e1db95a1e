# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""No start-up deadlock for any controller: short lockstep runs with user controllers written
from docs/controller-contract.md -- the shipped example controller and the contract controller
(it waits for each tick's driver input) -- beside a CPU hog of two busy processes, every one
complete and ok. Before the answer chain was durable, 1 of 15 contract-controller runs and 3
of 13 example-controller runs beside a hog stalled at t = 0 (the controller never received the
first driver input). bench/startup.py runs the long version (150 runs)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from fourws_ros.graph_run import run_graph

ROOT = Path(__file__).resolve().parent.parent


def _bench():
    """bench/startup.py (the benchmark's own run description)."""
    spec = importlib.util.spec_from_file_location("startup_bench", ROOT / "bench" / "startup.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


RUNS_PER_CONTROLLER = 5


@pytest.fixture
def cpu_hog():
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    try:
        yield
    finally:
        for h in hogs:
            h.kill()
            h.wait()


@pytest.mark.parametrize("controller", ["example", "contract"])
def test_user_controllers_start_every_time_beside_a_cpu_hog(tmp_path, cpu_hog, controller):
    """Five 1-s lockstep runs per controller: each ends ok with a complete bag of 100 states
    answered (no hang, no failure)."""
    config = _bench().short_config(1.0, controller)
    for k in range(RUNS_PER_CONTROLLER):
        run = run_graph(config, tmp_path, run_name=f"{controller}-{k}", echo=lambda _: None)
        assert run.ok, f"run {k}: {run.reason}"
        assert run.complete and run.message_counts["/fourws/rear_steer_cmd"] == 100
