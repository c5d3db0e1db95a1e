# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Under ``colcon test`` the suite runs on the sources of ``src/fourws``; this file checks that
the install it runs beside is those sources, so a stale install cannot pass unseen.

``colcon test`` (CTest) runs the suite from the source folder: the other tests import the
sources and read the checkout's files, which is what ``make test`` tests too. What only the
install has -- the Python packages ament_cmake_python copied, the share folder the installed
code reads its configuration and message definitions from, one executable per node under
``lib/fourws`` (what ``ros2 run`` starts) -- is compared here, file for file, with the sources
(CMakeLists.txt hands the suite its install prefix as ``FOURWS_INSTALL_PREFIX``; without it,
as in ``make test``, there is no install to check). ``test/test_workspace.py`` builds a fresh
workspace and runs the installed nodes as a graph.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import pytest

from fourws_cli.nodes import NODES

ROOT = Path(__file__).resolve().parent.parent
PREFIX = os.environ.get("FOURWS_INSTALL_PREFIX", "")

pytestmark = pytest.mark.skipif(not PREFIX, reason="no install to check: FOURWS_INSTALL_PREFIX "
                                                   "is set by the CTest registration of "
                                                   "CMakeLists.txt (colcon test)")


def _digests(root: Path, pattern: str) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.glob(pattern)) if p.is_file() and "__pycache__" not in p.parts}


def _differences(source: dict[str, str], installed: dict[str, str]) -> list[str]:
    return sorted(k for k in source.keys() | installed.keys() if source.get(k) != installed.get(k))


def _site_packages(prefix: Path) -> Path:
    found = sorted(prefix.glob("lib/python*/site-packages/fourws_sim/__init__.py"))
    assert found, f"no fourws Python packages under {prefix}: run colcon build first"
    return found[0].parent.parent


def test_installed_python_packages_are_the_sources() -> None:
    """Every module of every package fourws_* (CMakeLists.txt installs each folder with an
    __init__.py), byte for byte, and no module more or less."""
    site = _site_packages(Path(PREFIX))
    packages = sorted(p.parent.name for p in ROOT.glob("fourws_*/__init__.py"))
    assert packages == sorted(p.parent.name for p in site.glob("fourws_*/__init__.py"))
    for package in packages:
        differ = _differences(_digests(ROOT, f"{package}/**/*.py"),
                              _digests(site, f"{package}/**/*.py"))
        assert not differ, (f"the install {PREFIX} is not these sources ({len(differ)} "
                            f"modules differ: {', '.join(differ[:5])}); run colcon build")


@pytest.mark.parametrize("pattern", ["config/**/*", "launch/*", "msg/*.msg"])
def test_installed_share_folder_is_the_sources(pattern: str) -> None:
    """``share/fourws``: the configuration (vehicles, maneuvers, scenarios, studies, node
    parameters, DDS profile), the launch file and the message definitions the installed code
    reads (``fourws_sim.params.find_resource_dir``)."""
    share = Path(PREFIX) / "share" / "fourws"
    differ = _differences(_digests(ROOT, pattern), _digests(share, pattern))
    assert not differ, (f"{share} is not these sources ({len(differ)} files differ: "
                        f"{', '.join(differ[:5])}); run colcon build")


def test_an_installed_executable_per_node() -> None:
    """``lib/fourws`` holds one executable per node of fourws_cli.nodes.NODES (what ``ros2 run
    fourws NAME`` starts), each entering through run_node with its own name, and ``bin/fourws``
    the command."""
    lib = Path(PREFIX) / "lib" / "fourws"
    assert sorted(p.name for p in lib.iterdir()) == sorted(NODES)
    for name in NODES:
        path = lib / name
        assert os.access(path, os.X_OK), path
        assert f"run_node(['{name}', *sys.argv[1:]])" in path.read_text(), path
    command = Path(PREFIX) / "bin" / "fourws"
    assert os.access(command, os.X_OK) and "from fourws_cli.main import main" in \
        command.read_text()
