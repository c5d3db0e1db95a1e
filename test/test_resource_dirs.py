# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Shipped folders are found both in a checkout and in an installed package.

Source: the install layout of setup.py's ``data_files`` and of rosidl (``share/<package>/...``
under an ament prefix), which is what ``colcon build`` without ``--symlink-install`` produces.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from fourws_run.bagfile import MSG_DIR
from fourws_sim.params import CONFIG_DIR, find_resource_dir


def test_checkout_folders_are_found() -> None:
    root = Path(__file__).resolve().parent.parent
    assert CONFIG_DIR == root / "config"
    assert MSG_DIR == root / "msg"
    assert len(list(MSG_DIR.glob("*.msg"))) >= 5


def test_installed_share_folder_is_found(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    missing = tmp_path / "site-packages" / "config"          # no config beside the sources
    prefix = tmp_path / "install" / "fourws"
    share = prefix / "share" / "fourws" / "config"
    (share / "vehicles").mkdir(parents=True)
    monkeypatch.setenv("AMENT_PREFIX_PATH", f"{tmp_path / 'other'}:{prefix}")
    assert find_resource_dir(missing, "fourws", "config", "vehicles") == share
    # with nothing anywhere, the source-side path is returned (and its absence reported later)
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(tmp_path / "other"))
    assert find_resource_dir(missing, "fourws", "config", "vehicles") == missing
