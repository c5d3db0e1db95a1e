# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""`make demo` is `fourws demo`: the default scenario's three laws through the real graph,
then the report. A newcomer's first command must work as the README says."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from fourws_ros.domains import reserve_domain_id
from fourws_run.bagfile import verify_bag


def test_demo_runs_three_laws_and_writes_the_report(tmp_path):
    """On the user's own ROS_DOMAIN_ID, the three runs one after the other on it (each run
    gives the domain back to the next; the leased domains are every other graph test's)."""
    lease = reserve_domain_id()  # a domain no other test holds, handed to the demo as the
    domain = lease.domain_id     # user's (leased least recently used: not leased again soon)
    lease.release()
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain)}
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "demo", "--out",
                          str(tmp_path)], capture_output=True, text=True, timeout=900, env=env)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    assert (res.stdout + res.stderr).count(f"nodes on ROS domain {domain} (lockstep)") == 3
    assert "Traceback" not in res.stdout + res.stderr
    for law in ("fws", "sol1", "rwc2_3dof"):
        assert verify_bag(tmp_path / law / "bag").complete
    metrics = json.loads((tmp_path / "report" / "metrics.json").read_text())
    assert sorted(r["law"] for r in metrics["runs"].values()) == ["fws", "rwc2_3dof", "sol1"]
    assert (tmp_path / "report" / "index.html").stat().st_size > 10_000
    # the report process analysed each bag ahead (its law's critical speeds and sweep from the
    # run configuration, only the topics the analysis reads): every metric is that of a
    # fresh analysis of the whole bag in this process
    from fourws_analysis import compare
    from fourws_analysis.bag import load_bag, resample
    from fourws_analysis.memo import Memo

    compare._SWEEP_CACHE, compare._LEVELS_CACHE = Memo(4), Memo(4)
    for name, reported in metrics["runs"].items():
        result = compare.analyze_run(resample(load_bag(tmp_path / name / "bag"), None))
        result.recording = "complete"  # (fourws analyze's word for a verified bag)
        fresh = json.loads(json.dumps(result.metrics()))
        assert json.dumps(fresh, sort_keys=True) == json.dumps(reported, sort_keys=True)
