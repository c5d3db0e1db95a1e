# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""`make demo` is `fourws demo`: the default scenario's three laws through the real graph,
then the report. A newcomer's first command must work as the README says."""

from __future__ import annotations

import json
import subprocess
import sys

from fourws_run.bagfile import verify_bag


def test_demo_runs_three_laws_and_writes_the_report(tmp_path):
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "demo", "--out",
                          str(tmp_path)], capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    assert "Traceback" not in res.stdout + res.stderr
    for law in ("fws", "sol1", "rwc2_3dof"):
        assert verify_bag(tmp_path / law / "bag").complete
    metrics = json.loads((tmp_path / "report" / "metrics.json").read_text())
    assert sorted(r["law"] for r in metrics["runs"].values()) == ["fws", "rwc2_3dof", "sol1"]
    assert (tmp_path / "report" / "index.html").stat().st_size > 10_000
