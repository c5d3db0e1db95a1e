# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws node NAME [--ros-args ...]``: run one node of the graph in this process.

:data:`NODES` is the one table of the nodes: CMakeLists.txt installs an executable per entry
under ``lib/fourws`` (``ros2 run fourws NAME``) and setup.py a console script ``fourws-NAME``
(the venv, where the ``ros2`` CLI does not exist); both enter through :func:`run_node` (the
console scripts through :data:`entry`). Both read the table without importing fourws, so this
module imports nothing but the standard library at its top.

A node is stopped with SIGINT or SIGTERM at any time, also while it is still starting: the
launcher stops every node of a run that failed early, Ctrl-C stops a graph started by hand.
Its own handling (:func:`fourws_ros.runtime.run_node`) is installed only once rclpy, numpy
and the node's modules are imported, seconds after the process started; until then
:func:`run_node` has a handler that ends the process at once with exit code
:data:`EXIT_STOPPED` (Python's default handler raised KeyboardInterrupt in the middle of an
import, and the node's log got its traceback).
"""

from __future__ import annotations

import functools
import importlib
import os
import signal
import sys
import types

#: One line for ``fourws --help``.
HELP = "run one node of the graph in this process: fourws node NAME --ros-args ..."

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

#: Exit code of a node stopped by a signal while starting: a stop asked for, as a node
#: stopped by a signal later (``fourws_ros.runtime.EXIT_OK``).
EXIT_STOPPED = 0


def _stopped_while_starting(_signum: int, _frame: object) -> None:
    # nothing is open yet (no ROS context, no file): leave at once, wherever the import is
    os._exit(EXIT_STOPPED)


def run_node(argv: list[str]) -> int:
    """Run node ``argv[0]`` with the remaining arguments, then end the process with its exit
    code (see the module's text); returns only a usage error's code (and raises what the node
    raised)."""
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: fourws node NAME [--ros-args ...]\nnodes: " + ", ".join(NODES))
        return 0 if argv else 1
    name, rest = argv[0], argv[1:]
    if name not in NODES:
        print(f"fourws node: error: unknown node {name!r}; valid: {', '.join(NODES)}",
              file=sys.stderr)
        return 2
    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:  # an ignored signal stays ignored
            signal.signal(sig, _stopped_while_starting)
    module_name, _, function = NODES[name].partition(":")
    module = importlib.import_module(module_name)
    code = int(getattr(module, function or "main")([f"fourws_{name}", *rest]) or 0)
    _leave(code)
    return code  # not reached


def _leave(code: int) -> None:
    """End this node's process with ``code`` now, Python's finalization skipped."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed or broken log: nothing more to say
            pass
    os._exit(code)


def _console_script(name: str) -> int:
    return run_node([name, *sys.argv[1:]])


#: The console scripts' entry points, ``fourws_cli.nodes:entry.NAME`` (setup.py).
entry = types.SimpleNamespace(**{name: functools.partial(_console_script, name)
                                 for name in NODES})
