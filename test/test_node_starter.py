# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A node forked by the node starter is what a node started with ``exec`` is to the launcher
(fourws_cli.node_starter): its child, in its own session, with its command line, the run's
environment, its log, its exit code and its signals; a starter that is gone or refuses
leaves the node to be started as its own program, and nothing outlives its launcher."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from fourws_cli import node_starter
from fourws_ros import processes
from fourws_ros.processes import ProcessGroup, node_command
from fourws_ros.runtime import EXIT_USER_ERROR

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="no node starter here")


@pytest.fixture(autouse=True)
def _installed(monkeypatch):
    """The starter switched on (FOURWS_NODE_STARTER=1, whatever the suite runs with) and
    installed as ``fourws run`` installs it; stopped after the test, and the suite's own
    installation (conftest) given back for the tests after this file."""
    suite_spawner = list(processes._NODE_SPAWNER)
    monkeypatch.setenv(node_starter.ENABLE_ENV, "1")
    assert node_starter.enabled()
    node_starter.install(start=False)
    yield
    node_starter.shutdown()
    processes.use_node_spawner(suite_spawner[0] if suite_spawner else None)


def _bad_params(tmp_path: Path) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text("fourws_simulator:\n  ros__parameters:\n    model: 9dof\n")
    return path


def _proc_status(pid: int) -> dict[str, str]:
    out = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        key, _, value = line.partition(":")
        out[key] = value.strip()
    return out


def test_a_forked_node_is_the_launchers_child_with_its_own_session_and_title(
        tmp_path, ros_domain):
    group = ProcessGroup(tmp_path / "logs", dict(os.environ), print)
    cmd = node_command("maneuver", params={"maneuver": "step_steer_85kmh"})
    child = group.start("fourws_maneuver", cmd)
    try:
        assert isinstance(child.proc, node_starter.ForkedProcess)
        pid = child.proc.pid
        assert int(_proc_status(pid)["PPid"]) == os.getpid()
        assert os.getpgid(pid) == pid and os.getsid(pid) == pid
        cmdline = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        assert cmdline.strip() == " ".join(cmd)
        deadline = time.monotonic() + 60.0
        while not child.phase_log and time.monotonic() < deadline:
            group.read_phases()
            time.sleep(0.01)
        assert child.phase_log, "the node reported no start-up phase on its pipe"
        assert child.alive()
    finally:
        codes = group.stop()
    assert codes["fourws_maneuver"] == 0  # SIGINT: a clean stop


def test_a_forked_nodes_refusal_is_its_exit_code_and_its_log(tmp_path):
    group = ProcessGroup(tmp_path / "logs", dict(os.environ), print)
    child = group.start("fourws_simulator", node_command("simulator", _bad_params(tmp_path)))
    assert isinstance(child.proc, node_starter.ForkedProcess)
    assert child.proc.wait(timeout=120) == EXIT_USER_ERROR
    log = child.log_tail()
    assert "9dof" in log and "Traceback" not in log


def test_zero_starts_every_node_as_its_own_program(tmp_path, monkeypatch):
    """FOURWS_NODE_STARTER=0 (the starter is on by default): the node is exec'd, a Popen."""
    monkeypatch.setenv(node_starter.ENABLE_ENV, "0")
    assert not node_starter.enabled()
    group = ProcessGroup(tmp_path / "logs", dict(os.environ), print)
    child = group.start("fourws_simulator", node_command("simulator", _bad_params(tmp_path)))
    assert isinstance(child.proc, subprocess.Popen)
    assert child.proc.wait(timeout=120) == EXIT_USER_ERROR
    monkeypatch.delenv(node_starter.ENABLE_ENV)
    assert node_starter.enabled()  # unset: on


def test_a_killed_node_reports_the_signal(tmp_path, ros_domain):
    group = ProcessGroup(tmp_path / "logs", dict(os.environ), print)
    child = group.start("fourws_maneuver", node_command("maneuver"))
    child.proc.send_signal(signal.SIGKILL)
    assert child.proc.wait(timeout=60) == -signal.SIGKILL


def test_another_environment_gets_another_starter(tmp_path):
    node_starter.prestart()
    before = node_starter._STARTER[0]
    env = dict(os.environ, FOURWS_TEST_IMPORT_SETTING="1")  # as numba's settings are read
    group = ProcessGroup(tmp_path / "logs", env, print)
    child = group.start("fourws_simulator", node_command("simulator", _bad_params(tmp_path)))
    assert child.proc.wait(timeout=120) == EXIT_USER_ERROR
    after = node_starter._STARTER[0]
    assert after is not before and after.proc.pid != before.proc.pid
    assert before.proc.poll() is not None  # the old one was stopped
    assert after.env["FOURWS_TEST_IMPORT_SETTING"] == "1"
    # a run's own variables (the domain) do not restart it
    group = ProcessGroup(tmp_path / "logs2", dict(env, ROS_DOMAIN_ID="99"), print)
    child = group.start("fourws_simulator", node_command("simulator", _bad_params(tmp_path)))
    assert child.proc.wait(timeout=120) == EXIT_USER_ERROR
    assert node_starter._STARTER[0] is after


def test_a_dead_starter_leaves_the_node_to_be_started_as_a_program(tmp_path):
    node_starter.prestart()
    starter = node_starter._STARTER[0]
    starter.proc.kill()
    starter.proc.wait()
    group = ProcessGroup(tmp_path / "logs", dict(os.environ), print)
    child = group.start("fourws_simulator", node_command("simulator", _bad_params(tmp_path)))
    assert isinstance(child.proc, subprocess.Popen)
    assert child.proc.wait(timeout=120) == EXIT_USER_ERROR
    # and the next node gets a new starter
    child = group.start("fourws_simulator2", node_command("simulator", _bad_params(tmp_path)))
    assert isinstance(child.proc, node_starter.ForkedProcess)
    assert child.proc.wait(timeout=120) == EXIT_USER_ERROR


_LAUNCHER = textwrap.dedent("""
    import os, sys, time
    from pathlib import Path
    from fourws_cli import node_starter
    from fourws_ros.processes import ProcessGroup, node_command
    node_starter.install()
    group = ProcessGroup(Path(sys.argv[1]), dict(os.environ), print)
    child = group.start("fourws_maneuver", node_command("maneuver"))
    print(child.proc.pid, node_starter._STARTER[0].proc.pid, flush=True)
    time.sleep(600)
""")


def test_nothing_outlives_a_killed_launcher(tmp_path, ros_domain):
    proc = subprocess.Popen([sys.executable, "-c", _LAUNCHER, str(tmp_path / "logs")],
                            stdout=subprocess.PIPE, text=True, start_new_session=True)
    try:
        node_pid, starter_pid = (int(x) for x in proc.stdout.readline().split())
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        deadline = time.monotonic() + 30.0
        alive = [node_pid, starter_pid]
        while alive and time.monotonic() < deadline:
            alive = [p for p in alive if Path(f"/proc/{p}").exists()
                     and _proc_status(p)["State"][0] != "Z"]
            time.sleep(0.05)
        assert alive == [], f"left running after the launcher was killed: {alive}"
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def test_a_stopped_starter_leaves_the_node_to_be_started_as_a_program(tmp_path):
    node_starter.prestart()
    starter = node_starter._STARTER[0]
    os.kill(starter.proc.pid, signal.SIGSTOP)
    try:
        group = ProcessGroup(tmp_path / "logs", dict(os.environ), print)
        child = group.start("fourws_simulator", node_command("simulator", _bad_params(tmp_path)))
        assert isinstance(child.proc, subprocess.Popen)
        assert child.proc.wait(timeout=120) == EXIT_USER_ERROR
        assert starter.broken and starter.proc.poll() is not None  # stopped for good
    finally:
        if starter.proc.poll() is None:
            os.kill(starter.proc.pid, signal.SIGKILL)


def test_a_node_the_launcher_gave_up_on_leaves_without_running(tmp_path):
    """The starter forked the node but its launcher did not take the answer (it timed out,
    or the starter died first): the node must not run beside the copy started instead."""
    node_starter.prestart()
    starter = node_starter._STARTER[0]
    assert starter._receive(node_starter.READY_TIMEOUT_S) == {"ready": True}
    starter._ready = True
    log = tmp_path / "node.log"
    cmd = node_command("simulator", _bad_params(tmp_path))
    request = {"cmd": cmd, "argv": cmd[4:], "env": dict(os.environ), "cwd": str(tmp_path),
               "launcher": os.getpid(), "sigmask": [], "ignored": []}
    phase_r, phase_w = os.pipe()
    go_r, go_w = os.pipe()
    with open(log, "wb") as f:
        socket.send_fds(starter._sock, [json.dumps(request).encode()], [f.fileno(), phase_w, go_r])
    os.close(go_r)
    os.close(phase_w)
    reply = starter._receive(node_starter.REPLY_TIMEOUT_S)
    os.close(go_w)  # given up: no go
    proc = node_starter.ForkedProcess(int(reply["pid"]), cmd)
    assert proc.wait(timeout=60) == 0
    assert log.read_bytes() == b""  # it never ran (a run refuses this file with exit 2)
    assert os.read(phase_r, 100) == b""  # and reported no phase
    os.close(phase_r)


_CREATE_NODES = textwrap.dedent("""
    import importlib, json, os, sys
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from fourws_cli import node_starter
    node_starter.prepare()
    params_file, out = sys.argv[1], sys.argv[2]
    classes = {"simulator": "fourws_ros.simulator_node:SimulatorNode",
               "maneuver": "fourws_ros.maneuver_node:ManeuverNode",
               "controller": "fourws_ros.controller_node:ControllerNode",
               "recorder": "fourws_ros.recorder_node:RecorderNode"}
    for name, target in classes.items():
        pid = os.fork()
        if pid == 0:
            module, _, cls = target.partition(":")
            before = set(sys.modules)
            rclpy.init(args=["x", "--ros-args", "--params-file", params_file],
                       signal_handler_options=SignalHandlerOptions.NO)
            node = getattr(importlib.import_module(module), cls)()
            with open(f"{out}.{name}", "w") as f:
                json.dump(sorted(set(sys.modules) - before), f)
            os._exit(0)
        os.waitpid(pid, 0)
""")


def test_a_node_forked_from_a_warm_starter_imports_nothing_while_it_is_created(
        tmp_path, ros_domain):
    """After the starter's preparation (fourws_cli.node_starter.prepare), creating each
    of the four nodes of a default run (sol1) in a forked process imports no module but the
    simulator's kernel variant: the messages, their type support, the tire and vehicle
    models and the laws a node loads on first use are the starter's, loaded once for every
    node (about 0.6 s of CPU per run of four nodes when each did it, measured)."""
    from fourws_ros import node_params
    from fourws_run.config import RunConfig
    from fourws_run.scenario import load_scenario

    config = RunConfig.from_scenario(load_scenario("default"), "sol1")
    params = node_params.node_parameters(config, tmp_path / "bag", False)
    params_file = node_params.write_params_file(tmp_path / "params.yaml", params)
    script = tmp_path / "create.py"
    script.write_text(_CREATE_NODES)
    out = tmp_path / "imported"
    res = subprocess.run([sys.executable, str(script), str(params_file), str(out)],
                         capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    imported = {name: json.loads(Path(f"{out}.{name}").read_text())
                for name in ("simulator", "maneuver", "controller", "recorder")}
    assert imported["maneuver"] == imported["controller"] == imported["recorder"] == []
    assert [m.partition("[")[0] for m in imported["simulator"]] == [
        "fourws_sim.models.eightdof_kernels"], imported["simulator"]
