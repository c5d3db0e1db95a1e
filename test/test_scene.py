# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The car in 3D without a graph: the URDF of every shipped vehicle, the scene's transforms
and markers, and their encoders against rclpy's serialization.

Sources: the vehicle files (wheelbase a + b, tracks, wheel radius), ROS's own URDF parser
(urdf_parser_py), rclpy's deserializer, and hand computations written in the tests (a
quaternion's yaw, the spin angle of a wheel at constant speed).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from tf2_msgs.msg import TFMessage
from urdf_parser_py.urdf import URDF
from visualization_msgs.msg import MarkerArray

from fourws_run import cdr, interface
from fourws_run.scene import (DYNAMIC_FRAMES, PATH_POINTS, STATIC_FRAMES, CarScene, PathTrail,
                              friction_color)
from fourws_run.scene_codecs import MarkersEncoder, TransformsEncoder
from fourws_run.urdf import WHEEL_WIDTH_PER_RADIUS, CarGeometry, robot_description
from fourws_sim.maneuvers import make_maneuver
from fourws_sim.params import CONFIG_DIR, load_vehicle
from fourws_sim.simulator import Simulator

VEHICLES = sorted(p.stem for p in (Path(CONFIG_DIR) / "vehicles").glob("*.yaml"))


def yaw_of(q) -> float:
    """Yaw of a quaternion (x, y, z, w): atan2(2 (w z + x y), 1 - 2 (y^2 + z^2))."""
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


@pytest.mark.parametrize("name", VEHICLES)
def test_the_urdf_parses_and_carries_the_vehicle_files_geometry(name):
    vehicle = load_vehicle(name)
    robot = URDF.from_xml_string(robot_description(vehicle))
    joints = {j.name: j for j in robot.joints}
    fl, fr, rl, rr = (joints[f"{m}_joint"].origin.xyz for m in interface.FRAME_MOUNT)
    c = vehicle.chassis
    # wheelbase = a + b and the CG between the axles, from the vehicle file
    assert fl[0] - rl[0] == pytest.approx(c.cg_to_front_axle_m + c.cg_to_rear_axle_m, abs=1e-5)
    assert fl[0] == pytest.approx(c.cg_to_front_axle_m, abs=1e-5)
    geometry = CarGeometry.of(vehicle)
    if vehicle.body is not None:
        assert fl[1] - fr[1] == pytest.approx(vehicle.body.track_front_m, abs=1e-5)
        assert rl[1] - rr[1] == pytest.approx(vehicle.body.track_rear_m, abs=1e-5)
        assert fl[2] == pytest.approx(vehicle.body.wheel_radius_m, abs=1e-6)
        assert geometry.assumed == ("wheel_width_m",)
    else:
        # table_8_1's proportions: track 1.43 m of a 2.45 m wheelbase
        assert fl[1] - fr[1] == pytest.approx(1.43 / 2.45 * c.wheelbase_m, abs=1e-5)
        assert "track_front_m" in geometry.assumed
    links = {link.name: link for link in robot.links}
    assert set(links) == set(interface.FRAMES) - {interface.FRAME_ODOM}
    wheel = links[interface.FRAME_WHEEL[0]].visual.geometry
    assert wheel.radius == pytest.approx(geometry.wheel_radius_m, abs=1e-6)
    assert wheel.length == pytest.approx(WHEEL_WIDTH_PER_RADIUS * geometry.wheel_radius_m,
                                         abs=1e-6)


def test_f1tenth_is_drawn_at_its_scale():
    """The F1TENTH car: tracks 0.2645/0.2628 m and wheel radius 0.051 m of its file."""
    g = CarGeometry.of(load_vehicle("f1tenth"))
    assert (g.track_front_m, g.track_rear_m, g.wheel_radius_m) == (0.2645, 0.2628, 0.051)
    centre, size = g.body_box()
    # 2.5 wheel radii of overhang at each end: 0.3302 + 5 * 0.051 m long
    assert size[0] == pytest.approx(0.3302 + 5 * 0.051)
    # the box's centroid at the CG height 0.074 m
    assert centre[2] == pytest.approx(0.074)


def _state(vehicle):
    sim = Simulator(vehicle)
    sim.reset(speed_mps=20.0)
    return sim.outputs()


def test_transforms_follow_the_state():
    vehicle = load_vehicle("table_8_1")
    scene = CarScene(vehicle)
    out = dict(_state(vehicle))
    out.update(x_m=3.0, y_m=-1.5, heading_rad=0.4, roll_rad=0.05, front_wheel_angle_rad=0.03,
               rear_wheel_angle_rad=-0.01)
    tf = dict(zip(DYNAMIC_FRAMES, scene.transforms(out)))
    base = tf[(interface.FRAME_ODOM, interface.FRAME_BODY)]
    assert base[:3] == (3.0, -1.5, 0.0) and yaw_of(base[3:]) == pytest.approx(0.4, abs=1e-15)
    body = tf[(interface.FRAME_BODY, interface.FRAME_SPRUNG)]
    # roll about x by 0.05 rad: (sin 0.025, 0, 0, cos 0.025), at the 0.3048 m roll axis
    assert body == pytest.approx((0, 0, 0.3048, math.sin(0.025), 0, 0, math.cos(0.025)))
    for i, angle in enumerate((0.03, 0.03, -0.01, -0.01)):
        steer = tf[(interface.FRAME_MOUNT[i], interface.FRAME_STEER[i])]
        assert yaw_of(steer[3:]) == pytest.approx(angle, abs=1e-15)
    static = dict(zip(STATIC_FRAMES, scene.static_transforms()))
    assert static[(interface.FRAME_BODY, interface.FRAME_MOUNT[3])][:3] == (-1.45, -0.705, 0.29)


def test_the_wheel_spin_integrates_the_wheel_speeds():
    """Constant 80 rad/s for 0.01 s per state: 0.8 rad a state, wrapped into [-pi, pi)."""
    vehicle = load_vehicle("table_8_1")
    scene = CarScene(vehicle)
    out = dict(_state(vehicle))
    out["wheel_speed_radps"] = np.full(4, 80.0)
    for k in range(6):
        out["sim_time_s"] = 0.01 * k
        tf = scene.transforms(out)
    expected = (0.8 * 5 + math.pi) % (2 * math.pi) - math.pi
    assert scene.spin == pytest.approx([expected] * 4, abs=1e-12)
    q = tf[-1][3:]  # about y: (0, sin(theta/2), 0, cos(theta/2))
    assert q == pytest.approx((0.0, math.sin(expected / 2), 0.0, math.cos(expected / 2)))
    out["sim_time_s"] = 0.0  # a state at t = 0 (a reset): the wheels start again
    scene.transforms(out)
    assert scene.spin == [0.0] * 4


def test_the_encoders_write_what_rclpy_reads():
    """Our CDR bytes deserialize (rclpy) into the messages rclpy would have built; every
    byte but the alignment padding is rclpy's own serialization (rclpy leaves padding
    uninitialized, the encoders write zeros)."""
    vehicle = load_vehicle("table_8_1")
    scene = CarScene(vehicle, make_maneuver("double_lane_change", vehicle))
    out = _state(vehicle)
    stamp = 12_345_678_901
    raw = TransformsEncoder(DYNAMIC_FRAMES).encode(stamp, scene.transforms(out))
    msg = deserialize_message(raw, TFMessage)
    assert len(serialize_message(msg)) == len(raw)
    assert [(t.header.frame_id, t.child_frame_id) for t in msg.transforms] == list(DYNAMIC_FRAMES)
    assert msg.transforms[9].header.stamp.sec == 12 and msg.transforms[9].header.stamp.nanosec \
        == 345_678_901
    assert cdr.stamp_ns(raw, interface.TOPIC_TYPES[interface.TF]) == stamp
    for markers, values in ((scene.fast_markers, scene.fast_values(out)),
                            (scene.slow_markers, scene.slow_values(out))):
        raw = MarkersEncoder(markers).encode(stamp, values)
        msg = deserialize_message(raw, MarkerArray)
        assert len(serialize_message(msg)) == len(raw)
        assert cdr.stamp_ns(raw, interface.TOPIC_TYPES[interface.MARKERS]) == stamp
        for marker, spec, value in zip(msg.markers, markers, values):
            assert (marker.ns, marker.id, marker.header.frame_id) == (spec.ns, spec.id, spec.frame)
            assert marker.type == getattr(marker, spec.kind)
            assert [(p.x, p.y, p.z) for p in marker.points] == list(value.points)
            assert marker.text == value.text and marker.pose.orientation.w == 1.0
    names = {m.ns for m in scene.slow_markers}
    assert names == {"path", "cones", "corridor", "target_line"}


def test_an_empty_tf_message_has_no_stamp():
    raw = TransformsEncoder(()).encode(5, [])
    assert cdr.stamp_ns(raw, interface.TOPIC_TYPES[interface.TF]) is None


def test_the_tire_force_arrows_and_colours():
    """An arrow of fx, fy times the scale (half a wheelbase per static wheel load) from the
    contact patch; friction use sqrt(fx^2 + fy^2) / (mu Fz) = 0.5 is yellow."""
    vehicle = load_vehicle("table_8_1")
    scene = CarScene(vehicle)
    out = dict(_state(vehicle))
    out.update(fx_n=np.array([300.0, 0, 0, 0]), fy_n=np.array([-400.0, 0, 0, 0]),
               normal_load_n=np.array([1000.0, 1, 1, 1]))
    arrow = scene.fast_values(out)[0]
    k = 0.5 * 2.45 / (1298.857 * 9.80665 / 4)
    assert arrow.points == ((0.0, 0.0, -0.29), pytest.approx((300 * k, -400 * k, -0.29)))
    assert arrow.color == friction_color(0.5) == (1.0, 0.8, 0.0, 1.0)
    assert friction_color(2.0) == (1.0, 0.0, 0.0, 1.0)
    assert scene.fast_values(out)[-1].text == "beta  +0.00 deg"


def test_the_path_keeps_its_length_and_thins_itself():
    trail = PathTrail(8)
    for k in range(20):
        line = trail.add(float(k), 0.0)
    assert len(line) == 8 and line[-1] == (19.0, 0.0, 0.0)
    # full at 7 kept points twice: every 4th position is kept now
    assert trail.stride == 4 and [p[0] for p in trail.kept] == [0.0, 4.0, 8.0, 12.0, 16.0]
    assert PATH_POINTS == 256


def test_sequence_layouts_refuse_what_does_not_fit():
    with pytest.raises(cdr.CodecError, match="sequence"):
        cdr.layout(interface.TOPIC_TYPES[interface.TF])
    with pytest.raises(cdr.CodecError, match="no sequence fields"):
        cdr.layout(interface.TOPIC_TYPES[interface.TF], sequences={"points": 1})
    with pytest.raises(cdr.CodecError, match="text of its string fields"):
        cdr.layout(interface.TOPIC_TYPES[interface.TF], sequences={"transforms": 1})
