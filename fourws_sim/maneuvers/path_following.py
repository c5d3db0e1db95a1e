# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Closed-loop driving tasks: ISO 4138 constant radius and the ISO 3888-2 lane change.

A driver model of :mod:`fourws_sim.drivers` steers (the preview path follower on a circle, the
path-tracking driver on the widest-margin line through the cones); the speed-hold driver holds
the speed the type asks for.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

from fourws_sim.corridor import CorridorPlan, plan_corridor_path
from fourws_sim.drivers import Path as ReferencePath
from fourws_sim.drivers import CirclePath, PathTrackingDriver, PreviewPathDriver, SplinePath
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers.base import (MAX_DURATION_S, MAX_PATH_POINTS, TIME_EPS_S, Maneuver,
                                       ManeuverSpec)
from fourws_sim.params import MAX_SPEED_MPS, Vehicle, _spec


class PathFollowing(Maneuver):
    """A maneuver whose driver steers (the subclass builds ``self._path_driver``)."""

    _path_driver: PreviewPathDriver | PathTrackingDriver

    @property
    def reference_path(self) -> ReferencePath | None:
        """The path the driver follows."""
        return self._path_driver.path

    def steer_angles(self, t: float, outputs: Mapping[str, Any]) -> tuple[float, float]:
        """The driver's front road-wheel angle and its steering-wheel angle (rad)."""
        front = self._path_driver.steer(t, outputs)
        return front * self._ratio, front


@dataclass(frozen=True)
class ConstantRadiusParams:
    """ISO 4138 constant-radius method (closed loop): the path driver follows a circle of
    ``radius_m`` (``direction`` left or right, tangent to the start pose) while the target
    speed steps from the initial speed by ``speed_step_mps`` every ``dwell_s`` up to
    ``final_speed_mps`` (quasi-steady: each step settles before the next). The run ends after
    the last dwell, or aborts when the path error exceeds ``max_path_error_m`` (the car can no
    longer hold the circle) or the sideslip exceeds ``max_sideslip_rad`` (the car spun; the
    kinematic sideslip b/R of a 40 m circle is ~0.04 rad)."""

    radius_m: float = _spec(bounds=(0.1, 1e4))
    final_speed_mps: float = _spec(bounds=(0.0, MAX_SPEED_MPS))
    speed_step_mps: float = _spec(default=1.0, bounds=(1e-3, MAX_SPEED_MPS))
    dwell_s: float = _spec(default=8.0, bounds=(1e-2, MAX_DURATION_S))
    direction: str = "left"
    # abort thresholds: any small one is meaningful (it ends the run early on purpose)
    max_path_error_m: float = _spec(default=5.0, bounds=(0.0, 1e3))
    max_sideslip_rad: float = _spec(default=0.25, bounds=(0.0, math.pi / 2))

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if self.direction not in ("left", "right"):
            raise ParameterError(f"{prefix}direction",
                                 f"must be left or right, got {self.direction!r}", source)


class ConstantRadius(PathFollowing):
    """ISO 4138 constant radius with the preview path follower (:class:`ConstantRadiusParams`,
    driver ``path_driver``)."""

    Params = ConstantRadiusParams
    driver_key = "path_driver"

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        super().__init__(spec, vehicle)
        p = spec.params
        direction = 1 if p.direction == "left" else -1
        assert spec.path_driver is not None
        self._path_driver = PreviewPathDriver(spec.path_driver, vehicle,
                                              CirclePath(p.radius_m, direction))

    @classmethod
    def check_spec(cls, params: Any, common: Mapping[str, float], source: str) -> None:
        """The speed only steps up: ``final_speed_mps >= initial_speed_mps``."""
        if params.final_speed_mps < common["initial_speed_mps"]:
            raise ParameterError("final_speed_mps", "must be >= initial_speed_mps", source)

    def target_speed_mps(self, t: float) -> float:
        """The initial speed stepped up by ``speed_step_mps`` every ``dwell_s``, capped."""
        p = self.params
        steps = math.floor((t + TIME_EPS_S) / p.dwell_s)
        return min(self.initial_speed_mps + steps * p.speed_step_mps, p.final_speed_mps)

    def type_phase(self, t: float) -> str:
        """``speed_<target>_mps``."""
        return f"speed_{self.target_speed_mps(t):.2f}_mps"

    def check_end(self, t: float, outputs: Mapping[str, Any]) -> None:
        """Abort when the car leaves the circle or spins."""
        p = self.params
        error = self._path_driver.path.lateral_error(float(outputs["x_m"]),
                                                     float(outputs["y_m"]))
        sideslip = float(outputs.get("sideslip_rad", 0.0))
        if abs(error) > p.max_path_error_m:
            self.end(f"path error {error:.2f} m exceeds max_path_error_m")
        elif abs(sideslip) > p.max_sideslip_rad:
            self.end(f"sideslip {sideslip:.2f} rad exceeds max_sideslip_rad (the driver "
                     "cannot hold the circle)")


@dataclass(frozen=True)
class DoubleLaneChangeParams:
    """ISO 3888-2 obstacle-avoidance lane change, driven by the path-tracking driver.

    Track (ISO 3888-2:2011, Table 1; W = ``vehicle_width_m``; the car starts at x = 0, y = 0
    heading +x, section 1 begins ``approach_m`` = x0 ahead, y = 0 on its centre line, lane
    change to the left; positions below relative to x0): section 1 x in [0, 12],
    width 1.1 W + 0.25; section 2 (free) 13.5 m; section 3 x in [25.5, 36.5], width W + 1,
    its right edge 1 m left of the left edge of section 1; section 4 (free) 12.5 m; section 5
    x in [49, 61], width 1.3 W + 0.25 but at least 3 m, its right edge in line with that of
    section 1. The driver's reference line is the widest-margin line through the three gated
    sections (:func:`fourws_sim.corridor.plan_corridor_path`) at the maneuver's speed, with
    its lateral acceleration bounded by ``path_lateral_accel_mps2`` and its lateral jerk by
    ``path_lateral_jerk_mps3``; it starts at the start pose and runs out straight
    ``path_runout_m`` after section 5, on a grid of ``path_step_m``.
    """

    vehicle_width_m: float = _spec(default=1.7, bounds=(0.05, 5.0))
    approach_m: float = _spec(default=30.0, doc="start to section 1, m", bounds=(0.1, 1e3))
    path_lateral_accel_mps2: float = _spec(default=6.25,
                                           doc="line's lateral-acceleration bound",
                                           bounds=(0.1, 30.0))
    path_lateral_jerk_mps3: float = _spec(default=30.0, doc="line's lateral-jerk bound",
                                          bounds=(0.1, 1e3))
    path_runout_m: float = _spec(default=20.0, doc="straight run-out after section 5, m",
                                 bounds=(0.1, 1e3))
    path_step_m: float = _spec(default=0.5, doc="grid step of the line, m", bounds=(0.01, 5.0))

    #: Length of the ISO 3888-2 course from the entry of section 1 to the exit of section 5, m.
    COURSE_LENGTH_M: ClassVar[float] = 61.0

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        points = (self.approach_m + self.COURSE_LENGTH_M + self.path_runout_m) / self.path_step_m
        if points > MAX_PATH_POINTS:
            raise ParameterError(f"{prefix}path_step_m", f"gives a line of {points:.3g} points, "
                                 f"more than the limit {MAX_PATH_POINTS}", source)

    @property
    def sections(self) -> list[tuple[float, float, float, float]]:
        """Gated sections as (x_start, x_end, y_right, y_left) in m (earth frame)."""
        x0 = self.approach_m
        w = self.vehicle_width_m
        w1 = 1.1 * w + 0.25
        w3 = w + 1.0
        w5 = max(1.3 * w + 0.25, 3.0)
        y3_right = 0.5 * w1 + 1.0
        return [(x0, x0 + 12.0, -0.5 * w1, 0.5 * w1),
                (x0 + 25.5, x0 + 36.5, y3_right, y3_right + w3),
                (x0 + 49.0, x0 + 61.0, -0.5 * w1, -0.5 * w1 + w5)]

    def plan(self, speed_mps: float) -> CorridorPlan:
        """The widest-margin line for ``speed_mps`` (m/s), earth frame (cached per input)."""
        return _planned_line(tuple(self.sections), self.vehicle_width_m, float(speed_mps),
                             self.path_lateral_accel_mps2, self.path_lateral_jerk_mps3,
                             self.approach_m + self.COURSE_LENGTH_M + self.path_runout_m,
                             self.path_step_m)

    def path(self, speed_mps: float) -> SplinePath:
        """The driver's reference line for ``speed_mps`` (m/s) as a :class:`SplinePath`."""
        plan = self.plan(speed_mps)
        return SplinePath(plan.x_m, plan.y_m, plan.margin_m)


@functools.lru_cache(maxsize=32)
def _planned_line(sections: tuple[tuple[float, float, float, float], ...], width_m: float,
                  speed_mps: float, accel_mps2: float, jerk_mps3: float, x_end_m: float,
                  step_m: float) -> CorridorPlan:
    """:func:`plan_corridor_path` from the start pose, cached: a run, its twin in the node graph
    and every law of a comparison plan the same line once (two linear programs, ~0.1 s)."""
    plan = plan_corridor_path(sections, width_m, speed_mps, accel_mps2, jerk_mps3,
                              x_start_m=0.0, x_end_m=x_end_m, step_m=step_m)
    plan.x_m.flags.writeable = False
    plan.y_m.flags.writeable = False
    return plan


class DoubleLaneChange(PathFollowing):
    """ISO 3888-2 lane change with the path-tracking driver (:class:`DoubleLaneChangeParams`,
    driver ``tracking_driver``)."""

    Params = DoubleLaneChangeParams
    driver_key = "tracking_driver"

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        super().__init__(spec, vehicle)
        assert spec.tracking_driver is not None
        self._path_driver = PathTrackingDriver(spec.tracking_driver, vehicle,
                                               spec.params.path(spec.initial_speed_mps))

    @classmethod
    def check_spec(cls, params: Any, common: Mapping[str, float], source: str) -> None:
        """The line is planned for the initial speed: it must be > 0; and the run must last
        until the car is through the course."""
        if common["initial_speed_mps"] <= 0.0:
            raise ParameterError("initial_speed_mps",
                                 "must be > 0 (the line is planned for it)", source)
        course_end_m = params.approach_m + params.COURSE_LENGTH_M
        if common["initial_speed_mps"] * common["duration_s"] < course_end_m:
            raise ParameterError("duration_s", f"too short to reach the end of the course "
                                 f"({course_end_m:g} m) at initial_speed_mps", source)

    def type_phase(self, t: float) -> str:
        """``approach``, ``course`` (the 61 m of gates), ``exit`` by the nominal position."""
        x = t * self.initial_speed_mps - self.params.approach_m  # position in the course
        return "approach" if x < 0.0 else ("course" if x < self.params.COURSE_LENGTH_M
                                           else "exit")


__all__ = ["ConstantRadius", "ConstantRadiusParams", "DoubleLaneChange",
           "DoubleLaneChangeParams", "PathFollowing"]
