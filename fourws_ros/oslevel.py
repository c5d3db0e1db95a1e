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


def is_stopped(pid: int) -> bool:
    """Process ``pid`` is stopped (SIGSTOP/SIGTSTP, state T or t in ``/proc/PID/stat``)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[-1].split()[0] in ("T", "t")
    except (OSError, IndexError):
        return False


def node_prefix() -> list[str]:
    """The command line of a fourws node up to its name (``... node NAME``)."""
    return [sys.executable, "-m", "fourws_cli.main", "node"]


__all__ = ["PR_SET_CHILD_SUBREAPER", "PR_SET_PDEATHSIG", "is_stopped", "node_prefix", "prctl"]
