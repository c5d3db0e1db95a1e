# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The one place that converts ROS messages <-> fourws core structures.

Core side: ``Simulator.outputs()`` mappings (keys = the fields of ``VehicleState.msg``),
:class:`fourws_sim.drivers.DriverCommand`, :class:`fourws_control.LawInput`. Message side: the
``fourws`` types and the standard ``nav_msgs/Odometry``, ``sensor_msgs/Imu``,
``rosgraph_msgs/Clock`` for RViz, Foxglove and PlotJuggler users.

Times: a simulation time ``t`` in s becomes a ``builtin_interfaces/Time`` rounded to the
nanosecond; ``VehicleState.sim_time_s`` carries the exact float so nodes that answer a state
(maneuver, controller) compute with the very number the simulator (and the offline runner)
used — lockstep runs are then bit-identical to :func:`fourws_run.closed_loop.run_closed_loop`.
"""

from __future__ import annotations

import json
import math
from typing import Any, Mapping

import numpy as np

from fourws_run.codecs import (IMU_FIELDS, ODOMETRY_FIELDS, check_finite_mapping, imu_values,
                               odometry_values, outputs_finite)
from fourws_run.interface import (FRAME_BODY, FRAME_ODOM, NS_PER_S, STATE_SCALARS, STATE_WHEELS,
                                  time_to_ns)
from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import NonFiniteError, ParameterError
from fourws_sim.params import load_vehicle, vehicle_from_mapping


# ---------------------------------------------------------------------------- parameters
def vehicle_from_params(node: Any, name_param: str = "vehicle",
                        json_param: str = "vehicle_json") -> Any:
    """The vehicle a node's parameters name: the mapping in ``json_param`` (the launcher's,
    a whole vehicle file as JSON) if not empty, else the file ``name_param`` names.

    Raises
    ------
    fourws_sim.errors.ParameterError
        Bad JSON or an invalid vehicle (names the parameter).
    """
    text = str(node.get_parameter(json_param).value)
    if not text:
        return load_vehicle(str(node.get_parameter(name_param).value))
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ParameterError(json_param, f"not JSON ({exc})") from None
    return vehicle_from_mapping(data, f"parameter {json_param}")


# ---------------------------------------------------------------------------- time
def set_stamp(stamp: Any, time_s: float) -> Any:
    """Fill a ``builtin_interfaces/Time`` with ``time_s`` (s, >= 0); returns it."""
    ns = time_to_ns(time_s)
    stamp.sec, stamp.nanosec = divmod(ns, NS_PER_S)
    return stamp


def stamp_to_s(stamp: Any) -> float:
    """``builtin_interfaces/Time`` -> s."""
    return stamp.sec + stamp.nanosec * 1e-9


def stamp_to_ns(stamp: Any) -> int:
    """``builtin_interfaces/Time`` -> integer ns."""
    return int(stamp.sec) * NS_PER_S + int(stamp.nanosec)


# ---------------------------------------------------------------------------- state
def state_msg(outputs: Mapping[str, Any], *, time_s: float, step: int, model: str,
              msg: Any = None) -> Any:
    """``VehicleState`` from ``Simulator.outputs()``.

    Fields missing from ``outputs`` stay zero (single-track models have no wheel data).

    Raises
    ------
    NonFiniteError
        If any value is NaN or infinite (nothing non-finite leaves a node).
    """
    # message classes (45 modules): nodes send raw CDR; only replay and tests build them
    from fourws.msg import VehicleState

    bad = outputs_finite(outputs)
    if bad:
        raise NonFiniteError(f"state field {bad} is not finite at t = {time_s} s")
    m = VehicleState() if msg is None else msg
    set_stamp(m.header.stamp, time_s)
    m.header.frame_id = FRAME_BODY
    m.step = int(step)
    m.sim_time_s = float(time_s)
    m.model = model
    for key in STATE_SCALARS:
        if key in outputs:
            setattr(m, key, float(outputs[key]))
    for key in STATE_WHEELS:
        if key in outputs:
            getattr(m, key)[:] = outputs[key]  # in place: no new array per message
    return m


def state_to_outputs(msg: Any) -> dict[str, Any]:
    """``VehicleState`` -> the ``Simulator.outputs()`` mapping (what maneuvers read)."""
    out: dict[str, Any] = {key: float(getattr(msg, key)) for key in STATE_SCALARS}
    for key in STATE_WHEELS:
        out[key] = np.array(getattr(msg, key), dtype=np.float64)
    out["sim_time_s"] = float(msg.sim_time_s)
    out["step"] = int(msg.step)
    return out


# ---------------------------------------------------------------------------- driver input
def driver_msg(cmd: Any, time_s: float, msg: Any = None) -> Any:
    """``DriverInput`` from a :class:`fourws_sim.drivers.DriverCommand` at ``time_s``."""
    # message classes (45 modules): nodes send raw CDR; only replay and tests build them
    from fourws.msg import DriverInput

    values = cmd.to_dict()
    if not math.isfinite(values["steering_wheel_angle_rad"] + values["front_wheel_angle_rad"]
                         + values["steering_torque_nm"] + sum(values["drive_torque_nm"])
                         + sum(values["brake_torque_nm"])):
        check_finite_mapping(values, "driver input")
    m = DriverInput() if msg is None else msg
    set_stamp(m.header.stamp, time_s)
    m.header.frame_id = FRAME_BODY
    m.steering_wheel_angle_rad = float(values["steering_wheel_angle_rad"])
    m.front_wheel_angle_rad = float(values["front_wheel_angle_rad"])
    m.steering_torque_nm = float(values["steering_torque_nm"])
    m.drive_torque_nm[:] = values["drive_torque_nm"]
    m.brake_torque_nm[:] = values["brake_torque_nm"]
    return m


def driver_command(msg: Any) -> Any:
    """``DriverInput`` -> :class:`fourws_sim.drivers.DriverCommand`.

    Raises
    ------
    NonFiniteError
        If a field is NaN or infinite (names the field).
    """
    cmd = DriverCommand(
        steering_wheel_angle_rad=float(msg.steering_wheel_angle_rad),
        front_wheel_angle_rad=float(msg.front_wheel_angle_rad),
        steering_torque_nm=float(msg.steering_torque_nm),
        drive_torque_nm=tuple(float(v) for v in msg.drive_torque_nm),
        brake_torque_nm=tuple(float(v) for v in msg.brake_torque_nm))
    if not math.isfinite(cmd.steering_wheel_angle_rad + cmd.front_wheel_angle_rad
                         + cmd.steering_torque_nm + sum(cmd.drive_torque_nm)
                         + sum(cmd.brake_torque_nm)):
        check_finite_mapping(cmd.to_dict(), "driver input")
    return cmd


# ---------------------------------------------------------------------------- rear steer
def rear_cmd_msg(angle_rad: float, rate_radps: float, law: str, state_stamp_ns: int,
                 state_step: int, msg: Any = None) -> Any:
    """``RearSteerCommand`` answering the state stamped ``state_stamp_ns`` (ns) with step
    ``state_step``."""
    # message classes (45 modules): nodes send raw CDR; only replay and tests build them
    from fourws.msg import RearSteerCommand

    if not (math.isfinite(angle_rad) and math.isfinite(rate_radps)):
        raise NonFiniteError(f"rear steer command of law {law} is not finite "
                             f"(angle {angle_rad!r}, rate {rate_radps!r})")
    m = RearSteerCommand() if msg is None else msg
    m.header.stamp.sec, m.header.stamp.nanosec = divmod(int(state_stamp_ns), NS_PER_S)
    m.header.frame_id = FRAME_BODY
    m.angle_rad = float(angle_rad)
    m.rate_radps = float(rate_radps)
    m.law = law
    m.state_stamp.sec, m.state_stamp.nanosec = divmod(int(state_stamp_ns), NS_PER_S)
    m.state_step = int(state_step)
    return m


# ---------------------------------------------------------------------------- standard msgs
class _StateFields:
    """A ``VehicleState`` read like an outputs mapping (``get``), for the value functions of
    :mod:`fourws_run.codecs`."""

    def __init__(self, state: Any) -> None:
        self._state = state

    def get(self, key: str) -> Any:
        return getattr(self._state, key, None)


def _set_fields(msg: Any, names: tuple[str, ...], values: tuple[float, ...]) -> None:
    """Set the dotted fields ``names`` of ``msg`` to ``values``."""
    for name, value in zip(names, values):
        *path, last = name.split(".")
        target = msg
        for part in path:
            target = getattr(target, part)
        setattr(target, last, value)


def odometry_msg(state: Any, msg: Any = None) -> Any:
    """``nav_msgs/Odometry`` of the body (``base_link``) in ``odom`` from a ``VehicleState``
    (the fields of :func:`fourws_run.codecs.odometry_values`)."""
    # message classes (45 modules): nodes send raw CDR; only replay and tests build them
    from nav_msgs.msg import Odometry

    m = Odometry() if msg is None else msg
    m.header.stamp = state.header.stamp
    m.header.frame_id = FRAME_ODOM
    m.child_frame_id = FRAME_BODY
    _set_fields(m, ODOMETRY_FIELDS, odometry_values(_StateFields(state)))
    return m


def imu_msg(state: Any, msg: Any = None) -> Any:
    """``sensor_msgs/Imu`` at the CG from a ``VehicleState`` (the fields of
    :func:`fourws_run.codecs.imu_values`)."""
    # message classes (45 modules): nodes send raw CDR; only replay and tests build them
    from sensor_msgs.msg import Imu

    m = Imu() if msg is None else msg
    m.header.stamp = state.header.stamp
    m.header.frame_id = FRAME_BODY
    _set_fields(m, IMU_FIELDS, imu_values(_StateFields(state)))
    return m


def clock_msg(time_s: float, msg: Any = None) -> Any:
    """``rosgraph_msgs/Clock`` at ``time_s``."""
    # message classes (45 modules): nodes send raw CDR; only replay and tests build them
    from rosgraph_msgs.msg import Clock

    m = Clock() if msg is None else msg
    set_stamp(m.clock, time_s)
    return m
