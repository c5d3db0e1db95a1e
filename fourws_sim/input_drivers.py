# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Drivers fed from outside: another stack's Ackermann commands, a gamepad, a keyboard.

These turn the latest external command into the :class:`~fourws_sim.drivers.DriverCommand`
of a control tick, without ROS (the driver nodes of :mod:`fourws_ros.input_driver_node`
convert the messages and call them):

* :class:`AckermannDriver` -- an ``ackermann_msgs/AckermannDrive`` command: ``steering_angle``
  is the front road-wheel angle (the "virtual wheel at the centre of the front axle" of its
  definition), ``speed`` the speed to hold, which the speed-hold loop of
  :class:`~fourws_sim.drivers.SpeedHoldDriver` turns into wheel drive and brake torques;
* :class:`JoyDriver` -- gamepad axes (``sensor_msgs/Joy``) to steering-wheel angle, throttle
  and brake by a :class:`JoyMapping` (defaults: the common pad layout of the ROS ``joy``
  driver, left stick x steers, right trigger throttle, left trigger brake; triggers rest at
  +1 and read -1 pressed).

Trust: a command is refused (and counted by reason, :attr:`rejections`) when it is not finite
or not plausible (a steer beyond :data:`fourws_run.ticks.FRONT_ANGLE_LIMIT_RAD`'s 60 deg, a
speed beyond ``params.MAX_SPEED_MPS``, a gamepad axis outside [-1, 1]); a tick whose latest
accepted command is older than ``timeout_s`` (wall time; realtime) is *stale*: counted, and the
driver steers straight and brakes to a stop (Ackermann: target speed 0; gamepad: full brake),
never holding an old command on.
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

from fourws_sim.drivers import (DriverCommand, SpeedHoldDriver, SpeedHoldSpec,
                                split_brake_torque)
from fourws_sim.errors import ParameterError
from fourws_sim.params import MAX_SPEED_MPS, Vehicle, _from_mapping, _spec

#: Largest road-wheel angle an external command may ask, rad (the simulator's input limit).
STEER_LIMIT_RAD = math.radians(60.0)
#: Default command timeout, s of wall time.
COMMAND_TIMEOUT_S = 0.5


class InputBook:
    """Refusals and stale ticks of an external driver (counted by reason)."""

    def __init__(self) -> None:
        self.rejections: collections.Counter[str] = collections.Counter()
        self.last = ""
        self.stale_ticks = 0
        self.accepted = 0

    def refuse(self, reason: str, detail: str) -> bool:
        """Count one refused command; False."""
        self.rejections[reason] += 1
        self.last = f"{reason} ({detail})"
        return False


class AckermannDriver:
    """Ackermann steering angle and speed to driver inputs (module docstring).

    Parameters
    ----------
    vehicle : Vehicle
        The simulated vehicle (steering ratio, mass, wheel radius of the speed hold).
    speed_hold : SpeedHoldSpec, optional
        The speed loop (default gains).
    timeout_s : float
        A command older than this (wall time) is stale, s.
    """

    def __init__(self, vehicle: Vehicle, speed_hold: SpeedHoldSpec | None = None,
                 timeout_s: float = COMMAND_TIMEOUT_S) -> None:
        self.ratio = vehicle.steering.ratio if vehicle.steering is not None else 1.0
        self.hold = SpeedHoldDriver(speed_hold or SpeedHoldSpec(), vehicle)
        self.timeout_s = float(timeout_s)
        self.book = InputBook()
        self.steer_rad = 0.0
        self.speed_mps = 0.0
        self.received_s = -math.inf

    def offer(self, steering_angle_rad: float, speed_mps: float, now_s: float) -> bool:
        """An Ackermann command received at wall time ``now_s``; True if accepted (held)."""
        if not (math.isfinite(steering_angle_rad) and math.isfinite(speed_mps)):
            return self.book.refuse("not finite", f"{steering_angle_rad!r}, {speed_mps!r}")
        if abs(steering_angle_rad) > STEER_LIMIT_RAD:
            return self.book.refuse("impossible values", f"steering angle "
                                    f"{steering_angle_rad:.4g} rad beyond {STEER_LIMIT_RAD:.3g}")
        if not 0.0 <= speed_mps <= MAX_SPEED_MPS:
            return self.book.refuse("impossible values", f"speed {speed_mps:.4g} m/s outside "
                                    f"[0, {MAX_SPEED_MPS:g}] (fourws drives forward)")
        self.steer_rad, self.speed_mps, self.received_s = (float(steering_angle_rad),
                                                           float(speed_mps), now_s)
        self.book.accepted += 1
        return True

    def command(self, t_s: float, outputs: Mapping[str, Any],
                now_s: float | None = None) -> DriverCommand:
        """The driver input of the tick at simulation time ``t_s`` (``now_s``: wall time, to
        judge staleness; None: the held command is this tick's own, as in lockstep)."""
        steer, target = self.steer_rad, self.speed_mps
        if now_s is not None and now_s - self.received_s > self.timeout_s:
            self.book.stale_ticks += 1
            steer, target = 0.0, 0.0
        drive, brake = self.hold.command(t_s, float(outputs["speed_mps"]), target)
        return DriverCommand(steering_wheel_angle_rad=steer * self.ratio,
                             front_wheel_angle_rad=steer, drive_torque_nm=tuple(drive),
                             brake_torque_nm=tuple(brake))


@dataclass(frozen=True)
class JoyMapping:
    """Which gamepad axis does what (YAML ``joy_mapping`` of ``config/drivers/joy.yaml``).

    The defaults are the common pad layout of the ROS ``joy`` driver (Xbox-style): axis 0 the
    left stick's x (left +1), axis 5 the right trigger, axis 2 the left trigger (each +1
    released, -1 pressed).
    """

    steer_axis: int = 0
    throttle_axis: int = 5
    brake_axis: int = 2
    #: steering-wheel angle at full stick, rad (a quarter turn of a car's wheel)
    steering_wheel_max_rad: float = _spec(default=math.pi / 2, bounds=(0.01, 20.0))
    #: drive request at full throttle and brake request at full brake, m/s^2
    max_accel_mps2: float = _spec(default=3.0, bounds=(0.01, 20.0))
    max_decel_mps2: float = _spec(default=8.0, bounds=(0.01, 20.0))
    #: stick travel around the centre read as 0 (worn pads drift), fraction
    deadzone: float = _spec("fraction", default=0.05, bounds=(0.0, 0.5))
    #: front share of the brake torque
    brake_front_fraction: float = _spec("fraction", default=0.65, bounds=(0.0, 1.0))

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        del unchecked
        for name in ("steer_axis", "throttle_axis", "brake_axis"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 64:
                raise ParameterError(f"{prefix}{name}", f"must be an axis index 0-63, got "
                                     f"{value!r}", source)


def joy_mapping_from(data: Any, source: str | None = None,
                     prefix: str = "joy_mapping.") -> JoyMapping:
    """Validate a ``joy_mapping`` mapping (``None``: the defaults)."""
    return _from_mapping(JoyMapping, {} if data is None else data, source, prefix)


class JoyDriver:
    """Gamepad axes to driver inputs (module docstring).

    Parameters
    ----------
    vehicle : Vehicle
        Steering ratio, mass and wheel radius (torque = mass x request x radius).
    mapping : JoyMapping
    timeout_s : float
        Axes older than this (wall time) are stale, s.
    """

    def __init__(self, vehicle: Vehicle, mapping: JoyMapping | None = None,
                 timeout_s: float = COMMAND_TIMEOUT_S) -> None:
        self.mapping = mapping or JoyMapping()
        self.ratio = vehicle.steering.ratio if vehicle.steering is not None else 1.0
        radius = vehicle.body.wheel_radius_m if vehicle.body is not None else 0.0
        self._torque_per_mps2 = vehicle.chassis.mass_kg * radius
        self.timeout_s = float(timeout_s)
        self.book = InputBook()
        self.axes = (0.0, 0.0, 0.0)  # steer, throttle, brake in [0, 1] / [-1, 1]
        self.received_s = -math.inf

    def offer(self, axes: Sequence[float], now_s: float) -> bool:
        """A ``Joy`` message's axes received at wall time ``now_s``; True if accepted."""
        m = self.mapping
        needed = max(m.steer_axis, m.throttle_axis, m.brake_axis) + 1
        if len(axes) < needed:
            return self.book.refuse("impossible values", f"{len(axes)} axes, the mapping "
                                    f"reads axis {needed - 1}")
        values = [float(axes[i]) for i in (m.steer_axis, m.throttle_axis, m.brake_axis)]
        if not all(math.isfinite(v) and -1.0 <= v <= 1.0 for v in values):
            return self.book.refuse("impossible values", f"axes {values} outside [-1, 1]")
        steer = 0.0 if abs(values[0]) < m.deadzone else values[0]
        # triggers: +1 released, -1 pressed -> 0..1
        self.axes = (steer, (1.0 - values[1]) / 2.0, (1.0 - values[2]) / 2.0)
        self.received_s = now_s
        self.book.accepted += 1
        return True

    def command(self, t_s: float, outputs: Mapping[str, Any],
                now_s: float | None = None) -> DriverCommand:
        """The driver input of a tick (stale axes: straight ahead, full brake)."""
        del t_s, outputs
        m = self.mapping
        steer, throttle, brake = self.axes
        if now_s is not None and now_s - self.received_s > self.timeout_s:
            self.book.stale_ticks += 1
            steer, throttle, brake = 0.0, 0.0, 1.0
        wheel = steer * m.steering_wheel_max_rad
        drive = throttle * m.max_accel_mps2 * self._torque_per_mps2 / 2.0  # rear axle
        total_brake = brake * m.max_decel_mps2 * self._torque_per_mps2
        return DriverCommand(steering_wheel_angle_rad=wheel,
                             front_wheel_angle_rad=wheel / self.ratio,
                             drive_torque_nm=(0.0, 0.0, drive, drive),
                             brake_torque_nm=split_brake_torque(total_brake,
                                                                m.brake_front_fraction))


class KeyboardAxes:
    """A terminal's keys as the axes of the common pad layout (what ``fourws node
    keyboard_driver`` publishes on ``/joy`` for :class:`JoyDriver`): ``a``/``d`` (or the
    left/right arrows) steer by :attr:`STEER_STEP` of full lock per press, ``w``/``s`` (or
    up/down) add throttle or brake by :attr:`PEDAL_STEP` (one pedal at a time: pressing one
    releases the other), space returns to straight ahead with no pedal."""

    STEER_STEP = 0.1
    PEDAL_STEP = 0.25
    #: key -> action (arrow keys arrive as the escape sequences' last byte)
    KEYS = {"a": "left", "D": "left", "d": "right", "C": "right", "w": "throttle",
            "A": "throttle", "s": "brake", "B": "brake", " ": "centre"}

    def __init__(self, mapping: JoyMapping | None = None) -> None:
        self.mapping = mapping or JoyMapping()
        self.steer = 0.0
        self.throttle = 0.0
        self.brake = 0.0

    def press(self, key: str) -> bool:
        """A key; True if it is one of :attr:`KEYS`."""
        action = self.KEYS.get(key)
        if action == "left":
            self.steer = min(self.steer + self.STEER_STEP, 1.0)
        elif action == "right":
            self.steer = max(self.steer - self.STEER_STEP, -1.0)
        elif action == "throttle":
            self.throttle, self.brake = min(self.throttle + self.PEDAL_STEP, 1.0), 0.0
        elif action == "brake":
            self.brake, self.throttle = min(self.brake + self.PEDAL_STEP, 1.0), 0.0
        elif action == "centre":
            self.steer = self.throttle = self.brake = 0.0
        return action is not None

    def axes(self) -> list[float]:
        """The ``Joy`` axes (triggers +1 released, -1 pressed) under :attr:`mapping`."""
        m = self.mapping
        out = [0.0] * (max(m.steer_axis, m.throttle_axis, m.brake_axis) + 1)
        out[m.steer_axis] = self.steer
        out[m.throttle_axis] = 1.0 - 2.0 * self.throttle
        out[m.brake_axis] = 1.0 - 2.0 * self.brake
        return out


__all__ = ["AckermannDriver", "COMMAND_TIMEOUT_S", "InputBook", "JoyDriver", "JoyMapping",
           "KeyboardAxes",
           "STEER_LIMIT_RAD", "joy_mapping_from"]
