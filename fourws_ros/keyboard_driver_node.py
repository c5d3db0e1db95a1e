# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Keyboard driver: ``fourws node keyboard_driver`` turns a terminal's keys into a gamepad's
``sensor_msgs/Joy`` on ``/joy`` (:class:`fourws_sim.input_drivers.KeyboardAxes`: a/d steer,
w/s throttle and brake, space straight and idle; the arrows too), so ``fourws run --driver joy
--clock realtime`` is driven from a terminal without a pad. It publishes every
``publish_period_s`` (the joy driver refuses axes older than its command timeout), reads the
keys of its own terminal (standard input must be one: one line and exit code 2 if not) and
restores the terminal on exit. ``q`` quits.
"""

from __future__ import annotations

import os
import select
import sys
import termios
import tty
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor

from fourws_ros import topics
from fourws_ros.node_base import FourwsNode
from fourws_ros.runtime import EXIT_USER_ERROR, run_node
from fourws_sim.input_drivers import KeyboardAxes


class KeyboardDriverNode(FourwsNode):
    """Keys to ``/joy`` (module docstring)."""

    def __init__(self) -> None:
        super().__init__("fourws_keyboard_driver")
        self.declare_parameter("publish_period_s", 0.05, ParameterDescriptor(
            description="period of the /joy messages, s",
            floating_point_range=[FloatingPointRange(from_value=0.005, to_value=1.0)],
            read_only=True))
        self.finished = False
        self.stop_reason = ""
        self._saved: Any = None
        if not os.isatty(sys.stdin.fileno()):
            self.stop_reason = "the keyboard driver needs a terminal (standard input is none)"
            self.exit_code = EXIT_USER_ERROR
            self.finished = True
            return
        self._saved = termios.tcgetattr(sys.stdin.fileno())
        tty.setcbreak(sys.stdin.fileno())
        self.keys = KeyboardAxes()
        self.pub = self.create_publisher(topics.message_class(topics.JOY), topics.JOY,
                                         topics.DRIVE_QOS)
        self.create_timer(float(self.get_parameter("publish_period_s").value), self._tick)
        print("keyboard driver: a/d steer, w/s throttle/brake, space straight, q quit",
              file=sys.stderr, flush=True)

    def _tick(self) -> None:
        while select.select([sys.stdin], [], [], 0.0)[0]:
            key = sys.stdin.read(1)
            if key == "q":
                self.finished = True
                return
            self.keys.press(key)
        msg = topics.message_class(topics.JOY)()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.axes = self.keys.axes()
        self.pub.publish(msg)

    def on_shutdown(self, executor: Any) -> None:
        """Give the terminal back as it was."""
        del executor
        if self._saved is not None:
            termios.tcsetattr(sys.stdin.fileno(), termios.TCSADRAIN, self._saved)


def main(args: list[str] | None = None) -> int:
    """Console entry point ``keyboard_driver``."""
    return run_node(KeyboardDriverNode, args, name="fourws_keyboard_driver")


if __name__ == "__main__":
    sys.exit(main())
