# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Figures drawn side by side (fourws_analysis.figure_jobs): the result is the one-process
result, whatever happens to a child.

Each case runs in a fresh interpreter: draw_all forks only where no other thread runs, and a
test session may hold threads of earlier tests, so in-process the cases could quietly take
the one-process path and prove nothing. Every case checks that children did draw.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

# A job writes its own index and the pid that drew it into its file, or draws nothing (None)
# for odd indices when asked. ``fail`` says how the child of job 2 fails: by SIGKILL, by
# SIGSTOP (stopped for good), by raising; the parent then draws it again.
CASE = textwrap.dedent("""
    import json, os, signal, sys
    from pathlib import Path
    from fourws_analysis import figure_jobs

    out, fail, workers = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
    parent = os.getpid()
    forks = []
    fork = figure_jobs._fork_job
    figure_jobs._fork_job = lambda job: forks.append(1) or fork(job)

    def job(k, path):
        if k == 2 and os.getpid() != parent:
            if fail == "kill":
                os.kill(os.getpid(), signal.SIGKILL)
            if fail == "stop":
                os.kill(os.getpid(), signal.SIGSTOP)
            if fail in ("raise", "raise_everywhere"):
                raise RuntimeError("child failed")
        if k == 2 and fail == "raise_everywhere":
            raise RuntimeError("job 2 cannot be drawn")
        if k % 2 and fail == "none_for_odd":
            return None
        path.write_text(json.dumps({"job": k, "pid": os.getpid()}))
        return path

    jobs = [(job, k, out / f"{k}.txt") for k in range(5)]
    started = []
    try:
        drawn = figure_jobs.draw_all(jobs, workers=workers, started=started.append,
                                     order=[4, 0, 1, 2, 3])
    except RuntimeError as exc:
        print(json.dumps({"error": str(exc), "forks": len(forks)}))
        sys.exit(0)
    print(json.dumps({"drawn": [None if p is None else str(p) for p in drawn],
                      "parent": parent, "forks": len(forks), "started": started}))
""")


def _case(tmp_path: Path, fail: str, workers: int = 2) -> dict:
    res = subprocess.run([sys.executable, "-c", CASE, str(tmp_path), fail, str(workers)],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    return json.loads(res.stdout.strip().splitlines()[-1])


def _drawers(tmp_path: Path, k: int) -> dict:
    return json.loads((tmp_path / f"{k}.txt").read_text())


@pytest.mark.parametrize("fail", ["", "kill", "stop", "raise"])
def test_every_figure_is_drawn_once_in_order_whatever_a_child_does(tmp_path, fail):
    """Five jobs on two workers: the results are the paths in the jobs' order, every file
    holds its own job, the jobs started in the order asked, and a child that was killed,
    stopped or raised had its job drawn again by the parent -- the others by children."""
    got = _case(tmp_path, fail)
    assert got["drawn"] == [str(tmp_path / f"{k}.txt") for k in range(5)]
    assert got["started"] == [4, 0, 1, 2, 3]
    assert got["forks"] == 5
    for k in range(5):
        drew = _drawers(tmp_path, k)
        assert drew["job"] == k
        by_parent = drew["pid"] == got["parent"]
        assert by_parent == (k == 2 and bool(fail)), (k, drew, got)


def test_a_job_with_nothing_to_draw_gives_none(tmp_path):
    got = _case(tmp_path, "none_for_odd")
    assert got["drawn"] == [str(tmp_path / f"{k}.txt") if k % 2 == 0 else None
                            for k in range(5)]
    assert got["forks"] == 5
    assert all(_drawers(tmp_path, k)["pid"] != got["parent"] for k in (0, 2, 4))


def test_an_error_in_drawing_is_raised_as_in_one_process(tmp_path):
    """A figure that cannot be drawn fails the child and then the parent's own attempt: the
    caller gets the drawing error itself, as without children."""
    got = _case(tmp_path, "raise_everywhere")
    assert got["error"] == "job 2 cannot be drawn"


def test_one_worker_draws_everything_here(tmp_path):
    got = _case(tmp_path, "", workers=1)
    assert got["forks"] == 0 and got["started"] == [4, 0, 1, 2, 3]
    assert all(_drawers(tmp_path, k)["pid"] == got["parent"] for k in range(5))


REPORT = textwrap.dedent("""
    import hashlib, json, os, sys
    from pathlib import Path
    from fourws_analysis import bag as B, figure_jobs
    from fourws_analysis.compare import analyze_run
    from fourws_analysis.report import write_report
    from fourws_run.closed_loop import run_scenario
    from fourws_run.scenario import load_scenario

    root = Path(sys.argv[1])
    forks = []
    fork = figure_jobs._fork_job
    figure_jobs._fork_job = lambda job: forks.append(1) or fork(job)
    scenario = load_scenario("default")
    runs = []
    for law in scenario.laws:
        r = run_scenario(scenario, law)
        B.write_run(root / law, r.time_s, r.outputs, r.config, driver=r.driver, model=r.model)
        runs.append(analyze_run(B.resample(B.load_bag(root / law))))
    sums = {}
    for workers in (1, 2):
        out = root / f"report{workers}"
        os.environ[figure_jobs.WORKERS_ENV] = str(workers)
        write_report(runs, out)
        sums[workers] = {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
                         for p in sorted(out.glob("*.png"))}
    print(json.dumps({"sums": sums, "forks": len(forks)}))
""")


def test_the_default_report_drawn_side_by_side_is_byte_identical(tmp_path):
    """The default scenario's report drawn in one process and on two workers: the same PNG
    files, byte for byte, and the second one drew each of them in a child."""
    res = subprocess.run([sys.executable, "-c", REPORT, str(tmp_path)], capture_output=True,
                         text=True, timeout=600)
    assert res.returncode == 0, res.stdout + res.stderr
    got = json.loads(res.stdout.strip().splitlines()[-1])
    one, two = got["sums"]["1"], got["sums"]["2"]
    assert len(one) >= 3 and one == two
    assert got["forks"] >= len(two)
