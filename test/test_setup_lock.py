# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``make setup`` installs the versions of requirements.lock (the ones the tests passed with).

Source: requirements.lock (``make lock``: a clean install of requirements.txt, frozen) and the
distributions installed in this environment. Skipped outside the venv of ``make setup`` (a
ROS workspace's ``colcon test`` runs with the system's packages).
"""

from __future__ import annotations

import re
import sys
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _lock() -> dict[str, str]:
    pins = {}
    for line in (ROOT / "requirements.lock").read_text().splitlines():
        if line and not line.startswith("#"):
            name, _, pinned = line.partition("==")
            assert pinned, f"requirements.lock: {line!r} is not a pin (name==version)"
            pins[_canonical(name)] = pinned
    return pins


def test_lock_pins_every_requirement() -> None:
    pins = _lock()
    wanted = {_canonical(re.split(r"[<>=!~\[; ]", line.split("#")[0].strip())[0])
              for line in (ROOT / "requirements.txt").read_text().splitlines()
              if line.split("#")[0].strip()}
    assert wanted <= set(pins), f"not in requirements.lock (make lock): {wanted - set(pins)}"


def test_setup_installed_the_locked_versions() -> None:
    makefile = (ROOT / "Makefile").read_text()
    venv = re.search(r"^VENV \?= (\S+)", makefile, re.M)
    if venv is None or Path(sys.prefix).resolve() != (ROOT / venv.group(1)).resolve():
        pytest.skip("not the venv of make setup")
    pins = _lock()
    installed = {_canonical(d.metadata["Name"]): d.version for d in metadata.distributions()}
    differ = {name: (installed[name], pinned) for name, pinned in pins.items()
              if name in installed and installed[name] != pinned}
    assert not differ, f"installed != requirements.lock (run make setup): {differ}"
    missing = set(pins) - set(installed)
    assert not missing, f"locked but not installed (run make setup): {sorted(missing)}"
