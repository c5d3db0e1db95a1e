# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""launch/fourws.launch.py names what exists: the executables CMake installs, the node names
and shipped parameter files of ``fourws run``'s graph.

launch and launch_ros are not on PyPI, so the file is read (``ast``), not run. Sources: the
node table fourws_cli/nodes.py (what CMakeLists.txt installs under lib/fourws), the roles and
node names of fourws_run.interface, the parameter files in config/params, and
the node names the files configure.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
import yaml

from fourws_cli.nodes import NODES
from fourws_run.interface import NODE_NAMES, Role

ROOT = Path(__file__).resolve().parent.parent
LAUNCH = ROOT / "launch" / "fourws.launch.py"


@pytest.fixture(scope="module")
def launch() -> tuple[dict[str, object], list[dict[str, object]]]:
    """Module-level constants and the keyword constants of every ``Node(...)`` call."""
    tree = ast.parse(LAUNCH.read_text())
    constants = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 \
                and isinstance(node.targets[0], ast.Name):
            constants[node.targets[0].id] = ast.literal_eval(node.value)
    calls = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Node":
            kw = {}
            for k in node.keywords:
                if isinstance(k.value, ast.Constant):
                    kw[k.arg] = k.value.value
                elif isinstance(k.value, ast.Name) and k.value.id in constants:
                    kw[k.arg] = constants[k.value.id]
            calls.append(kw)
    return constants, calls


def test_launch_starts_the_node_set_of_fourws_run(launch) -> None:
    _, calls = launch
    graph_roles = [r for r in Role if r is not Role.LAUNCHER]
    assert sorted(c["executable"] for c in calls) == sorted(r.value for r in graph_roles)
    for call in calls:
        assert call["package"] == "fourws"
        assert call["executable"] in NODES  # installed as lib/fourws/<executable>
        assert call["name"] == NODE_NAMES[Role(call["executable"])]


def test_launch_uses_the_shipped_parameter_files(launch) -> None:
    constants, calls = launch
    files = constants["PARAMS_FILES"]
    assert sorted(files) == ["lockstep", "realtime"]
    for clock, name in files.items():
        params = yaml.safe_load((ROOT / "config" / "params" / name).read_text())
        for call in calls:
            assert "ros__parameters" in params[call["name"]], (name, call["name"])
        assert params[NODE_NAMES[Role.SIMULATOR]]["ros__parameters"]["clock_mode"] == clock
