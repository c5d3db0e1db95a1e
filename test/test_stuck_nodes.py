# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A fourws node stuck in C (a Fast DDS deadlock: eProsima/Fast-DDS#6502 is one) can neither
run its Python signal handlers nor its teardown timer. Such a node still ends: the launcher,
before it kills a node that ignored SIGINT and SIGTERM, has it write every thread's stack to
its log and repeats where its main thread is; a teardown stuck while holding the interpreter
ends by faulthandler's own thread; a recorder that closed its bag and then hangs costs the
run its teardown limit, not the run."""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time
from pathlib import Path

from fourws_ros import graph_run, runtime
from fourws_ros.processes import ProcessGroup
from fourws_run.config import RunConfig
from fourws_run.scenario import load_scenario
from stuck_node import STUCK_LINE

STUCK = Path(__file__).with_name("stuck_node.py")


def test_a_node_stuck_in_c_is_killed_with_its_stack_repeated(tmp_path, ros_domain):
    lines: list[str] = []
    group = ProcessGroup(tmp_path / "logs", dict(os.environ), lines.append, grace_s=1.0)
    child = group.start("fourws_stuck", [sys.executable, str(STUCK), "spin"])
    deadline = time.monotonic() + 120.0
    while STUCK_LINE not in child.log_tail() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert STUCK_LINE in child.log_tail()  # its timer fired: stuck from here on
    child.read_phases()
    assert child.phase == "ready"  # it reported its phases (a fourws node: it gets the dump)
    codes = group.stop(["fourws_stuck"])
    assert codes == {"fourws_stuck": -signal.SIGKILL}
    assert "  fourws_stuck ignored SIGINT, escalating" in lines
    assert "  fourws_stuck ignored SIGTERM, escalating" in lines
    # the main thread's innermost frame is the deadlocking call, named with its file
    frames = [line for line in lines if line.startswith("    ")]
    assert frames[0].startswith("    Current thread"), lines
    assert "stuck_node.py" in frames[1] and "deadlock_in_c" in frames[1], frames
    assert frames[-1] == f"    (every thread's stack: {child.log_path})"
    assert "deadlock_in_c" in child.log_path.read_text()


def test_a_teardown_stuck_holding_the_interpreter_still_exits(tmp_path, ros_domain):
    """No Python thread can run, so the teardown timer cannot: the interpreter-free backstop
    exits with code 1 after TEARDOWN_TIMEOUT_S + TEARDOWN_BACKSTOP_S, the stacks in the log."""
    group = ProcessGroup(tmp_path / "logs", dict(os.environ), print)
    child = group.start("fourws_stuck", [sys.executable, str(STUCK), "teardown"])
    limit = runtime.TEARDOWN_TIMEOUT_S + runtime.TEARDOWN_BACKSTOP_S
    try:
        code = child.proc.wait(timeout=120.0 + limit)
    finally:
        group.kill_all()
    assert code == 1
    log = child.log_path.read_text()
    assert f"Timeout (0:00:{limit:02.0f})!" in log
    assert "in destroy_node" in log and "deadlock_in_c" in log
    assert "the ROS teardown did not finish" not in log  # the Python timer never ran


def test_a_recorder_stopped_after_closing_its_bag_does_not_fail_the_run(
        tmp_path, monkeypatch, capfd):
    """The recorder is stopped (SIGSTOP) the moment it says it closed the bag (its closed
    status may not have reached the launcher): the bag's metadata.yaml is on disk, so the
    launcher stops the recorder at once and the run is ok, its bag complete (read from disk),
    instead of failing as a recorder stopped before the close (seen beside a CPU hog) or after
    RECORDER_GRACE_S."""
    monkeypatch.setattr(graph_run, "RECORDER_GRACE_S", 600.0)  # were it waited for: the test
    stopped = threading.Event()

    def stop_on_close(group) -> None:
        rec = group.child("fourws_recorder")

        def watch() -> None:
            while rec.alive():
                if "] closed " in rec.log_path.read_text(errors="replace"):
                    try:
                        os.kill(rec.proc.pid, signal.SIGSTOP)
                        stopped.set()
                    except ProcessLookupError:
                        pass
                    return
                time.sleep(0.001)

        threading.Thread(target=watch, daemon=True).start()

    config = RunConfig.from_scenario(load_scenario("default"), "sol1")
    for attempt in range(5):  # the recorder may exit before the watcher stops it
        stopped.clear()
        record = graph_run.run_graph(config, tmp_path / str(attempt), run_name="r",
                                     on_running=stop_on_close)
        if stopped.is_set():
            break
    assert stopped.is_set(), "the recorder always exited before it could be stopped"
    assert record.ok, record.reason
    assert record.complete
    assert record.message_counts["/fourws/state"] == 501
    # ended by the stopped-after-the-close rule, not by the grace of 600 s
    assert ("fourws_recorder closed the bag but is stopped (SIGSTOP); stopping it"
            in capfd.readouterr().err)


def test_the_record_is_on_disk_before_the_launchers_participant_closes(tmp_path, monkeypatch):
    """A close that never ends (a Fast DDS deadlock holding the interpreter ends the process)
    cannot take the run's verdict along: run.json is complete when the close begins."""
    from fourws_ros import launcher_node
    seen = []
    close = launcher_node.LauncherNode.close

    def checked_close(self, keep=None, destroy=False):
        record = json.loads((tmp_path / "r" / "run.json").read_text())
        seen.append((record["outcome"], record["message_counts"]["/fourws/state"]))
        return close(self, keep, destroy)

    monkeypatch.setattr(launcher_node.LauncherNode, "close", checked_close)
    config = RunConfig.from_scenario(load_scenario("default"), "fws")
    record = graph_run.run_graph(config, tmp_path, run_name="r")
    assert record.ok, record.reason
    assert seen == [(record.outcome.value, 501)] and record.outcome.value == "completed"
