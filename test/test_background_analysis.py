# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws demo``'s report process (fourws_cli/background_analysis.py): the report it writes
is ``fourws analyze``'s, and whatever happens to it (killed, stopped, failing) the demo still
writes the report, naming in one line why it analysed the bags itself."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from fourws_cli import cmd_demo
from fourws_cli.background_analysis import NICENESS, BackgroundAnalysis
from fourws_ros.oslevel import niceness as _nice
from fourws_cli.main import main
from fourws_sim.params import vehicle_from_mapping

from test_analysis_frequency import SET_1
from test_analysis_report import SPEED, _step_bag


def _gain(report: Path, run: str) -> float:
    metrics = json.loads((report / "metrics.json").read_text())["runs"][run]
    return metrics["iso7401_step"]["yaw_rate_radps"][
        "steady_state_gain_radps_per_rad_road_wheel"]


def test_the_report_process_writes_what_analyze_writes(tmp_path: Path) -> None:
    """Two bags added one at a time: exit 0, and the yaw gain of each is the in-process
    ``fourws analyze``'s (same code, another process) and the 2-DOF analytic
    U/(L + K_us U^2) within 0.1 %; a third, missing bag is a failure named, exit 1."""
    for name in ("a", "b"):
        _step_bag(tmp_path / name)
    assert main(["analyze", str(tmp_path / "a"), "--report", str(tmp_path / "here"),
                 "--quiet"]) == 0
    bags = [str(tmp_path / name) for name in ("a", "b", "missing")]
    worker = BackgroundAnalysis([*bags, "--report", str(tmp_path / "there"), "--quiet"])
    try:
        for name in ("a", "b", "missing"):
            worker.add(str(tmp_path / name))
        code = worker.finish()
    finally:
        worker.close()
    assert worker.problem == "" and code == 1
    vehicle = vehicle_from_mapping(SET_1)
    analytic = SPEED / (vehicle.chassis.wheelbase_m
                        + vehicle.understeer_gradient_rad_per_mps2 * SPEED ** 2)
    for run in ("a", "b"):
        assert _gain(tmp_path / "there", run) == _gain(tmp_path / "here", "a")
        assert _gain(tmp_path / "there", run) == pytest.approx(analytic, rel=1e-3)
    failed = json.loads((tmp_path / "there" / "metrics.json").read_text())["failed_bags"]
    assert list(failed) == [str(tmp_path / "missing")]


@pytest.mark.parametrize("how", ["killed", "stopped"])
def test_a_killed_or_stopped_report_process_is_named_not_waited_for(
        tmp_path: Path, how: str) -> None:
    """SIGKILL: finish says the process ended with exit code -9; SIGSTOP: that it is stopped
    (not a wait without end); both None (the demo then analyses here), the process gone."""
    _step_bag(tmp_path / "a")
    worker = BackgroundAnalysis([str(tmp_path / "a"), "--report", str(tmp_path / "rep"),
                                 "--quiet"])
    try:
        worker.add(str(tmp_path / "a"))
        pid = worker._proc.pid
        os.kill(pid, signal.SIGKILL if how == "killed" else signal.SIGSTOP)
        code = worker.finish()
    finally:
        worker.close()
    assert code is None
    assert worker.problem == {"killed": "the report's process ended (exit code -9)",
                              "stopped": "the report's process is stopped (SIGSTOP)"}[how]
    assert worker._proc.poll() is not None


def test_refused_arguments_are_a_failure_named() -> None:
    """No bag given: argparse refuses (exit code 2 in the worker); finish says so."""
    worker = BackgroundAnalysis(["--quiet"])
    try:
        code = worker.finish()
    finally:
        worker.close()
    assert code is None
    assert worker.problem == ("the report's process failed: its arguments were refused "
                              "(exit code 2)")


class _DyingReport(BackgroundAnalysis):
    """The report process, killed after its first bag."""

    def add(self, path: str) -> None:
        super().add(path)
        if self._proc.poll() is None:  # (the first bag's; it is gone for the others)
            os.kill(self._proc.pid, signal.SIGKILL)
            self._proc.wait(timeout=10.0)


def test_the_demo_writes_the_report_itself_when_its_report_process_dies(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    """The demo's three runs (bags written here in place of the graph's), the report process
    killed: exit 0, one line naming the cause, and the report of all three bags, each bag's
    yaw gain the analytic one."""
    import fourws_ros.graph_run

    def fake_run_graph(config, out, run_name):
        _step_bag(out / run_name / "bag")
        return SimpleNamespace(summary_lines=lambda: [f"run {run_name}: ok"], interrupted=False,
                               ok=True, bag_path=out / run_name / "bag", reason="")

    monkeypatch.setattr(fourws_ros.graph_run, "run_graph", fake_run_graph)
    monkeypatch.setattr(cmd_demo, "BackgroundAnalysis", _DyingReport)
    start = time.monotonic()
    assert main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert out.count("fourws demo: the report's process ended (exit code -9); "
                     "analysing the bags here") == 1
    metrics = json.loads((tmp_path / "report" / "metrics.json").read_text())
    assert len(metrics["runs"]) == 3
    gains = {_gain(tmp_path / "report", run) for run in metrics["runs"]}
    assert len(gains) == 1  # the same bag three times
    assert time.monotonic() - start < 600  # (a bound on a hang, not a speed)


def test_a_script_without_a_main_guard_runs_once(tmp_path: Path) -> None:
    """A user's script that starts the report process at its top level (no ``__main__``
    guard): the script runs once (a multiprocessing spawn would run it again in the child,
    and there start a second worker), the report is written (exit 0)."""
    _step_bag(tmp_path / "a")
    runs = tmp_path / "runs.txt"
    script = tmp_path / "user_script.py"
    script.write_text(
        "import sys\n"
        f"open({str(runs)!r}, 'a').write('ran\\n')\n"
        "from fourws_cli.background_analysis import BackgroundAnalysis\n"
        f"w = BackgroundAnalysis([{str(tmp_path / 'a')!r}, '--report', "
        f"{str(tmp_path / 'rep')!r}, '--quiet'])\n"
        f"w.add({str(tmp_path / 'a')!r})\n"
        "code = w.finish()\n"
        "w.close()\n"
        "sys.exit(3 if code is None else code)\n")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=600, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert runs.read_text() == "ran\n"
    assert (tmp_path / "rep" / "metrics.json").is_file()


def test_the_report_process_does_not_outlive_a_killed_demo(tmp_path: Path) -> None:
    """A demo process SIGKILLed while its report process is busy (here: stopped, so it cannot
    notice the closed socket itself): the report process goes with it (parent-death signal),
    instead of analysing on for nobody."""
    script = tmp_path / "demo_like.py"
    script.write_text(
        "import os, signal, sys\n"
        "from fourws_cli.background_analysis import BackgroundAnalysis\n"
        f"w = BackgroundAnalysis([{str(tmp_path / 'a')!r}, '--quiet'])\n"
        "print(w._proc.pid, flush=True)\n"
        "sys.stdin.readline()\n"
        "os.kill(os.getpid(), signal.SIGKILL)\n")
    demo = subprocess.Popen([sys.executable, str(script)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    worker = int(demo.stdout.readline())
    deadline = time.monotonic() + 120  # (a bound on a hang, not a speed)
    while _nice(worker) != NICENESS and time.monotonic() < deadline:
        time.sleep(0.02)  # the worker is niced after it set its parent-death signal
    os.kill(worker, signal.SIGSTOP)
    try:
        demo.stdin.write("\n")
        demo.stdin.flush()
        assert demo.wait(timeout=60) == -signal.SIGKILL
        deadline = time.monotonic() + 60  # (a bound on a hang, not a speed)
        while _alive(worker) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _alive(worker)
    finally:
        if _alive(worker):
            os.kill(worker, signal.SIGKILL)


def test_the_report_process_is_back_at_the_demos_niceness_when_the_demo_waits(
        tmp_path: Path) -> None:
    """Niced while the runs go on, the worker takes the demo's niceness back when the demo
    starts waiting for the report, even while it still analyses an earlier bag; where
    lowering a niceness is not permitted it stays nice and still writes the report."""
    permitted = subprocess.run(
        [sys.executable, "-c", "import os; base = os.getpriority(os.PRIO_PROCESS, 0); "
         "os.nice(1); os.setpriority(os.PRIO_PROCESS, 0, base)"]).returncode == 0
    base = os.getpriority(os.PRIO_PROCESS, 0)
    _step_bag(tmp_path / "a")
    worker = BackgroundAnalysis([str(tmp_path / "a"), "--report", str(tmp_path / "rep"),
                                 "--quiet"])
    pid = worker._proc.pid
    try:
        worker.add(str(tmp_path / "a"))
        deadline = time.monotonic() + 120  # (a bound on a hang, not a speed)
        while _nice(pid) != base + NICENESS and time.monotonic() < deadline:
            time.sleep(0.02)
        assert _nice(pid) == base + NICENESS
        codes: list[int | None] = []
        waiting = threading.Thread(target=lambda: codes.append(worker.finish()))
        waiting.start()
        seen = set()
        # the worker is alive until it has written the report and answered
        while waiting.is_alive():
            seen.add(_nice(pid))
        assert codes == [0]
    finally:
        worker.close()
    assert (tmp_path / "rep" / "metrics.json").is_file()
    seen.discard(None)
    assert (base in seen) if permitted else (seen == {base + NICENESS})


def _alive(pid: int) -> bool:
    """``pid`` runs (a zombie, reaped by nobody here, has gone)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
