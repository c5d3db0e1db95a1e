# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The Python API of README.md ("From Python, without ROS"), run as the README writes it.

Sources: the README's own snippet (extracted, not copied), the offline twin it wraps (the same
run through :func:`fourws_run.closed_loop.run_closed_loop`), and ISO 7401's steady state (the
mean of the last part of the hold, which for a settled step equals the final value within the
settling band).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from fourws_run.closed_loop import run_closed_loop
from fourws_sim.params import load_vehicle

README = Path(__file__).resolve().parent.parent / "README.md"


def readme_snippet() -> str:
    """The first ``python`` block of the README's section on the Python API."""
    text = README.read_text()
    section = text[text.index("## From Python, without ROS"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_readme_snippet_runs_as_written():
    code = readme_snippet()
    assert len(code.strip().splitlines()) == 5  # the "five lines"
    scope: dict = {}
    exec(compile(code, str(README), "exec"), scope)  # noqa: S102 - the README's own code
    run, gain = scope["run"], scope["gain"]
    # the twin itself, run directly: the same states bit for bit
    twin = run_closed_loop(load_vehicle("table_8_1"), "step_steer_85kmh", "sol1")
    np.testing.assert_array_equal(scope["yaw_rate"], twin["yaw_rate_radps"])
    assert run.time_s.size == twin.time_s.size == 500
    # the steady yaw rate of the ISO 7401 metrics is the end of the hold (settled)
    assert gain == pytest.approx(run.history["yaw_rate_radps"][-1], rel=1e-3)
    assert run.metrics["law"] == "sol1" and run.metrics["maneuver"] == "step_steer"
