# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The ROS 2 workspace flow, as a ROS user types it, from ``ws/src/fourws``: ``colcon build``
(no flags), ``source install/setup.bash``, the installed node executables with the installed
parameter file, and ``colcon test``.

colcon comes from PyPI and builds against this environment's ROS 2 (the venv's wheels, or a
system install). The copy of the checkout is what a clone holds (``git ls-files``). Sources of
the numbers: the lockstep tick count of a maneuver (duration / control period, one state more
than answers), the offline closed loop (fourws_run.closed_loop, the same tick sequence the
lockstep graph runs), and the two tests the selected ``colcon test`` run holds.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml

from fourws_analysis.bag import load_bag
from fourws_cli.nodes import NODES
from fourws_run import interface
from fourws_run.closed_loop import run_closed_loop
from fourws_sim.maneuvers import load_maneuver_spec
from fourws_sim.params import load_vehicle

ROOT = Path(__file__).resolve().parent.parent
#: Bounds (s) of the steps; a loaded 2-core machine builds in about 1 min.
BUILD_TIMEOUT_S = 900
RUN_TIMEOUT_S = 180
TEST_TIMEOUT_S = 600
#: The short maneuver of the run (the shipped step steer, shortened).
DURATION_S = 1.0

pytestmark = pytest.mark.skipif(shutil.which("colcon") is None and
                                not (Path(sys.prefix) / "bin" / "colcon").exists(),
                                reason="colcon is not installed (pip install "
                                       "colcon-common-extensions, see requirements.txt)")


def _environment() -> dict[str, str]:
    """This environment, with the venv's ROS 2 prefix on the search paths if it has one
    (what an activated venv with the ROS wheels amounts to)."""
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.prefix) / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    if (Path(sys.prefix) / "share" / "ament_index").is_dir():
        env["VIRTUAL_ENV"] = sys.prefix
        for var in ("CMAKE_PREFIX_PATH", "AMENT_PREFIX_PATH"):
            env[var] = os.pathsep.join(p for p in (sys.prefix, env.get(var)) if p)
    env.pop("PYTEST_ADDOPTS", None)
    return env


def _copy_checkout(dest: Path) -> None:
    """The files of a clone (tracked, and new ones not ignored), or the tree minus build
    products when this is no git checkout."""
    listed = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-z", "-co",
                             "--exclude-standard"], capture_output=True)
    if listed.returncode != 0:
        shutil.copytree(ROOT, dest, ignore=shutil.ignore_patterns(
            ".venv", "build", "install", "log", "runs", "report", "__pycache__", ".git"))
        return
    for name in listed.stdout.decode().split("\0"):
        if name and (ROOT / name).is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, dest / name)


def _run(cmd: list[str], cwd: Path, env: dict[str, str], timeout_s: float,
         what: str) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout_s)
    assert done.returncode == 0, f"{what} failed:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> tuple[Path, dict[str, str]]:
    """``ws/src/fourws`` built with a plain ``colcon build``; the environment of
    ``source install/setup.bash``."""
    ws = tmp_path_factory.mktemp("ws")
    src = ws / "src" / "fourws"
    src.mkdir(parents=True)
    _copy_checkout(src)
    env = _environment()
    _run(["colcon", "build"], ws, env, BUILD_TIMEOUT_S, "colcon build")
    sourced = _run(["bash", "-c", "source install/setup.bash && env -0"], ws, env, 60,
                   "source install/setup.bash")
    installed = dict(line.split("=", 1) for line in sourced.stdout.split("\0") if "=" in line)
    return ws, installed


def test_build_installs_the_nodes_messages_config_and_launch_file(workspace) -> None:
    ws, env = workspace
    prefix = ws / "install" / "fourws"
    # ros2 run fourws <node> looks in lib/fourws: one executable per node of fourws node
    assert sorted(p.name for p in (prefix / "lib" / "fourws").iterdir()) == sorted(NODES)
    share = prefix / "share" / "fourws"
    assert sorted(p.name for p in (share / "msg").glob("*.msg")) \
        == sorted(p.name for p in (ROOT / "msg").glob("*.msg"))
    for sub in ("vehicles", "maneuvers", "scenarios", "params"):
        assert sorted(p.name for p in (share / "config" / sub).iterdir()) \
            == sorted(p.name for p in (ROOT / "config" / sub).iterdir())
    assert (share / "launch" / "fourws.launch.py").is_file()
    # the installed code finds the installed folders (no checkout beside it), from anywhere
    found = _run([env.get("PYTHON", sys.executable), "-c",
                  "from fourws_run.bagfile import MSG_DIR; from fourws_sim.params import "
                  "CONFIG_DIR; import fourws_sim; print(MSG_DIR); print(CONFIG_DIR); "
                  "print(fourws_sim.__file__)"], ws, env, 120, "installed resource folders")
    msg_dir, config_dir, module = found.stdout.split()
    assert Path(msg_dir) == share / "msg" and Path(config_dir) == share / "config"
    assert Path(module).is_relative_to(prefix)


def test_installed_nodes_run_a_lockstep_graph(workspace, ros_domain, tmp_path) -> None:
    """simulator, maneuver, controller and recorder as installed, with the installed lockstep
    parameter file (a shorter maneuver, a bag path); the bag loads complete and matches the
    offline closed loop."""
    ws, env = workspace
    env = {**env, "ROS_DOMAIN_ID": str(ros_domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    share = ws / "install" / "fourws" / "share" / "fourws"
    params_file = share / "config" / "params" / "lockstep.yaml"
    spec = load_maneuver_spec("step_steer_85kmh").to_dict()
    spec["duration_s"] = DURATION_S
    maneuver = tmp_path / "short.yaml"
    maneuver.write_text(yaml.safe_dump(spec))
    bag = tmp_path / "bag"
    extra = {"simulator": [],
             "maneuver": [f"maneuver:={maneuver}"], "controller": [],
             "recorder": [f"bag_path:={bag}"]}
    procs = {}
    try:
        for node, params in extra.items():
            cmd = [str(ws / "install" / "fourws" / "lib" / "fourws" / node), "--ros-args",
                   "--params-file", str(params_file)]
            for p in params:
                cmd += ["-p", p]
            procs[node] = subprocess.Popen(cmd, cwd=tmp_path, env=env, start_new_session=True,
                                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        outputs = {node: p.communicate(timeout=RUN_TIMEOUT_S)[0].decode(errors="replace")
                   for node, p in procs.items()}
    finally:
        for p in procs.values():
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
    codes = {node: p.returncode for node, p in procs.items()}
    assert set(codes.values()) == {0}, (codes, outputs)

    run = load_bag(bag)
    assert run.complete is True
    ticks = int(round(DURATION_S / 0.01))  # lockstep.yaml: control_period_s 0.01
    state = run.topics[interface.STATE]
    assert len(state) == ticks + 1
    assert len(run.topics[interface.DRIVER_INPUT]) == ticks
    commands = run.topics[interface.REAR_STEER_CMD]
    assert len(commands) == ticks
    # the same run offline: the installed graph computes what the checkout's twin computes
    sim = yaml.safe_load(params_file.read_text())["fourws_simulator"]["ros__parameters"]
    vehicle = load_vehicle(sim["vehicle"])
    ref = run_closed_loop(vehicle, spec, "sol1", model=sim["model"],
                          dt_s=sim["integration_step_s"],
                          control_period_s=sim["control_period_s"], integrator=sim["integrator"])
    np.testing.assert_allclose(commands.fields["angle_rad"], ref.rear_angle_rad,
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(state.fields["yaw_rate_radps"][:ticks], ref["yaw_rate_radps"],
                               rtol=0, atol=1e-9)


def test_colcon_test_runs_the_suite_and_reports_a_failure(workspace) -> None:
    """``colcon test`` runs pytest on test/ (here three tests chosen with PYTEST_ADDOPTS: two
    passing, one of them the check that the install is the sources, which runs only with the
    install prefix the CTest registration hands it, and one added that fails): the result
    holds the three, none skipped, one failed, and ``colcon test-result`` exits non-zero."""
    ws, env = workspace
    failing = ws / "src" / "fourws" / "test" / "test_zz_fails_on_purpose.py"
    failing.write_text("def test_fails_on_purpose():\n    assert 1 + 1 == 3\n")
    selected = ("test_checkout_folders_are_found or test_fails_on_purpose or "
                "test_installed_python_packages_are_the_sources")
    env = {**env, "PYTEST_ADDOPTS": f"-p no:cacheprovider -k '{selected}'"}
    done = subprocess.run(["colcon", "test"], cwd=ws, env=env, capture_output=True, text=True,
                          timeout=TEST_TIMEOUT_S)
    failing.unlink()
    assert "1 package had test failures: fourws" in done.stdout + done.stderr, done.stdout
    result = subprocess.run(["colcon", "test-result", "--all"], cwd=ws, env=env,
                            capture_output=True, text=True, timeout=60)
    assert result.returncode != 0
    xml = ws / "build" / "fourws" / "test_results" / "fourws" / "pytest.xunit.xml"
    suite = ET.parse(xml).getroot()
    suite = suite if suite.tag == "testsuite" else suite.find("testsuite")
    assert (int(suite.get("tests")), int(suite.get("failures")),
            int(suite.get("skipped", 0))) == (3, 1, 0)
