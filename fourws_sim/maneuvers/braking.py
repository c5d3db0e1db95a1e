"""Braking in a turn (Samsundar 1996, ch. 8, Figs. 8.23-8.27)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

from fourws_sim.drivers import DriverCommand, split_brake_torque
from fourws_sim.maneuvers.base import (ANGLE_BOUNDS_RAD, MAX_DURATION_S, RATE_BOUNDS_RADPS,
                                       TIME_BOUNDS_S, TIME_EPS_S, Maneuver, ManeuverSpec,
                                       smooth_ramp)
from fourws_sim.params import GRAVITY_MPS2, Vehicle, _spec


@dataclass(frozen=True)
class BrakeInTurnParams:
    """Braking in a turn (ch. 8, Figs. 8.23-8.27): ramp steer to ``amplitude_rad`` at
    ``rate_radps`` from ``steer_start_s``; at ``brake_start_s`` a step brake torque meant to give
    ``deceleration_mps2`` (default 0.3 g) is applied for ``brake_duration_s`` (1 s) — total
    torque ``(m + 4 I_w / R^2) R a``: the vehicle mass plus the equivalent mass of the four
    spinning wheels, which the brakes decelerate too (7 % of m on table_8_1; with ``m R a``
    alone the car reaches 0.28 g). The paper applies a step torque (Fig. 8.23), not a
    deceleration controller, and so does fourws. The torque is split by the speed-hold
    ``brake_front_fraction``. No drive torque while braking; afterwards the speed-hold driver
    holds the speed reached at the brake release."""

    amplitude_rad: float = _spec("any", bounds=ANGLE_BOUNDS_RAD)
    rate_radps: float = _spec(bounds=RATE_BOUNDS_RADPS)
    steer_start_s: float = _spec("nonnegative", default=0.5, bounds=TIME_BOUNDS_S)
    brake_start_s: float = _spec("nonnegative", default=2.0, bounds=TIME_BOUNDS_S)
    brake_duration_s: float = _spec(default=1.0, bounds=(1e-3, MAX_DURATION_S))
    deceleration_mps2: float = _spec(default=0.3 * GRAVITY_MPS2, bounds=(0.01, 15.0))

    event_fields: ClassVar[tuple[str, ...]] = ("steer_start_s", "brake_start_s")

    def steer(self, t: float) -> float:
        """Input angle (rad) at time ``t`` (s)."""
        ramp = abs(self.amplitude_rad) / self.rate_radps
        if ramp == 0.0:
            return self.amplitude_rad if t >= self.steer_start_s - TIME_EPS_S else 0.0
        return self.amplitude_rad * smooth_ramp((t - self.steer_start_s) / ramp)

    def braking(self, t: float) -> bool:
        """True while the brake torque is applied (edges with a 1 ns tolerance, so tick
        times that differ by rounding, k*Tc vs n*dt, switch at the same tick)."""
        return (self.brake_start_s - TIME_EPS_S <= t
                < self.brake_start_s + self.brake_duration_s - TIME_EPS_S)

    def phase(self, t: float) -> str:
        """``settle``, ``steer``, ``brake``, ``hold``."""
        if t < self.steer_start_s:
            return "settle"
        if self.braking(t):
            return "brake"
        if t < self.brake_start_s:
            return "steer"
        return "hold"


class BrakeInTurn(Maneuver):
    """Braking in a turn (:class:`BrakeInTurnParams`): a step brake torque instead of the
    speed-hold driver while braking, then the speed reached is held."""

    Params = BrakeInTurnParams

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        super().__init__(spec, vehicle)
        self._hold_after_brake_mps: float | None = None

    def target_speed_mps(self, t: float) -> float:
        """The initial speed, after the brake release the speed reached then."""
        if self._hold_after_brake_mps is not None:
            return self._hold_after_brake_mps
        return self.initial_speed_mps

    def command(self, t: float, outputs: Mapping[str, Any]) -> DriverCommand:
        """The ramp steer; while braking the step brake torque and no drive torque."""
        speed = float(outputs["speed_mps"])
        hand, front = self.steer_angles(t, outputs)
        p = self.params
        if p.braking(t):
            self._speed_driver.command(t, speed, speed)  # keeps its clock, no integration
            total = self._brake_torque_nm(p.deceleration_mps2)
            brake = split_brake_torque(total, self.spec.speed_hold.brake_front_fraction)
            return DriverCommand(hand, front, 0.0, (0.0, 0.0, 0.0, 0.0), brake)
        if t >= p.brake_start_s - TIME_EPS_S and self._hold_after_brake_mps is None:
            self._hold_after_brake_mps = speed
            self._speed_driver.reset()
        drive, brake = self._speed_driver.command(t, speed, self.target_speed_mps(t))
        return DriverCommand(hand, front, 0.0, drive, brake)

    def _brake_torque_nm(self, decel_mps2: float) -> float:
        """Total brake torque (N m) for ``decel_mps2``: ``(m + 4 I_w / R^2) R a``."""
        self.vehicle.require("body", user="maneuver brake_in_turn (brake torque from m, R, I_w)")
        body = self.vehicle.body
        assert body is not None
        radius = body.wheel_radius_m
        mass = self.vehicle.chassis.mass_kg + 4.0 * body.wheel_spin_inertia_kgm2 / radius ** 2
        return mass * radius * decel_mps2


__all__ = ["BrakeInTurn", "BrakeInTurnParams"]
