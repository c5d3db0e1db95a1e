# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Driver nodes fed from outside: ``fourws node ackermann_driver`` and ``fourws node
joy_driver`` (``fourws run --driver ackermann|joy`` starts one in place of the maneuver node).

Each plays the maneuver's role in the run -- it answers every admitted state
(:class:`fourws_run.ticks.StateGate`) with one ``DriverInput`` stamped with the state's stamp,
counts what it publishes, reports in ``ManeuverStatus`` and ends the run when the run's
maneuver is done (its duration, or the car left its limits) -- but its steering and speed come
from another stack or a person (the core: :mod:`fourws_sim.input_drivers`):

* ``ackermann``: ``ackermann_msgs/AckermannDriveStamped`` on ``/drive`` (steering angle, speed;
  the speed-hold loop turns speed into wheel torques). Lockstep: a state is answered once the
  command stamped with that state's stamp has arrived (the stack answers each state, as a
  controller does; the simulator waits). Realtime: each state with the latest command, a
  command older than ``command_timeout_s`` (wall time) is stale.
* ``joy``: ``sensor_msgs/Joy`` on ``/joy`` (a gamepad's ``joy`` node or ``fourws node
  keyboard_driver``): each state with the latest axes (older than ``command_timeout_s``:
  stale), mapping from ``joy_mapping_file`` (default ``config/drivers/joy.yaml``).

A command that is not finite or not plausible is refused, a stale tick (straight ahead,
braking) counted: both in ``ManeuverStatus.rejected_*`` (and the run record).
"""

from __future__ import annotations

import sys
import time
from typing import Any, Callable

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor

from fourws_ros import conversions, topics
from fourws_ros.maneuver_node import ManeuverNode
from fourws_ros.runtime import run_node
from fourws_sim.config_yaml import read_yaml
from fourws_sim.errors import ParameterError
from fourws_sim.input_drivers import (COMMAND_TIMEOUT_S, AckermannDriver, JoyDriver,
                                      joy_mapping_from)
from fourws_sim.params import CONFIG_DIR

#: Input sources: the topic each reads.
SOURCES = {"ackermann": topics.DRIVE, "joy": topics.JOY}


class InputDriverNode(ManeuverNode):
    """A maneuver-role node whose commands come from ``source`` (module docstring)."""

    def __init__(self, source: str) -> None:
        super().__init__()
        if source not in SOURCES:
            raise ParameterError("source", f"must be one of {', '.join(SOURCES)}")
        self.source = source
        self.declare_parameter("command_timeout_s", COMMAND_TIMEOUT_S, ParameterDescriptor(
            description="realtime: a command older than this (wall time) is stale; the car "
                        "then steers straight and brakes, s",
            floating_point_range=[FloatingPointRange(from_value=1e-3, to_value=60.0)]))
        self.declare_parameter("joy_mapping_file", str(CONFIG_DIR / "drivers" / "joy.yaml"),
                               ParameterDescriptor(
            description="joy: YAML file with the axis mapping under joy_mapping (default: "
                        "config/drivers/joy.yaml, the common pad layout)", read_only=True))
        timeout = float(self.get_parameter("command_timeout_s").value)
        vehicle = conversions.vehicle_from_params(self)
        if source == "ackermann":
            self.input: Any = AckermannDriver(vehicle, self.maneuver.spec.speed_hold, timeout)
        else:
            path = str(self.get_parameter("joy_mapping_file").value)
            data = read_yaml(path)
            if not isinstance(data, dict) or "joy_mapping" not in data:
                raise ParameterError("joy_mapping", "missing (a mapping of the axes)", path)
            self.input = JoyDriver(vehicle, joy_mapping_from(data["joy_mapping"], path), timeout)
        self.lockstep = self.gate.lockstep
        self._waiting: list[dict[str, Any]] = []  # lockstep Ackermann: states awaiting /drive
        self._commands: dict[int, tuple[float, float]] = {}  # stamp -> (steer, speed)
        topic = SOURCES[source]
        self.create_subscription(topics.message_class(topic), topic, self._receiver(),
                                 topics.TOPIC_QOS[topic])
        self.get_logger().info(f"{source} driver on {topic} "
                               f"({'per state' if self._per_state else 'latest command'})")

    @property
    def _per_state(self) -> bool:
        return self.lockstep and self.source == "ackermann"

    def _receiver(self) -> Callable[[Any], None]:
        def on_drive(msg: Any) -> None:
            stamp = conversions.stamp_to_ns(msg.header.stamp)
            steer, speed = float(msg.drive.steering_angle), float(msg.drive.speed)
            if self._per_state:
                if not self.input.offer(steer, speed, time.monotonic()):
                    self.gate.rejections.add(topics.DRIVE, "refused", self.input.book.last)
                    return
                self._commands[stamp] = (steer, speed)
                self._answer_waiting()
            elif not self.input.offer(steer, speed, time.monotonic()):
                self.gate.rejections.add(topics.DRIVE, "refused", self.input.book.last)

        def on_joy(msg: Any) -> None:
            if not self.input.offer(list(msg.axes), time.monotonic()):
                self.gate.rejections.add(topics.JOY, "refused", self.input.book.last)

        return on_drive if self.source == "ackermann" else on_joy

    def _answer(self, outputs: dict[str, Any]) -> None:
        """An admitted state: answered now, or (lockstep Ackermann) once its command came."""
        if self._per_state:
            self._waiting.append(outputs)
            self._answer_waiting()
            return
        super()._answer(outputs)

    def _answer_waiting(self) -> None:
        while self._waiting and (self._waiting[0]["stamp_ns"] in self._commands
                                 or self.maneuver.done(self._waiting[0]["sim_time_s"],
                                                       self._waiting[0])):
            outputs = self._waiting.pop(0)
            command = self._commands.pop(outputs["stamp_ns"], None)
            if command is not None:
                self.input.steer_rad, self.input.speed_mps = command
            super()._answer(outputs)

    def driver_command(self, t: float, outputs: dict[str, Any]) -> Any:
        """The driver input of the state at ``t`` from the external command."""
        stale = self.input.book.stale_ticks
        cmd = self.input.command(t, outputs, None if self._per_state else time.monotonic())
        if self.input.book.stale_ticks > stale:
            self.gate.rejections.add(SOURCES[self.source], "stale command",
                                     f"t = {t:.3f} s")
        return cmd


def ackermann_main(args: list[str] | None = None) -> int:
    """Console entry point ``ackermann_driver``."""
    return run_node(lambda: InputDriverNode("ackermann"), args, name="fourws_ackermann_driver")


def joy_main(args: list[str] | None = None) -> int:
    """Console entry point ``joy_driver``."""
    return run_node(lambda: InputDriverNode("joy"), args, name="fourws_joy_driver")


if __name__ == "__main__":
    sys.exit(ackermann_main())
