# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The operating-system facts the launcher and the node starter share (standard library only:
the node starter's launcher side uses them before rclpy is imported)."""

from __future__ import annotations

import ctypes
import sys

PR_SET_PDEATHSIG = 1
PR_SET_CHILD_SUBREAPER = 36


def prctl(option: int, value: int) -> bool:
    """``prctl(option, value)`` of the calling process; False if refused or unavailable."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(option, value, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _stat_fields(pid: int) -> list[str]:
    """The fields of ``/proc/PID/stat`` after the command name (field 3, the state, first);
    empty if the process has gone."""
    try:
        # the command name may hold any bytes; the fields after it are ASCII
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as f:
            return f.read().rsplit(")", 1)[-1].split()
    except OSError:
        return []


def is_stopped(pid: int) -> bool:
    """Process ``pid`` is stopped (SIGSTOP/SIGTSTP, state T or t in ``/proc/PID/stat``)."""
    return _stat_fields(pid)[:1] in (["T"], ["t"])


def niceness(pid: int) -> int | None:
    """The niceness of process ``pid`` (its main thread: ``/proc/PID/stat`` field 19), None
    if it has gone."""
    fields = _stat_fields(pid)
    try:
        return int(fields[16])
    except (IndexError, ValueError):
        return None


def node_prefix() -> list[str]:
    """The command line of a fourws node up to its name (``... node NAME``)."""
    return [sys.executable, "-m", "fourws_cli.main", "node"]


__all__ = ["PR_SET_CHILD_SUBREAPER", "PR_SET_PDEATHSIG", "is_stopped", "niceness", "node_prefix",
           "prctl"]
