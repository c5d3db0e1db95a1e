# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""What the simulator draws of each state, without ROS: the car's frames and its markers.

:class:`CarScene` turns a state's outputs (``Simulator.outputs()``, the ``VehicleState``
fields) into the transforms of ``/tf`` and the markers of ``/fourws/markers``; the encoders of
:mod:`fourws_run.scene_codecs` write them as CDR bytes, the simulator node publishes them
(:mod:`fourws_ros.simulator_node`, ``side_publications``). Frames and their meaning:
:mod:`fourws_run.urdf` (module docstring) and :data:`fourws_run.interface.FRAMES`.

Transforms (each ``(tx, ty, tz, qx, qy, qz, qw)``, m and a unit quaternion), in
:data:`DYNAMIC_FRAMES` order:

* ``odom -> base_link``: the CG's position on the road and the heading (``x_m``, ``y_m``,
  ``heading_rad``): the position and yaw of ``/fourws/odom``;
* ``base_link -> body``: the roll ``roll_rad`` about x, at the roll-axis height (REP-103 roll:
  positive lowers the right side, the fourws sign), so ``odom -> body`` has the orientation of
  ``/fourws/odom``;
* ``<wheel>_mount -> <wheel>_steer``: the applied road-wheel angle about z
  (``front_wheel_angle_rad`` for FL and FR, ``rear_wheel_angle_rad`` for RL and RR; roll steer
  included);
* ``<wheel>_steer -> <wheel>_wheel``: the spin angle about y. The model has no wheel angle
  state, so the scene integrates ``wheel_speed_radps`` between consecutive states
  (trapezoidal rule, wrapped to [-pi, pi)): a visual quantity only, 0 for models without
  wheels, restarting at 0 when a state at t = 0 comes.

The fixed ``base_link -> <wheel>_mount`` offsets (the wheel centres) go on ``/tf_static``
(:meth:`CarScene.static_transforms`).

Markers (fixed in number and layout, so one encoder serves a run):

* every state the odometry is due (``viz_period_s``): per wheel the tire force (``fx_n``,
  ``fy_n`` in the steer frame, the tire frame of the model) as an arrow from the contact
  patch, :data:`FORCE_LENGTH_PER_LOAD` wheelbases long per static wheel load, coloured by
  friction use ``sqrt(fx^2 + fy^2) / (mu Fz)`` from green (0) through yellow to red (1 and
  beyond; ``mu`` the tire file's ``friction_coefficient``, 1 without one: the peak of the
  STI, Magic Formula and TMeasy tires at the road of their data); the CG velocity as an arrow
  (the distance covered in :data:`VELOCITY_ARROW_S`) and the sideslip as a text above the car;
* every ``path_period_s``: the path the CG drove (a line of :data:`PATH_POINTS` points, thinned
  by half whenever full) and, where the maneuver has one, its course: the cones along both
  edges of the ISO 3888-2 gated sections (every :data:`CONE_SPACING_M`), the edges as lines,
  and the target line of the driver (the lane change's planned line, the constant-radius
  circle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from fourws_run.interface import (FRAME_BODY, FRAME_MOUNT, FRAME_ODOM, FRAME_SPRUNG,
                                  FRAME_STEER, FRAME_WHEEL, N_WHEELS)
from fourws_run.urdf import CarGeometry
from fourws_sim.drivers import CirclePath
from fourws_sim.maneuvers import Maneuver
from fourws_sim.maneuvers.path_following import ConstantRadius, DoubleLaneChange
from fourws_sim.params import GRAVITY_MPS2, Vehicle

#: The moving frames, (parent, child), in the order of :meth:`CarScene.transforms`.
DYNAMIC_FRAMES: tuple[tuple[str, str], ...] = (
    (FRAME_ODOM, FRAME_BODY), (FRAME_BODY, FRAME_SPRUNG),
    *zip(FRAME_MOUNT, FRAME_STEER), *zip(FRAME_STEER, FRAME_WHEEL))
#: The fixed frames (``/tf_static``), in the order of :meth:`CarScene.static_transforms`.
STATIC_FRAMES: tuple[tuple[str, str], ...] = tuple((FRAME_BODY, m) for m in FRAME_MOUNT)
#: A tire force equal to the static wheel load is drawn this many wheelbases long.
FORCE_LENGTH_PER_LOAD = 0.5
#: The velocity arrow is the distance the CG covers in this time, s.
VELOCITY_ARROW_S = 0.1
#: Points of the driven-path line.
PATH_POINTS = 256
#: Points of a target line at most (a longer one is thinned).
TARGET_POINTS = 256
#: Spacing of the cones along a gated section's edges, m.
CONE_SPACING_M = 3.0
#: The sideslip text: fixed width (``beta +12.34 deg``), so every marker message has one layout.
SIDESLIP_FORMAT = "beta {:+6.2f} deg"
SIDESLIP_TEXT_CHARS = len(SIDESLIP_FORMAT.format(0.0))
#: Largest sideslip the text shows, deg (beyond it the car has spun: fourws_sim.outcome).
SIDESLIP_SHOWN_DEG = 999.99

_IDENTITY = (0.0, 0.0, 0.0, 1.0)
RGBA = tuple[float, float, float, float]


@dataclass(frozen=True)
class Marker:
    """The fixed part of one marker (its layout: the encoder's template).

    Attributes
    ----------
    ns : str
        Marker namespace (with ``id`` what a viewer replaces).
    id : int
    kind : str
        A ``visualization_msgs/Marker`` type constant name (``"ARROW"``, ``"LINE_STRIP"``...).
    frame : str
        ``header.frame_id``.
    points : int
        Number of points (fixed per run).
    scale : tuple of 3 float
        ``scale`` (arrows: shaft and head diameter, head length; lines: width; text: height), m.
    position : tuple of 3 float
        ``pose.position`` (orientation identity), m.
    color : tuple of 4 float
        The colour when it does not change (RGBA, 0..1).
    text_chars : int
        Length of the text (fixed), 0 for none.
    """

    ns: str
    id: int
    kind: str
    frame: str
    points: int = 0
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    color: RGBA = (1.0, 1.0, 1.0, 1.0)
    text_chars: int = 0


@dataclass(frozen=True)
class MarkerValues:
    """The changing part of one marker: colour, points (m, in its frame) and text."""

    color: RGBA
    points: Sequence[tuple[float, float, float]] = ()
    text: str = ""


@dataclass(frozen=True)
class Course:
    """A maneuver's course in ``odom``: cone positions, edge segments and the target line, m."""

    cones: tuple[tuple[float, float, float], ...]
    edges: tuple[tuple[float, float, float], ...]
    target: tuple[tuple[float, float, float], ...]


def course_of(maneuver: Maneuver | None) -> Course | None:
    """The course of ``maneuver`` (None when it has none): the ISO 3888-2 lane change's gates
    and planned line, the constant-radius circle."""
    if isinstance(maneuver, DoubleLaneChange):
        params = maneuver.spec.params
        cones: list[tuple[float, float, float]] = []
        edges: list[tuple[float, float, float]] = []
        for x0, x1, y_right, y_left in params.sections:
            n = max(int(math.ceil((x1 - x0) / CONE_SPACING_M)), 1)
            for y in (y_right, y_left):
                cones += [(x0 + (x1 - x0) * k / n, y, 0.0) for k in range(n + 1)]
                edges += [(x0, y, 0.0), (x1, y, 0.0)]
        plan = params.plan(maneuver.initial_speed_mps)
        step = max(int(math.ceil(plan.x_m.size / TARGET_POINTS)), 1)
        target = tuple((float(x), float(y), 0.0)
                       for x, y in zip(plan.x_m[::step], plan.y_m[::step]))
        return Course(tuple(cones), tuple(edges), target)
    if isinstance(maneuver, ConstantRadius):
        path = maneuver.reference_path
        assert isinstance(path, CirclePath)
        cx, cy = path.centre
        radius = math.hypot(cx, cy)
        start = math.atan2(-cy, -cx)
        target = tuple((cx + radius * math.cos(start + 2 * math.pi * k / (TARGET_POINTS - 1)),
                        cy + radius * math.sin(start + 2 * math.pi * k / (TARGET_POINTS - 1)),
                        0.0) for k in range(TARGET_POINTS))
        return Course((), (), target)
    return None


def about_axis(axis: int, angle_rad: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation by ``angle_rad`` about body axis 0 (x), 1 (y) or 2 (z):
    :func:`fourws_run.codecs.quaternion_from_euler` with one angle, without its other four
    trigonometric calls (the scene makes nine of them per state)."""
    q = [0.0, 0.0, 0.0, math.cos(angle_rad / 2)]
    q[axis] = math.sin(angle_rad / 2)
    return (q[0], q[1], q[2], q[3])


def friction_color(use: float) -> RGBA:
    """Green (0) through yellow (0.5) to red (1 and beyond) for a friction use."""
    u = min(max(use, 0.0), 1.0)
    return (min(1.0, 2.0 * u), 0.8 * min(1.0, 2.0 * (1.0 - u)), 0.0, 1.0)


def _floats(values: Any, default: tuple[float, ...]) -> list[float]:
    """A per-wheel output as Python floats (a numpy array's ``tolist``)."""
    if values is None:
        return list(default)
    return values.tolist() if isinstance(values, np.ndarray) else [float(v) for v in values]


class PathTrail:
    """The driven path as a fixed number of points: every ``stride``-th position is kept, and
    when the line is full every other point is dropped and the stride doubles (the line
    covers the whole run at a resolution that halves as it grows)."""

    def __init__(self, points: int = PATH_POINTS) -> None:
        self.capacity = int(points)
        self.kept: list[tuple[float, float, float]] = []
        self.stride = 1
        self._seen = 0

    def add(self, x_m: float, y_m: float) -> list[tuple[float, float, float]]:
        """Take the current position; the line to draw (:attr:`capacity` points, the last
        ones the current position)."""
        if self._seen % self.stride == 0:
            if len(self.kept) == self.capacity - 1:
                self.kept = self.kept[::2]
                self.stride *= 2
            if self._seen % self.stride == 0:  # the kept positions stay a whole stride apart
                self.kept.append((x_m, y_m, 0.0))
        self._seen += 1
        here = (x_m, y_m, 0.0)
        return self.kept + [here] * (self.capacity - len(self.kept))


class CarScene:
    """The frames and markers of one run's car (module docstring).

    Parameters
    ----------
    vehicle : Vehicle
        The simulated vehicle.
    maneuver : Maneuver, optional
        The run's maneuver (for its course).
    """

    def __init__(self, vehicle: Vehicle, maneuver: Maneuver | None = None) -> None:
        self.geometry = g = CarGeometry.of(vehicle)
        self.vehicle = vehicle
        self.course = course_of(maneuver)
        self.friction = (vehicle.tire.friction_coefficient if vehicle.tire is not None
                         and vehicle.tire.model == "linear" else 1.0)
        self._force_scale = (FORCE_LENGTH_PER_LOAD * g.wheelbase_m
                             / (vehicle.chassis.mass_kg * GRAVITY_MPS2 / N_WHEELS))
        self.spin = [0.0] * N_WHEELS
        self._t_prev: float | None = None
        self._w_prev = [0.0] * N_WHEELS
        self.trail = PathTrail()
        r, length = g.wheel_radius_m, g.wheelbase_m
        arrow = (0.15 * r, 0.3 * r, 0.3 * r)
        (_, _, box_z), (_, _, box_h) = g.body_box()
        self.fast_markers: tuple[Marker, ...] = (
            *(Marker("tire_force", i, "ARROW", FRAME_STEER[i], 2, arrow) for i in range(N_WHEELS)),
            Marker("velocity", 0, "ARROW", FRAME_BODY, 2, arrow, color=(0.2, 0.6, 1.0, 1.0)),
            Marker("sideslip", 0, "TEXT_VIEW_FACING", FRAME_BODY, 0, (0.0, 0.0, 0.12 * length),
                   (0.0, 0.0, box_z + box_h / 2 + 0.1 * length), text_chars=SIDESLIP_TEXT_CHARS),
        )
        slow = [Marker("path", 0, "LINE_STRIP", FRAME_ODOM, PATH_POINTS,
                       (0.03 * length, 0.0, 0.0), color=(0.2, 0.4, 1.0, 1.0))]
        if self.course is not None:
            if self.course.cones:
                slow.append(Marker("cones", 0, "CUBE_LIST", FRAME_ODOM, len(self.course.cones),
                                   (0.3, 0.3, 0.5), (0.0, 0.0, 0.25), (1.0, 0.45, 0.0, 1.0)))
                slow.append(Marker("corridor", 0, "LINE_LIST", FRAME_ODOM,
                                   len(self.course.edges), (0.04, 0.0, 0.0),
                                   color=(1.0, 0.45, 0.0, 0.8)))
            slow.append(Marker("target_line", 0, "LINE_STRIP", FRAME_ODOM,
                               len(self.course.target), (0.03 * length, 0.0, 0.0),
                               color=(0.1, 0.8, 0.1, 0.8)))
        self.slow_markers: tuple[Marker, ...] = tuple(slow)

    # ------------------------------------------------------------------ frames
    def static_transforms(self) -> list[tuple[float, ...]]:
        """``base_link -> <wheel>_mount`` (:data:`STATIC_FRAMES` order): the wheel centres."""
        return [(*centre, *_IDENTITY) for centre in self.geometry.wheel_centres()]

    def transforms(self, outputs: Mapping[str, Any]) -> list[tuple[float, ...]]:
        """The :data:`DYNAMIC_FRAMES` of a state's outputs (module docstring); advances the
        wheels' spin angles from the previous state."""
        get = outputs.get
        t = float(get("sim_time_s", 0.0))
        speeds = get("wheel_speed_radps")
        wheels = [float(w) for w in speeds] if speeds is not None else [0.0] * N_WHEELS
        if self._t_prev is None or t <= 0.0 or t < self._t_prev:
            self.spin = [0.0] * N_WHEELS
        else:
            dt = 0.5 * (t - self._t_prev)
            two_pi = 2.0 * math.pi
            self.spin = [(s + (w0 + w1) * dt + math.pi) % two_pi - math.pi
                         for s, w0, w1 in zip(self.spin, self._w_prev, wheels)]
        self._t_prev, self._w_prev = t, wheels
        steer = [about_axis(2, float(get("front_wheel_angle_rad", 0.0))),
                 about_axis(2, float(get("rear_wheel_angle_rad", 0.0)))]
        return [
            (float(get("x_m", 0.0)), float(get("y_m", 0.0)), 0.0,
             *about_axis(2, float(get("heading_rad", 0.0)))),
            (0.0, 0.0, self.geometry.roll_axis_height_m,
             *about_axis(0, float(get("roll_rad", 0.0)))),
            *((0.0, 0.0, 0.0, *steer[i // 2]) for i in range(N_WHEELS)),
            *((0.0, 0.0, 0.0, *about_axis(1, spin)) for spin in self.spin),
        ]

    # ------------------------------------------------------------------ markers
    def fast_values(self, outputs: Mapping[str, Any]) -> list[MarkerValues]:
        """The :attr:`fast_markers` of a state: tire forces, velocity, sideslip."""
        get = outputs.get
        zeros = (0.0,) * N_WHEELS
        fx, fy, fz = (_floats(get(key), zeros) for key in ("fx_n", "fy_n", "normal_load_n"))
        r = self.geometry.wheel_radius_m
        k = self._force_scale
        out = []
        for x, y, load in zip(fx, fy, fz):
            use = math.hypot(x, y) / (self.friction * load) if load > 0.0 else 0.0
            out.append(MarkerValues(friction_color(use), ((0.0, 0.0, -r),
                                                          (x * k, y * k, -r))))
        h = self.geometry.cg_height_m
        u, v = float(get("speed_mps", 0.0)), float(get("lateral_velocity_mps", 0.0))
        out.append(MarkerValues(self.fast_markers[N_WHEELS].color,
                                ((0.0, 0.0, h), (u * VELOCITY_ARROW_S, v * VELOCITY_ARROW_S, h))))
        beta = min(max(math.degrees(float(get("sideslip_rad", 0.0))), -SIDESLIP_SHOWN_DEG),
                   SIDESLIP_SHOWN_DEG)
        out.append(MarkerValues(self.fast_markers[-1].color, (), SIDESLIP_FORMAT.format(beta)))
        return out

    def slow_values(self, outputs: Mapping[str, Any]) -> list[MarkerValues]:
        """The :attr:`slow_markers` of a state: the driven path (advanced by this state) and
        the course."""
        line = self.trail.add(float(outputs.get("x_m", 0.0)), float(outputs.get("y_m", 0.0)))
        out = [MarkerValues(self.slow_markers[0].color, line)]
        course = self.course
        if course is not None:
            if course.cones:
                out.append(MarkerValues(self.slow_markers[1].color, course.cones))
                out.append(MarkerValues(self.slow_markers[2].color, course.edges))
            out.append(MarkerValues(self.slow_markers[-1].color, course.target))
        return out


__all__ = ["CONE_SPACING_M", "CarScene", "Course", "DYNAMIC_FRAMES", "FORCE_LENGTH_PER_LOAD",
           "Marker", "MarkerValues", "PATH_POINTS", "PathTrail", "SIDESLIP_FORMAT",
           "STATIC_FRAMES", "TARGET_POINTS", "VELOCITY_ARROW_S", "about_axis", "course_of",
           "friction_color"]
