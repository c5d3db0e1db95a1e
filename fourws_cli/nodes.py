# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws node NAME [--ros-args ...]``: run one node of the graph in this process.

:data:`NODES` is the one table of the nodes: CMakeLists.txt installs an executable per entry
under ``lib/fourws`` (``ros2 run fourws NAME``) and setup.py a console script ``fourws-NAME``
(the venv, where the ``ros2`` CLI does not exist). Both read it without importing fourws, so
this module imports nothing but the standard library at its top.
"""

from __future__ import annotations

import importlib
import sys

#: Node name -> module with a ``main(args) -> int`` (``module:function`` for another entry).
NODES: dict[str, str] = {
    "simulator": "fourws_ros.simulator_node",
    "maneuver": "fourws_ros.maneuver_node",
    "controller": "fourws_ros.controller_node",
    "recorder": "fourws_ros.recorder_node",
    "replay": "fourws_ros.replay_node",
    "example_controller": "fourws_ros.example_controller",
    "live_view": "fourws_ros.live_view_node",
    "ackermann_driver": "fourws_ros.input_driver_node:ackermann_main",
    "joy_driver": "fourws_ros.input_driver_node:joy_main",
    "keyboard_driver": "fourws_ros.keyboard_driver_node",
}


def run_node(argv: list[str]) -> int:
    """Run node ``argv[0]`` with the remaining arguments; returns its exit code."""
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: fourws node NAME [--ros-args ...]\nnodes: " + ", ".join(NODES))
        return 0 if argv else 1
    name, rest = argv[0], argv[1:]
    if name not in NODES:
        print(f"fourws node: error: unknown node {name!r}; valid: {', '.join(NODES)}",
              file=sys.stderr)
        return 2
    module_name, _, function = NODES[name].partition(":")
    module = importlib.import_module(module_name)
    return int(getattr(module, function or "main")([f"fourws_{name}", *rest]) or 0)
