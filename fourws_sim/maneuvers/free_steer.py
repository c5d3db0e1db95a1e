# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Torque-input maneuvers (free steering control): steering-torque step, ISO 17288-1 steering
release, ISO 17288-2 steering pulse.

These steer with the driver's torque on the steering wheel (``DriverInput.steering_torque_nm``,
N m) on a model whose front angle is a state of a steering system (``8dof-free``,
``2dof-free``); see :mod:`fourws_sim.models.eightdof` for the 8-DOF's steering system. The
angles of their driver inputs are not commands: they report the steering system's angle at the
tick, as the driver's hands (or a steering robot's encoder) feel it, taken from the state,
:math:`\delta_s = \delta_{f,applied} - \varepsilon_f\phi` (the applied angle less the roll
steer), with :math:`\delta_H = N\delta_s`. The controller hands that angle to the rear-steer law
as its :math:`\delta_f`: the laws see the free front angle, as the paper's free-control laws do
(ch. 3.4/4.4).

ISO 17288-1 (steering release): from straight running the driver turns in to a steady turn at
the lateral acceleration ``lateral_accel_mps2`` (ISO 17288-1: 4 m/s^2 at 100 km/h is the
standard condition), holds it, and at ``release_s`` lets go of the wheel: the steering torque
is 0 from then on, and the drive torque is held at its value at the release (the standard keeps
the throttle constant). The hold is a PI controller from the lateral-acceleration error to the
steering torque (a driver keeps the turn by feel, not by angle):

.. math::

    T_H = k_p (a_y^* - a_y) + k_i \int (a_y^* - a_y)\,dt,

with the target :math:`a_y^*` ramped in over ``turn_in_s`` and the integral advanced by
forward Euler with ``dt = t - t_previous`` (as the other drivers). The analysis
(:mod:`fourws_analysis.iso17288`) reads the return from the bag.

ISO 17288-2 (steering pulse): from straight running, a single torque pulse on the steering
wheel (triangle or half sine of peak ``torque_nm`` and width ``width_s``), hands off before and
after; the free oscillation of the steering and the yaw rate that follows is the result.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers.base import (MAX_DURATION_S, TIME_BOUNDS_S, TIME_EPS_S, Maneuver,
                                       ManeuverSpec, check_pulse_shape, pulse_shape,
                                       smooth_ramp)
from fourws_sim.params import Vehicle, _spec


#: Plausibility bounds of a driver's torque on the steering wheel, N m (a strong driver
#: holds about 50 N m with both hands; a steering robot's motor about 100 N m).
TORQUE_BOUNDS_NM = (-100.0, 100.0)


class FreeSteering(Maneuver):
    """Base of the torque-input types: the command's torque comes from
    :meth:`steering_torque_nm`, its angles report the steering system's angle (module
    docstring); the speed-hold driver holds the speed.

    Raises
    ------
    ParameterError
        The vehicle has no ``steering`` data (ratio), or ``steer_input`` is not the default.
    """

    steering_control = "torque"

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        super().__init__(spec, vehicle)
        vehicle.require("steering", user=f"maneuver {spec.name!r} (a steering-torque input "
                                         "acts through the steering ratio)")
        self._eps_f = vehicle.roll.roll_steer_front if vehicle.roll is not None else 0.0

    def steer_angles(self, t: float, outputs: Mapping[str, Any]) -> tuple[float, float]:
        """The steering system's angle at the tick (road wheel, and steering wheel), rad."""
        front = (float(outputs["front_wheel_angle_rad"])
                 - self._eps_f * float(outputs["roll_rad"]))
        return front * self._ratio, front

    def steering_torque_nm(self, t: float, outputs: Mapping[str, Any]) -> float:
        """Driver torque on the steering wheel at ``t`` (N m, positive steers left)."""
        return float(self.params.torque(t))

    def command(self, t: float, outputs: Mapping[str, Any]) -> DriverCommand:
        """The steering torque, the measured angles and the speed-hold torques."""
        speed = float(outputs["speed_mps"])
        hand, front = self.steer_angles(t, outputs)
        torque = self.steering_torque_nm(t, outputs)
        drive, brake = self._speed_driver.command(t, speed, self.target_speed_mps(t))
        return DriverCommand(hand, front, torque, drive, brake)


@dataclass(frozen=True)
class SteeringTorqueStepParams:
    """Steering-torque step: 0 until ``start_s``, a linear ramp over ``ramp_time_s`` to
    ``torque_nm`` on the steering wheel (N m, positive steers left), then held."""

    torque_nm: float = _spec("any", doc="steering-wheel torque, N m", bounds=TORQUE_BOUNDS_NM)
    start_s: float = _spec("nonnegative", default=0.5, bounds=TIME_BOUNDS_S)
    ramp_time_s: float = _spec("nonnegative", default=0.1, bounds=TIME_BOUNDS_S)

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def torque(self, t: float) -> float:
        """Steering-wheel torque (N m) at ``t`` (s)."""
        if self.ramp_time_s == 0.0:
            return self.torque_nm if t >= self.start_s - TIME_EPS_S else 0.0
        return self.torque_nm * smooth_ramp((t - self.start_s) / self.ramp_time_s)

    def phase(self, t: float) -> str:
        """``settle``, ``steer`` (the ramp), ``hold``."""
        if t < self.start_s:
            return "settle"
        return "steer" if t < self.start_s + self.ramp_time_s else "hold"


class SteeringTorqueStep(FreeSteering):
    """A step of steering-wheel torque (:class:`SteeringTorqueStepParams`)."""

    Params = SteeringTorqueStepParams


@dataclass(frozen=True)
class SteeringReleaseParams:
    """ISO 17288-1 steering release (module docstring): turn in from ``start_s`` to the
    steady ``lateral_accel_mps2`` (sign: direction, positive left) over ``turn_in_s``, hold
    it with the PI gains ``hold_kp_nm_per_mps2`` (N m per m/s^2) and ``hold_ki_nm_per_mps3``
    (N m per m/s^2 s), release the wheel at ``release_s``.

    Default gains, found on table_8_1 (its steering system with 1 N m of friction at the
    steering wheel) at 100 km/h: ``k_p = 0`` -- a proportional term feeds the lateral
    acceleration's share of the fast steering-system oscillation (~1.4 Hz, lightly damped)
    back into the torque, and with ``k_p = 1`` the fws car spun during the hold; ``k_i = 1.5``
    N m/(m/s^2 s) turns in without overshoot and holds a steady turn (yaw rate steady to
    0.002 deg/s over the last second) within 1.3 % of 4 m/s^2 by the default release at 10 s
    (the friction then holds the wheel; ``k_i = 4`` made the fws car spin). The stabilising
    laws (sol1, rwc2_3dof) reach the target within 1 %.
    """

    lateral_accel_mps2: float = _spec("any", default=4.0, bounds=(-30.0, 30.0))
    start_s: float = _spec("nonnegative", default=0.5, bounds=TIME_BOUNDS_S)
    turn_in_s: float = _spec("nonnegative", default=2.0, bounds=TIME_BOUNDS_S)
    release_s: float = _spec(default=10.0, bounds=TIME_BOUNDS_S)
    hold_kp_nm_per_mps2: float = _spec("nonnegative", default=0.0, bounds=(0.0, 100.0))
    hold_ki_nm_per_mps3: float = _spec("nonnegative", default=1.5, bounds=(0.0, 100.0))

    event_fields: ClassVar[tuple[str, ...]] = ("start_s", "release_s")

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if self.lateral_accel_mps2 == 0.0:
            raise ParameterError(f"{prefix}lateral_accel_mps2",
                                 "must be nonzero (its sign is the direction)", source)
        if self.release_s < self.start_s + self.turn_in_s:
            raise ParameterError(f"{prefix}release_s", "must be >= start_s + turn_in_s (the "
                                 "turn is held before the release)", source)

    def target(self, t: float) -> float:
        """Lateral-acceleration target of the hold (m/s^2) at ``t`` (s)."""
        if self.turn_in_s == 0.0:
            return self.lateral_accel_mps2 if t >= self.start_s - TIME_EPS_S else 0.0
        return self.lateral_accel_mps2 * smooth_ramp((t - self.start_s) / self.turn_in_s)

    def released(self, t: float) -> bool:
        """True from the release on (1 ns tolerance, as the other time edges)."""
        return t >= self.release_s - TIME_EPS_S

    def phase(self, t: float) -> str:
        """``settle``, ``turn_in``, ``hold``, ``released``."""
        if self.released(t):
            return "released"
        if t < self.start_s:
            return "settle"
        return "turn_in" if t < self.start_s + self.turn_in_s else "hold"


class SteeringRelease(FreeSteering):
    """ISO 17288-1 steering release (:class:`SteeringReleaseParams`)."""

    Params = SteeringReleaseParams

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        super().__init__(spec, vehicle)
        self._integral = 0.0
        self._t_prev: float | None = None
        self._throttle: tuple[float, ...] | None = None

    @classmethod
    def check_spec(cls, params: Any, common: Mapping[str, float], source: str) -> None:
        """The record goes on after the release: ``duration_s > release_s``."""
        if common["duration_s"] <= params.release_s:
            raise ParameterError("duration_s", "must be > release_s (the return after the "
                                 "release is the result)", source)

    def steering_torque_nm(self, t: float, outputs: Mapping[str, Any]) -> float:
        """The hold's PI torque before the release, 0 after."""
        p = self.params
        dt = 0.0 if self._t_prev is None else max(t - self._t_prev, 0.0)
        self._t_prev = t
        if p.released(t) or t < p.start_s:
            return 0.0
        error = p.target(t) - float(outputs["lateral_accel_mps2"])
        self._integral += error * dt
        return p.hold_kp_nm_per_mps2 * error + p.hold_ki_nm_per_mps3 * self._integral

    def command(self, t: float, outputs: Mapping[str, Any]) -> DriverCommand:
        """As :meth:`FreeSteering.command`; from the release on, the drive and brake torques
        of the release tick are held (constant throttle)."""
        cmd = super().command(t, outputs)
        if not self.params.released(t):
            return cmd
        if self._throttle is None:
            self._throttle = (*cmd.drive_torque_nm, *cmd.brake_torque_nm)
        held = self._throttle
        return DriverCommand(cmd.steering_wheel_angle_rad, cmd.front_wheel_angle_rad,
                             cmd.steering_torque_nm, (held[0], held[1], held[2], held[3]),
                             (held[4], held[5], held[6], held[7]))


@dataclass(frozen=True)
class SteeringPulseParams:
    """ISO 17288-2 steering pulse (module docstring): a single torque pulse on the steering
    wheel from ``start_s``, of peak ``torque_nm`` (N m, positive steers left) and width
    ``width_s``, ``triangle`` or ``half_sine``; hands off otherwise."""

    torque_nm: float = _spec("any", doc="peak steering-wheel torque, N m",
                             bounds=TORQUE_BOUNDS_NM)
    width_s: float = _spec(default=0.3, bounds=(1e-3, MAX_DURATION_S))
    start_s: float = _spec("nonnegative", default=0.5, bounds=TIME_BOUNDS_S)
    shape: str = "triangle"

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def shortest_period_s(self) -> tuple[str, float]:
        """The field setting the shortest period of the input, and that period in s."""
        return "width_s", self.width_s

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        check_pulse_shape(self.shape, source, prefix)

    def torque(self, t: float) -> float:
        """Steering-wheel torque (N m) at ``t`` (s)."""
        return self.torque_nm * pulse_shape(t, self.start_s, self.width_s, self.shape)

    def phase(self, t: float) -> str:
        """``settle``, ``pulse``, ``free``."""
        if t < self.start_s:
            return "settle"
        return "pulse" if t < self.start_s + self.width_s else "free"


class SteeringPulse(FreeSteering):
    """ISO 17288-2 steering pulse (:class:`SteeringPulseParams`)."""

    Params = SteeringPulseParams


__all__ = ["FreeSteering", "SteeringPulse", "SteeringPulseParams", "SteeringRelease",
           "SteeringReleaseParams", "SteeringTorqueStep", "SteeringTorqueStepParams"]
