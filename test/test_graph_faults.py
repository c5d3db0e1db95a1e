# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The node graph under attack: rogue publishers, killed and stopped nodes, runs side by side
under a CPU hog. Every case ends in a complete, exact record or a failure naming the cause.

The reference for "exact" is the offline twin (:func:`fourws_run.closed_loop.run_closed_loop`):
a lockstep graph run performs its float operations in the same order, so its recorded states
equal the twin's bit for bit.
"""

from __future__ import annotations

import dataclasses
import os
import selectors
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

from fourws_analysis.bag import load_bag
from fourws_ros import graph_run, topics
from fourws_ros.domains import reserve_domain_id
from fourws_run.bagfile import repair_bag
from fourws_run.closed_loop import run_scenario
from fourws_run.config import RunConfig
from fourws_run.record import Outcome
from fourws_run.scenario import load_scenario
from fourws_sim.maneuvers import maneuver_spec_from_mapping

ROGUE = Path(__file__).with_name("rogue_node.py")


def _scenario(duration_s: float, **changes):
    sc = load_scenario("default")
    spec = sc.maneuver.to_dict()
    spec["duration_s"] = duration_s
    return dataclasses.replace(sc, maneuver=maneuver_spec_from_mapping(spec), **changes)


def _assert_equals_twin(bag_path: Path, sc, law: str) -> None:
    """The recorded states are the offline twin's, bit for bit, none missing."""
    ref = run_scenario(sc, law)
    state = load_bag(bag_path).topics[topics.STATE]
    n = ref.time_s.size
    assert len(state) == n + 1  # every tick's state and the final one
    np.testing.assert_array_equal(state.fields["sim_time_s"][:n], ref.time_s)
    np.testing.assert_array_equal(state.fields["yaw_rate_radps"][:n], ref["yaw_rate_radps"])


@pytest.fixture
def user_domain(monkeypatch):
    """A free ROS domain given to the run as the user's ROS_DOMAIN_ID (so a rogue can be
    started on it before the run)."""
    lease = reserve_domain_id()
    domain = lease.domain_id
    lease.release()
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    return domain


class _Rogue:
    """A running ``rogue_node.py`` and what it printed (read as it comes, so a test can wait
    for its ``rogue met the run``)."""

    def __init__(self, proc: subprocess.Popen) -> None:
        self.proc = proc
        self.pid = proc.pid
        self._lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            self._lines.append(line)

    def said(self, text: str) -> bool:
        return any(text in line for line in list(self._lines))

    def output(self) -> str:
        return "".join(self._lines)


def _start_rogue(kind: str, seconds: float) -> _Rogue:
    proc = subprocess.Popen([sys.executable, str(ROGUE), kind, str(seconds)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    # bounded: a rogue whose participant never comes up (Fast DDS blocked in its start) must
    # fail this test, not hold the suite
    ready = selectors.DefaultSelector()
    ready.register(proc.stdout, selectors.EVENT_READ)
    line = proc.stdout.readline() if ready.select(timeout=120.0) else ""
    if "rogue ready" not in line:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert "rogue ready" in line, f"the rogue node did not start within 120 s: {line!r}"
    return _Rogue(proc)


def _stop(rogue: _Rogue) -> str:
    """Stop the rogue (SIGTERM to its group); what it printed."""
    os.killpg(rogue.pid, signal.SIGTERM)
    try:
        rogue.proc.wait(timeout=60)
    finally:
        if rogue.proc.poll() is None:
            os.killpg(rogue.pid, signal.SIGKILL)
            rogue.proc.wait()
    rogue._reader.join(timeout=10)
    return rogue.output()


#: How long :func:`_hold_maneuver_until` holds the maneuver node at most, s: well inside the
#: 20 s participant lease of Fast DDS, after which the stopped node would count as gone
HOLD_BOUND_S = 12.0


def _hold_maneuver_until(met: Callable[[], bool]):
    """An ``on_running`` hook: stop the maneuver node (SIGSTOP) until ``met()`` or
    :data:`HOLD_BOUND_S` passed, then let it go on. A lockstep run waits meanwhile for the
    maneuver's driver input, so a rogue's attack meets the run however late discovery joins
    them: a run of 40 s of simulation takes about 4 s of wall time, and on a loaded CI machine
    the controller once had not learnt the rogue's name by the end of it (the attack then
    never happened and the test failed). Held, the run's nodes are offered the rogue's
    messages while they wait on one state: the sharpest form of the attack."""
    def hold(group) -> None:
        maneuver = group.child("fourws_maneuver").proc
        os.kill(maneuver.pid, signal.SIGSTOP)
        try:
            deadline = time.monotonic() + HOLD_BOUND_S
            while time.monotonic() < deadline and not met():
                time.sleep(0.1)
        finally:
            os.kill(maneuver.pid, signal.SIGCONT)
    return hold


def _rogue_met(rogue: _Rogue) -> Callable[[], bool]:
    return lambda: rogue.said("rogue met the run")


def test_rogue_garbage_is_refused_counted_and_the_run_is_exact(tmp_path, user_domain):
    """A foreign node floods the run's domain with states of t = 1e6 s, NaN states, commands
    for future states, NaN and 0.08 rad commands, a 100 rad driver input, 'done' maneuver
    statuses and final simulator statuses. None of it reaches the run: the bag holds the
    twin's states exactly, none of the rogue's messages, and the record counts what was
    refused and by whom."""
    # 40 s of simulation (a few s of wall time): long enough for the rogue's publishers to
    # be discovered by every node, whatever the load, so each of them meets the garbage
    sc = _scenario(40.0)
    rogue = _start_rogue("garbage", 120.0)
    try:
        run = graph_run.run_graph(RunConfig.from_scenario(sc, "sol1"), tmp_path,
                                  run_name="rogue", on_running=_hold_maneuver_until(
                                      _rogue_met(rogue)))
    finally:
        rogue_out = _stop(rogue)
    assert "rogue met the run" in rogue_out, rogue_out
    assert run.ok, run.reason
    assert run.complete
    _assert_equals_twin(run.bag_path, sc, "sol1")
    # the rogue's messages were seen, counted, not stored
    foreign = run.account.foreign_publishers
    assert foreign.get(f"{topics.STATE} from rogue", 0) > 10
    assert foreign.get(f"{topics.REAR_STEER_CMD} from rogue", 0) > 10
    bag = load_bag(run.bag_path)
    assert set(bag.topics[topics.REAR_STEER_CMD].fields["law"]) == {"sol1"}
    assert np.all(np.isfinite(bag.topics[topics.STATE].fields["yaw_rate_radps"]))
    # and the nodes refused them by content too (they cannot see publishers)
    refused = run.rejections
    assert any("fourws_maneuver" in k and "state" in k for k in refused), refused
    assert any("fourws_simulator" in k and "rear_steer_cmd" in k for k in refused), refused
    assert any("fourws_simulator" in k and "driver_input" in k for k in refused), refused
    # a final status at t = 1e6 s did not stop the maneuver (nor the controller)
    assert any("fourws_maneuver" in k and "final status not of this run" in k
               for k in refused), refused


def test_rogue_driver_inputs_on_the_runs_grid_never_reach_the_law(tmp_path, user_domain):
    """A foreign node sends 100 rad driver inputs stamped on the run's control grid, so
    some carry the stamp of a state before the maneuver's input for it arrives (before, the
    controller kept them and took the first of a stamp as the law's feed-forward: the car
    spun at t = 15 s of a run whose twin completes). The controller takes driver inputs of
    the run's maneuver node only: every recorded state and command equals the twin's bit for
    bit, and the controller's log names the refused publisher. The simulator, which in
    lockstep cannot tell publishers apart, counts the rogue's inputs that reach it for a state
    already answered as second answers: the run is ok, or fails saying a second publisher
    answered -- never a plausible other result."""
    sc = _scenario(40.0)
    rogue = _start_rogue("driver_grid", 120.0)
    refused = "not from the run's node (publisher rogue)"
    try:
        run = graph_run.run_graph(RunConfig.from_scenario(sc, "sol1"), tmp_path,
                                  run_name="rogue_driver",
                                  on_running=_hold_maneuver_until(lambda: refused in (
                                      tmp_path / "rogue_driver" / "logs"
                                      / "fourws_controller.log").read_text(errors="replace")))
    finally:
        _stop(rogue)
    assert run.ok or run.reason.startswith("a second publisher answered"), run.reason
    ref = run_scenario(sc, "sol1")
    bag = load_bag(run.bag_path)
    n = ref.time_s.size
    state, cmd = bag.topics[topics.STATE], bag.topics[topics.REAR_STEER_CMD]
    assert len(state) == n + 1 and len(cmd) == n
    np.testing.assert_array_equal(state.fields["yaw_rate_radps"][:n], ref["yaw_rate_radps"])
    np.testing.assert_array_equal(cmd.fields["angle_rad"], ref.rear_angle_rad)
    log = (run.run_dir / "logs" / "fourws_controller.log").read_text()
    assert refused in log, log[-2000:]


def test_a_second_answering_publisher_fails_the_run_loudly(tmp_path, user_domain):
    """A foreign node that answers every state with a plausible driver input and command: the
    run cannot tell whose answer came first, so it must not pass as ok; the reason names the
    second publisher."""
    # 40 s of simulation, as above: the rogue must be discovered (and discover the run's
    # state) before the run ends, whatever the load; a 3 s run could end first
    sc = _scenario(40.0)
    rogue = _start_rogue("mimic", 120.0)
    try:
        run = graph_run.run_graph(RunConfig.from_scenario(sc, "sol1"), tmp_path,
                                  run_name="mimic", on_running=_hold_maneuver_until(
                                      _rogue_met(rogue)))
    finally:
        rogue_out = _stop(rogue)
    assert "rogue met the run" in rogue_out, rogue_out
    assert run.outcome == Outcome.FAILED, rogue_out
    assert "second publisher" in run.reason


def _fault(node: str, sig: signal.Signals, monkeypatch=None, stall_s: float = 0.0):
    """An ``on_running`` hook: ``sig`` to ``node`` 0.1 s after the simulation began to move;
    with ``stall_s``, the launcher's stall timeout becomes that from then on. Not from the
    start: until its first step the simulator waits for its publishers to match their
    subscribers, which on a loaded machine can take longer than a short stall timeout (seen
    in CI: "simulation stalled at t = 0.00 s ... waiting for 0 of 1 subscribers of
    /robot_description", before any fault was injected)."""
    def inject(group) -> None:
        if stall_s:
            monkeypatch.setattr(graph_run, "STALL_TIMEOUT_S", stall_s)
        time.sleep(0.1)
        os.kill(group.child(node).proc.pid, sig)
    return inject


@pytest.mark.parametrize("node, sig, expected", [
    ("fourws_simulator", signal.SIGKILL, "node fourws_simulator was killed by SIGKILL"),
    ("fourws_maneuver", signal.SIGKILL, "node fourws_maneuver was killed by SIGKILL"),
    ("fourws_controller", signal.SIGKILL, "node fourws_controller was killed by SIGKILL"),
    ("fourws_recorder", signal.SIGKILL, "node fourws_recorder was killed by SIGKILL"),
    ("fourws_simulator", signal.SIGSTOP, "node fourws_simulator is stopped"),
    ("fourws_maneuver", signal.SIGSTOP, "node fourws_maneuver is stopped"),
    ("fourws_recorder", signal.SIGSTOP, "node fourws_recorder is stopped"),
])
def test_killed_or_stopped_node_fails_the_run_naming_it(tmp_path, monkeypatch, node, sig,
                                                        expected):
    """SIGKILL or SIGSTOP of a node mid-run: the run fails with a reason naming that node, no
    process outlives the run, the record is written, and the bag is readable (a killed
    recorder's after `repair`)."""
    sc = _scenario(60.0)
    run = graph_run.run_graph(RunConfig.from_scenario(sc, "sol1"), tmp_path, run_name="f",
                              on_running=_fault(node, sig, monkeypatch, stall_s=3.0))
    assert run.outcome == Outcome.FAILED
    assert expected in run.reason, run.reason
    assert all(code is not None for code in run.exit_codes.values()), run.exit_codes
    assert (run.run_dir / "run.json").is_file()
    if node == "fourws_recorder" and sig == signal.SIGKILL:
        repair_bag(run.bag_path)
    bag = load_bag(run.bag_path, allow_incomplete=True)
    state = bag.topics[topics.STATE]
    assert len(state) >= 1
    # what was stored is the run's beginning, nothing lost in the middle
    np.testing.assert_allclose(np.diff(state.time_s), sc.control_period_s, atol=1e-9)
    if node == "fourws_recorder" and sig == signal.SIGKILL:
        # bounded loss: the simulator cannot be more than the flow-control window (50
        # states, 0.5 s) ahead of what the recorder took, and the recorder flushes every
        # 0.5 s of simulated time
        assert state.time_s[-1] >= run.sim_time_s - 1.0 - sc.control_period_s


def test_side_by_side_runs_under_a_cpu_hog_are_complete_and_exact(tmp_path):
    """Two `fourws run` at once while two busy processes load both cores: both bags are
    complete and hold exactly the states of the same run alone (its offline twin)."""
    scenario = tmp_path / "short.yaml"
    scenario.write_text("vehicle: table_8_1\nmaneuver: step_steer_85kmh\nlaws: [sol1]\n")
    sc = load_scenario(scenario)
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
            for _ in range(2)]
    try:
        runs = [subprocess.Popen([sys.executable, "-m", "fourws_cli.main", "run",
                                  str(scenario), "--out", str(tmp_path / f"out{k}")],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                for k in range(2)]
        outs = [p.communicate(timeout=300)[0] for p in runs]
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()
    for proc, out in zip(runs, outs):
        assert proc.returncode == 0, out
        assert "recording: complete" in out
    for k in range(2):
        (bag,) = (tmp_path / f"out{k}").glob("*/bag")
        _assert_equals_twin(bag, sc, "sol1")


def test_realtime_run_whose_maneuver_stops_ends_naming_it(tmp_path):
    """Realtime: the maneuver node is stopped (SIGSTOP) mid-run. The simulator does not drive
    on with a frozen driver input: after driver_timeout_s (1 s of simulation time) without a
    new one it ends the run, naming the maneuver node; nothing runs on past the maneuver."""
    sc = _scenario(30.0, clock_mode="realtime")
    run = graph_run.run_graph(RunConfig.from_scenario(sc, "sol1"), tmp_path, run_name="rt",
                              on_running=_fault("fourws_maneuver", signal.SIGSTOP))
    assert run.outcome == Outcome.FAILED
    assert "maneuver node (fourws_maneuver) stopped answering" in run.reason
    assert run.sim_time_s < 10.0  # ended about 1 s after the stop, not at the 30 s end
    assert all(code is not None for code in run.exit_codes.values())


def test_aborted_maneuver_is_not_ok_and_exits_3(tmp_path):
    """A constant-radius test whose path error limit is exceeded at once: the bag is
    complete, but the run is 'aborted' with the time and the reason, exit code 3 -- never
    'ok' with exit 0."""
    scenario = tmp_path / "circle.yaml"
    scenario.write_text(
        "vehicle: table_8_1\nlaws: [fws]\nmaneuver: {type: constant_radius, "
        "initial_speed_mps: 10.0, duration_s: 80.0, radius_m: 40.0, final_speed_mps: 12.0, "
        "max_path_error_m: 0.001}\n")
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "run", str(scenario),
                          "--out", str(tmp_path / "out")], capture_output=True, text=True,
                         timeout=300)
    assert res.returncode == 3, res.stdout + res.stderr
    assert "ABORTED" in res.stdout and "path error" in res.stdout
    assert "recording: complete" in res.stdout


@pytest.fixture
def small_disk(tmp_path):
    """A 256 KiB file system (tmpfs), and one mounted read-only; skipped where mounting is
    not permitted."""
    full, ro = tmp_path / "full", tmp_path / "ro"
    full.mkdir()
    ro.mkdir()
    mounted = []
    for where, opts in ((full, "size=256k"), (ro, "ro,size=64k")):
        res = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(where)],
                             capture_output=True, text=True)
        if res.returncode != 0:
            for m in mounted:
                subprocess.run(["umount", str(m)], capture_output=True)
            pytest.skip(f"cannot mount a tmpfs here ({res.stderr.strip()})")
        mounted.append(where)
    try:
        yield full, ro
    finally:
        for m in mounted:
            subprocess.run(["umount", "-l", str(m)], capture_output=True)


def test_full_and_read_only_disks_end_in_one_line_errors(tmp_path, small_disk):
    """A disk that fills up during the run: the recorder stops with the reason, the run fails
    naming it, no traceback, no process left. A read-only output folder: a one-line error
    before anything starts."""
    full, ro = small_disk
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "run", "--law", "sol1",
                          "--out", str(full)], capture_output=True, text=True, timeout=300)
    out = res.stdout + res.stderr
    assert res.returncode == 1, out
    assert "No space left on device" in out or "no space left on device" in out
    assert "Traceback" not in out
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "run", "--law", "sol1",
                          "--out", str(ro / "runs")], capture_output=True, text=True,
                         timeout=300)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "read-only file system" in lines[0].lower(), res.stderr


@pytest.mark.parametrize("kind", ["done", "clock"])
def test_foreign_messages_on_the_runs_clock_never_pass_as_ok(tmp_path, user_domain, kind):
    """A foreign node that copies the run's stamps: 'done' maneuver statuses for every state
    from t = 2 s (one that meets the tick the simulator waits on ends the run early), or
    copies of each state one step ahead. Content cannot tell them from the run's own.
    The copied states are refused by their publisher (the maneuver and the controller take
    states from the run's simulator only): that run is complete and exact (the twin's
    states). A foreign 'done' status may be refused by content and the run complete and
    exact, or end the run early: the run then fails saying so; it never passes short. (Before
    the nodes read with keep-all histories, the flood of statuses could also push the
    maneuver's own out of the recorder's queue.)"""
    sc = _scenario(40.0)
    rogue = _start_rogue(kind, 120.0)
    try:
        run = graph_run.run_graph(RunConfig.from_scenario(sc, "sol1"), tmp_path,
                                  run_name=kind, on_running=_hold_maneuver_until(
                                      _rogue_met(rogue)))
    finally:
        rogue_out = _stop(rogue)
    assert "rogue met the run" in rogue_out, rogue_out
    if kind == "clock":
        assert run.ok, run.reason
        assert run.rejections.get(
            f"fourws_maneuver: {topics.STATE}: not from the run's node", 0) > 0, run.rejections
        # (the controller's refusals are in its log: it reports no counts to the record)
        log = (run.run_dir / "logs" / "fourws_controller.log").read_text(errors="replace")
        assert (f"refused a {topics.STATE} message: not from the run's node (publisher rogue)"
                in log), log[-2000:]
    if run.ok:
        assert run.complete and run.sim_time_s == pytest.approx(40.0)
        _assert_equals_twin(run.bag_path, sc, "sol1")
        assert sum(run.rejections.values()) > 0  # its messages were met and refused
    else:
        assert run.outcome == Outcome.FAILED, run.reason
        assert "before the maneuver node was done" in run.reason, run.reason
