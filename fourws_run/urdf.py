# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The simulated car as a robot description (URDF), from its vehicle file, without ROS.

:class:`CarGeometry` is what RViz and Foxglove need to draw the car: wheelbase and CG position
(``chassis``), track per axle, wheel radius and CG height (``body``), the roll-axis height
under the CG (``body`` roll centres), and a box for the body. :func:`robot_description` writes
it as URDF, published latched on ``/robot_description`` by the simulator; its links are the
frames of :data:`fourws_run.interface.FRAMES` that :mod:`fourws_run.scene` moves on ``/tf``.

Frames (REP-103 axes, REP-105 names): ``base_link`` lies on the road under the CG and turns
with the heading only (for a ground vehicle the frame parallel to the road, which
``/fourws/odom`` places); the sprung mass is the link ``body``, a revolute joint about x on
the roll axis (at its height under the CG), so the box rolls as the model's sprung mass
does while the wheels, which do not roll with it, hang off ``base_link``: a fixed mount at
each wheel centre, a revolute steer joint about z (the applied road-wheel angle, front and
rear) and a continuous wheel joint about y (the spin angle). Chosen over rolling
``base_link`` itself (``/fourws/odom``'s orientation includes the roll) because the wheels
would then roll with the body and sink into or lift off the road; ``odom -> base_link ->
body`` has exactly the orientation of ``/fourws/odom``.

What the vehicle file does not give is assumed, and :attr:`CarGeometry.assumed` names it:
no vehicle file has a wheel width (0.7 x the wheel radius, the ratio of a 205 mm passenger-car
tire of 0.29 m radius); a vehicle without ``body`` (the 2-DOF data sets) takes track, wheel
radius, CG and roll-centre height in the proportions of ``table_8_1`` (the paper's 8-DOF car)
to its wheelbase. The box: from 2.5 wheel radii behind the rear axle to 2.5 ahead of the
front axle, as wide as the wider track plus a wheel width, from half a wheel radius above the
road to the height that puts its centroid at the CG height.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from html import escape  # quotes too (the name is an attribute); light: no urllib

from fourws_run.interface import (FRAME_BODY, FRAME_MOUNT, FRAME_SPRUNG, FRAME_STEER,
                                  FRAME_WHEEL, WHEELS)
from fourws_sim.params import Vehicle, load_vehicle

#: Wheel width as a share of the wheel radius (no vehicle file has a width).
WHEEL_WIDTH_PER_RADIUS = 0.7
#: Body overhang ahead of the front and behind the rear axle, in wheel radii.
OVERHANG_PER_RADIUS = 2.5
#: Height of the body box's floor above the road, in wheel radii.
FLOOR_PER_RADIUS = 0.5
#: The vehicle whose proportions a vehicle without ``body`` data takes.
PROPORTIONS_OF = "table_8_1"
#: Steer joint range in the URDF, rad (beyond any road-wheel angle the simulator accepts).
STEER_LIMIT_RAD = math.radians(60.0)
#: Roll joint range in the URDF, rad (the model stops being valid at 30 deg: fourws_sim.outcome).
ROLL_LIMIT_RAD = math.radians(45.0)


@dataclass(frozen=True)
class CarGeometry:
    """The drawn car, m, in ``base_link`` (on the road under the CG, x forward, y left).

    Attributes
    ----------
    name : str
        The vehicle's name.
    cg_to_front_axle_m, cg_to_rear_axle_m : float
        a and b.
    track_front_m, track_rear_m : float
        Wheel-centre distance across each axle.
    wheel_radius_m, wheel_width_m : float
        The wheels (a cylinder each).
    cg_height_m : float
        Total-mass CG above the road.
    roll_axis_height_m : float
        The roll axis above the road under the CG (the roll centres interpolated at the CG).
    assumed : tuple of str
        The values that do not come from the vehicle file (module docstring).
    """

    name: str
    cg_to_front_axle_m: float
    cg_to_rear_axle_m: float
    track_front_m: float
    track_rear_m: float
    wheel_radius_m: float
    wheel_width_m: float
    cg_height_m: float
    roll_axis_height_m: float
    assumed: tuple[str, ...] = ()

    @property
    def wheelbase_m(self) -> float:
        """a + b, m."""
        return self.cg_to_front_axle_m + self.cg_to_rear_axle_m

    @classmethod
    def of(cls, vehicle: Vehicle) -> "CarGeometry":
        """The geometry of ``vehicle`` (assumed values named in :attr:`assumed`)."""
        c = vehicle.chassis
        a, b = c.cg_to_front_axle_m, c.cg_to_rear_axle_m
        assumed = ["wheel_width_m"]
        body = vehicle.body
        if body is None:
            body = _proportional_body(a + b)
            assumed += ["track_front_m", "track_rear_m", "wheel_radius_m", "cg_height_m",
                        "roll_axis_height_m"]
        h_f, h_r = body.roll_centre_height_front_m, body.roll_centre_height_rear_m
        return cls(vehicle.name, a, b, body.track_front_m, body.track_rear_m,
                   body.wheel_radius_m, WHEEL_WIDTH_PER_RADIUS * body.wheel_radius_m,
                   body.cg_height_m, h_f + (h_r - h_f) * a / (a + b), tuple(assumed))

    def wheel_centres(self) -> tuple[tuple[float, float, float], ...]:
        """Each wheel's centre (x, y, z) in ``base_link``, :data:`WHEELS` order, m."""
        a, b, r = self.cg_to_front_axle_m, self.cg_to_rear_axle_m, self.wheel_radius_m
        tf, tr = self.track_front_m / 2, self.track_rear_m / 2
        return ((a, tf, r), (a, -tf, r), (-b, tr, r), (-b, -tr, r))

    def body_box(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """(centre in ``base_link``, size (length, width, height)) of the body box, m."""
        r = self.wheel_radius_m
        front = self.cg_to_front_axle_m + OVERHANG_PER_RADIUS * r
        rear = -self.cg_to_rear_axle_m - OVERHANG_PER_RADIUS * r
        floor = FLOOR_PER_RADIUS * r
        top = max(2.0 * self.cg_height_m - floor, floor + r)
        width = max(self.track_front_m, self.track_rear_m) + self.wheel_width_m
        return (((front + rear) / 2, 0.0, (floor + top) / 2),
                (front - rear, width, top - floor))


@functools.lru_cache(maxsize=1)
def _proportions() -> tuple[float, ...]:
    """(track front, track rear, wheel radius, CG height, roll centre front, rear) of
    :data:`PROPORTIONS_OF` per metre of its wheelbase."""
    ref = load_vehicle(PROPORTIONS_OF)
    body = ref.body
    assert body is not None
    wheelbase = ref.chassis.wheelbase_m
    return tuple(v / wheelbase for v in (body.track_front_m, body.track_rear_m,
                                         body.wheel_radius_m, body.cg_height_m,
                                         body.roll_centre_height_front_m,
                                         body.roll_centre_height_rear_m))


@dataclass(frozen=True)
class _Body:
    track_front_m: float
    track_rear_m: float
    wheel_radius_m: float
    cg_height_m: float
    roll_centre_height_front_m: float
    roll_centre_height_rear_m: float


def _proportional_body(wheelbase_m: float) -> _Body:
    return _Body(*(p * wheelbase_m for p in _proportions()))


def _xyz(values: tuple[float, float, float]) -> str:
    return " ".join(f"{v:.6g}" for v in values)


def robot_description(vehicle: Vehicle) -> str:
    """The URDF of ``vehicle`` (module docstring): links named as the frames of
    :mod:`fourws_run.interface`, a box body and four cylinder wheels."""
    g = CarGeometry.of(vehicle)
    (cx, cy, cz), (length, width, height) = g.body_box()
    h = g.roll_axis_height_m
    note = (f" Assumed (not in the vehicle file): {', '.join(g.assumed)}; see "
            "fourws_run/urdf.py." if g.assumed else "")
    lines = [
        '<?xml version="1.0"?>',
        f"<!-- fourws: the vehicle '{escape(g.name)}' drawn from its vehicle file; frames move "
        f"on /tf from the simulator.{note} -->",
        f'<robot name="{escape(g.name)}">',
        '  <material name="body"><color rgba="0.15 0.35 0.75 0.6"/></material>',
        '  <material name="tire"><color rgba="0.1 0.1 0.1 1"/></material>',
        f'  <link name="{FRAME_BODY}"/>',
        f'  <link name="{FRAME_SPRUNG}">',
        f'    <visual><origin xyz="{_xyz((cx, cy, cz - h))}" rpy="0 0 0"/>',
        f'      <geometry><box size="{_xyz((length, width, height))}"/></geometry>',
        '      <material name="body"/></visual>',
        '  </link>',
        f'  <joint name="{FRAME_SPRUNG}_roll" type="revolute">',
        f'    <parent link="{FRAME_BODY}"/><child link="{FRAME_SPRUNG}"/>',
        f'    <origin xyz="0 0 {h:.6g}" rpy="0 0 0"/><axis xyz="1 0 0"/>',
        f'    <limit lower="{-ROLL_LIMIT_RAD:.6g}" upper="{ROLL_LIMIT_RAD:.6g}" effort="0" '
        'velocity="0"/>',
        '  </joint>',
    ]
    for i, centre in enumerate(g.wheel_centres()):
        mount, steer, wheel = FRAME_MOUNT[i], FRAME_STEER[i], FRAME_WHEEL[i]
        lines += [
            f'  <link name="{mount}"/>',
            f'  <link name="{steer}"/>',
            f'  <link name="{wheel}">',
            f'    <visual><origin xyz="0 0 0" rpy="{math.pi / 2:.6g} 0 0"/>',
            f'      <geometry><cylinder radius="{g.wheel_radius_m:.6g}" '
            f'length="{g.wheel_width_m:.6g}"/></geometry>',
            '      <material name="tire"/></visual>',
            '  </link>',
            f'  <joint name="{mount}_joint" type="fixed">',
            f'    <parent link="{FRAME_BODY}"/><child link="{mount}"/>',
            f'    <origin xyz="{_xyz(centre)}" rpy="0 0 0"/>',
            '  </joint>',
            f'  <joint name="{steer}_joint" type="revolute">',
            f'    <parent link="{mount}"/><child link="{steer}"/>',
            '    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>',
            f'    <limit lower="{-STEER_LIMIT_RAD:.6g}" upper="{STEER_LIMIT_RAD:.6g}" '
            'effort="0" velocity="0"/>',
            '  </joint>',
            f'  <joint name="{wheel}_joint" type="continuous">',
            f'    <parent link="{steer}"/><child link="{wheel}"/>',
            '    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>',
            '  </joint>',
        ]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


assert len(WHEELS) == len(FRAME_MOUNT)

__all__ = ["CarGeometry", "FLOOR_PER_RADIUS", "OVERHANG_PER_RADIUS", "PROPORTIONS_OF",
           "WHEEL_WIDTH_PER_RADIUS", "robot_description"]
