# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A launcher participant that cannot be closed (Fast DDS 3.2 can deadlock destroying a
publisher, eProsima/Fast-DDS#6502) costs a bounded wait, is kept, never destroyed, with the
run's domain lease, and the process leaves with its exit code instead of hanging at exit."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
import types

from fourws_ros import launcher_node


def _stuck_launcher(release: threading.Event) -> types.SimpleNamespace:
    """An object with the launcher's ROS parts whose executor shutdown blocks until
    ``release`` (as the deadlocked destroy does, for ever)."""
    calls: list[str] = []
    return types.SimpleNamespace(
        calls=calls,
        executor=types.SimpleNamespace(shutdown=lambda timeout_sec: release.wait()),
        node=types.SimpleNamespace(destroy_node=lambda: calls.append("node")),
        context=types.SimpleNamespace(try_shutdown=lambda: calls.append("context")))


def _python(code: str) -> subprocess.CompletedProcess:
    """``code`` run by a fresh interpreter, its output captured."""
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)


def test_a_stuck_close_returns_after_its_timeout_and_keeps_the_lease(monkeypatch):
    monkeypatch.setattr(launcher_node, "CLOSE_TIMEOUT_S", 0.3)
    monkeypatch.setattr(launcher_node, "ABANDONED", [])
    release = threading.Event()
    fake = _stuck_launcher(release)
    t0 = time.monotonic()
    assert launcher_node.LauncherNode.close(fake, keep="the lease") == launcher_node.STUCK
    assert time.monotonic() - t0 >= 0.3  # it waited its timeout, no less
    assert launcher_node.ABANDONED == [(fake, "the lease")]
    assert fake.calls == []  # nothing destroyed past the stuck call
    release.set()


def test_a_close_that_ends_keeps_nothing(monkeypatch):
    monkeypatch.setattr(launcher_node, "ABANDONED", [])
    release = threading.Event()
    release.set()
    fake = _stuck_launcher(release)
    assert launcher_node.LauncherNode.close(fake, keep="the lease") == launcher_node.CLOSED
    assert fake.calls == ["node", "context"] and launcher_node.ABANDONED == []


def test_the_command_lines_participants_are_kept_not_destroyed(monkeypatch):
    """KEEP_PARTICIPANTS (set by fourws for its graph commands, which leave with os._exit):
    nothing is destroyed, the participant and its lease are kept."""
    monkeypatch.setattr(launcher_node, "ABANDONED", [])
    monkeypatch.setattr(launcher_node, "KEEP_PARTICIPANTS", True)
    fake = _stuck_launcher(threading.Event())  # a destroy would block this test for ever
    assert launcher_node.LauncherNode.close(fake, keep="the lease") == launcher_node.KEPT
    assert fake.calls == [] and launcher_node.ABANDONED == [(fake, "the lease")]


def test_a_participant_on_the_users_domain_is_destroyed_even_where_they_are_kept(monkeypatch):
    """The user's ROS_DOMAIN_ID is the domain of every run of the command: its lease cannot be
    kept with the participant (a demo's second run would be refused: 'domain N is used by
    another fourws run')."""
    monkeypatch.setattr(launcher_node, "ABANDONED", [])
    monkeypatch.setattr(launcher_node, "KEEP_PARTICIPANTS", True)
    release = threading.Event()
    release.set()
    fake = _stuck_launcher(release)
    assert launcher_node.LauncherNode.close(fake, keep="the lease", destroy=True) \
        == launcher_node.CLOSED
    assert fake.calls == ["node", "context"] and launcher_node.ABANDONED == []


def test_a_close_stuck_holding_the_interpreter_ends_the_process():
    """The destroy deadlocks in C holding the interpreter (no Python code runs again, the
    close's own timeout included): faulthandler's thread writes the stacks and exits, code 1,
    CLOSE_TIMEOUT_S + CLOSE_BACKSTOP_S later, instead of a process that never ends."""
    code = (
        "import ctypes, types\n"
        "from fourws_ros import launcher_node\n"
        "launcher_node.CLOSE_TIMEOUT_S, launcher_node.CLOSE_BACKSTOP_S = 0.2, 0.5\n"
        "def stuck_destroy():\n"
        "    libc, mutex = ctypes.PyDLL(None), ctypes.create_string_buffer(64)\n"
        "    libc.pthread_mutex_lock(mutex)\n"
        "    libc.pthread_mutex_lock(mutex)\n"
        "fake = types.SimpleNamespace(\n"
        "    executor=types.SimpleNamespace(shutdown=lambda timeout_sec: None),\n"
        "    node=types.SimpleNamespace(destroy_node=stuck_destroy),\n"
        "    context=types.SimpleNamespace(try_shutdown=lambda: None))\n"
        "launcher_node.LauncherNode.close(fake)\n"
        "print('never here')\n")
    res = _python(code)
    assert res.returncode == 1, res.stderr
    assert "never here" not in res.stdout
    assert "Timeout (0:00:00.700000)!" in res.stderr
    assert "in stuck_destroy" in res.stderr


def test_fourws_leaves_with_its_exit_code_while_holding_a_stuck_participant():
    """A process holding an abandoned participant leaves at once with the command's code,
    its output flushed; a non-daemon thread that would keep a normal exit waiting (as the
    stuck participant's destructor would) is not waited for."""
    code = (
        "import threading, sys\n"
        "from fourws_ros import launcher_node\n"
        "from fourws_cli.main import _leave_if_stuck\n"
        "threading.Thread(target=threading.Event().wait).start()\n"
        "launcher_node.ABANDONED.append((object(), None))\n"
        "print('summary line', end='')\n"
        "_leave_if_stuck(3)\n")
    res = _python(code)
    assert res.returncode == 3, res.stderr
    assert res.stdout == "summary line"


def _starting_launcher(status_after: int | None, final: bool = False) -> types.SimpleNamespace:
    """A launcher whose start request is never answered (the reply lost); its simulator's
    status says it runs after ``status_after`` spins (None: never)."""
    state = launcher_node.RunState()
    spins = []

    def spin_once(timeout_sec):
        spins.append(timeout_sec)
        if status_after is not None and len(spins) >= status_after:
            state.sim = types.SimpleNamespace(running=not final, final=final)

    never = types.SimpleNamespace(done=lambda: False)
    return types.SimpleNamespace(
        state=state, spins=spins, executor=types.SimpleNamespace(spin_once=spin_once),
        pause=types.SimpleNamespace(call_async=lambda request: never))


def test_a_lost_start_answer_counts_once_the_simulator_says_it_runs(monkeypatch):
    """The simulator took the start request but its reply never came (seen: rmw's 'failed to
    send response (timeout)' with a rogue flooding the domain, and the run failed as 'the
    simulator did not answer the start request' while it ran): its own running (or final)
    status is the answer; with neither, the start fails after START_TIMEOUT_S."""
    monkeypatch.setattr(launcher_node, "START_TIMEOUT_S", 0.5)
    for final in (False, True):
        fake = _starting_launcher(status_after=3, final=final)
        assert launcher_node.LauncherNode.start_simulation(fake) is True
        assert len(fake.spins) == 3
    silent = _starting_launcher(status_after=None)
    assert launcher_node.LauncherNode.start_simulation(silent) is False
    paused = _starting_launcher(status_after=1)
    paused.executor.spin_once = lambda timeout_sec: setattr(
        paused.state, "sim", types.SimpleNamespace(running=False, final=False))
    assert launcher_node.LauncherNode.start_simulation(paused) is False  # paused: no start


def test_the_launcher_asks_the_graph_for_names_at_most_every_refresh_period(monkeypatch):
    """The launcher spins once per status message; it refreshes the status publishers' names
    once per NAMES_REFRESH_S (0.1 s), not per spin: 100 spins 5 ms apart (0.5 s on a fake
    clock) ask the graph 5 times, each time for the three status topics, and every spin runs
    the executor."""
    clock = [1000.0]
    # the launcher module's clock only (time.monotonic itself serves every thread here)
    monkeypatch.setattr(launcher_node, "time", types.SimpleNamespace(monotonic=lambda: clock[0]))
    refreshed: list[tuple[str, ...]] = []
    spins: list[float] = []
    fake = types.SimpleNamespace(
        names=types.SimpleNamespace(refresh=lambda *t: refreshed.append(t)),
        executor=types.SimpleNamespace(spin_once=lambda timeout_sec: spins.append(timeout_sec)),
        _names_refreshed=-float("inf"))
    for _ in range(100):
        launcher_node.LauncherNode.spin(fake, 0.05)
        clock[0] += 0.005
    assert len(spins) == 100
    assert len(refreshed) == round(100 * 0.005 / launcher_node.NAMES_REFRESH_S) == 5
    assert set(refreshed) == {(launcher_node.topics.MANEUVER_STATUS,
                               launcher_node.topics.SIM_STATUS,
                               launcher_node.topics.RECORDER_STATUS)}
