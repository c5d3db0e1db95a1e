# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A node stopped while it is still starting ends cleanly: no traceback in its log, exit 0.

The launcher stops every node of a run that failed early with SIGINT, and Ctrl-C stops a graph
started by hand, so a node is often interrupted in its first seconds, while Python is still
importing rclpy, numpy and fourws (``fourws_cli.nodes`` handles that window; the node's own
handling, ``fourws_ros.runtime.run_node``, takes over once the imports are done). The moments
are taken from the process's progress, not from a clock: the shared libraries it has mapped
(``/proc/PID/maps``), in the order the simulator loads them.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fourws_cli import nodes
from fourws_ros import runtime

ROOT = Path(__file__).resolve().parent.parent
PARAMS = ROOT / "config" / "params" / "lockstep.yaml"
#: Progress marks of the simulator's start-up, in order: a library mapped at that point, and
#: whether the node is still importing its modules there (it has logged nothing yet).
MOMENTS = [
    ("_rclpy_pybind11", True),       # rclpy, the node module's first import
    ("_multiarray_umath", True),     # numpy, imported by the fourws modules the node imports
    ("zstandard/backend_c", True),   # the bag libraries (fourws_run)
    # rclpy.init loads the rmw's own message support: the node's own handling is on
    ("librmw_dds_common__rosidl_typesupport_fastrtps_cpp", False),
    ("scipy/linalg/_flapack", False),  # scipy.linalg, loaded while the node is built
]


def _mapped(pid: int, library: str) -> bool:
    try:
        return library in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


#: Runs ``argv[1:]`` in its own place with SIGINT and SIGTERM at their defaults: a test session
#: started where SIGINT is ignored (a background job of a non-interactive shell, ``nohup``)
#: would hand that on, and a node keeps an ignored signal ignored (as it should).
_DEFAULT_SIGNALS = ("import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
                    "signal.signal(signal.SIGTERM, signal.SIG_DFL); "
                    "os.execv(sys.argv[1], sys.argv[1:])")


def _stop_at(command: list[str], library: str) -> tuple[int, str, bool]:
    """Start ``command`` (with SIGINT and SIGTERM at their defaults), send SIGINT once
    ``library`` is mapped in it; returns the exit code, stderr, and whether the signal was sent
    before the process ended by itself."""
    proc = subprocess.Popen([sys.executable, "-c", _DEFAULT_SIGNALS, *command],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, errors="replace", env=dict(os.environ))
    sent = False
    try:
        deadline = time.monotonic() + 120.0
        while proc.poll() is None and time.monotonic() < deadline:
            if _mapped(proc.pid, library):
                proc.send_signal(signal.SIGINT)
                sent = True
                break
            time.sleep(0.001)
        _, err = proc.communicate(timeout=120.0)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return proc.returncode, err, sent


def test_a_stop_while_starting_is_the_exit_code_of_a_stop():
    """A node stopped by a signal while starting reports what a stopped node reports."""
    assert nodes.EXIT_STOPPED == runtime.EXIT_OK == 0


@pytest.mark.usefixtures("ros_domain")
@pytest.mark.parametrize("library, importing", MOMENTS,
                         ids=[m[0].split("/")[-1] for m in MOMENTS])
def test_sigint_while_starting_is_a_clean_exit(library, importing):
    """``fourws node simulator`` interrupted at each start-up mark: exit 0, no traceback and
    no KeyboardInterrupt in its output (before, an interrupt during the imports ended in a
    KeyboardInterrupt traceback, exit 1)."""
    code, err, sent = _stop_at([sys.executable, "-m", "fourws_cli.main", "node", "simulator",
                                "--ros-args", "--params-file", str(PARAMS)], library)
    assert sent, f"{library} was never mapped: {err[-500:]}"
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err[-2000:]
    assert code == 0, err[-2000:]
    if importing:
        assert "[INFO]" not in err, err  # the stop came before the node had started


@pytest.mark.usefixtures("ros_domain")
def test_console_script_stopped_while_importing_is_a_clean_exit():
    """The venv's console script ``fourws-simulator`` enters through fourws_cli.nodes too
    (setup.py), so it is covered the same way."""
    script = Path(sys.prefix) / "bin" / "fourws-simulator"
    if not script.is_file():
        pytest.skip(f"no console script {script} (not the venv of `make setup`)")
    code, err, sent = _stop_at([str(script), "--ros-args", "--params-file", str(PARAMS)],
                               "_rclpy_pybind11")
    assert sent and code == 0, err[-2000:]
    assert "Traceback" not in err and "[INFO]" not in err, err[-2000:]
