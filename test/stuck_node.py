# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A fourws node (``fourws_ros.runtime.run_node``) that gets stuck in C, for the tests of
stuck nodes (test_stuck_nodes.py): ``spin`` deadlocks in its first timer callback with the
interpreter released (as a Fast DDS lock cycle does), ``teardown`` deadlocks in its
``destroy_node`` holding the interpreter (so no Python thread can run)."""

from __future__ import annotations

import ctypes
import sys

from rclpy.node import Node

from fourws_ros.runtime import run_node


#: Written to the log just before the node blocks for ever in its spin.
STUCK_LINE = "[fourws_stuck] blocking in C now"


def deadlock_in_c(hold_interpreter: bool) -> None:
    """Lock a default pthread mutex twice: blocks for ever in C."""
    libc = ctypes.PyDLL(None) if hold_interpreter else ctypes.CDLL(None)
    mutex = ctypes.create_string_buffer(64)  # PTHREAD_MUTEX_INITIALIZER is all zeros
    libc.pthread_mutex_lock(mutex)
    libc.pthread_mutex_lock(mutex)


class StuckNode(Node):
    def __init__(self, where: str) -> None:
        super().__init__("fourws_stuck")
        self.where = where
        if where == "spin":
            self.create_timer(0.05, self._stuck)
        else:
            self.finished = True  # straight to the teardown

    def _stuck(self) -> None:
        print(STUCK_LINE, file=sys.stderr, flush=True)  # the test waits for it in the log
        deadlock_in_c(hold_interpreter=False)

    def destroy_node(self) -> None:
        if self.where == "teardown":
            deadlock_in_c(hold_interpreter=True)
        super().destroy_node()


if __name__ == "__main__":
    where = sys.argv[1]
    sys.exit(run_node(lambda: StuckNode(where), sys.argv[2:], name="fourws_stuck"))
