# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Fast decoding and encoding of the graph's hot-path messages as raw CDR bytes.

Lockstep runs are bounded by the per-tick cost of the answer chain simulator -> maneuver ->
controller -> simulator; rclpy's deserializer builds a full Python message with a numpy array
per wheel field for every state (about 50 us). These decoders read the fields straight from
the serialized bytes (raw subscriptions) with :mod:`struct`, in a few microseconds, and return
the same Python floats (a float64 is copied bit for bit, so lockstep runs stay identical to the
offline runner). ``test/test_ros_nodes.py`` checks them field by field against rclpy.

The encoders go the other way for what the answer chain publishes (state, driver input,
rear-steer command) and for the simulator's clock, odometry and IMU: each keeps one buffer
with the message's fixed bytes (encapsulation, frame ids, model or law name) and writes only
the changing fields into it with :mod:`struct` — about 1-7 us per message instead of 10-30 us
for filling a Python message and converting it. The bytes go out through the publishers' raw
path (``Publisher.publish(bytes)``); a subscriber cannot tell them from rclpy's.

Layout (plain CDR, XCDR1): a 4-byte encapsulation header (byte 1 is 1 for little endian), then
the fields in order, each aligned to its size relative to the payload start; a string is a
uint32 length (including the terminating NUL) followed by its bytes.
"""

from __future__ import annotations

import math
import struct
from typing import Any

import numpy as np

from fourws_ros.conversions import (NS_PER_S, STATE_SCALARS, STATE_WHEELS,
                                    _quaternion_from_euler, check_finite_mapping,
                                    outputs_finite, time_to_ns)
from fourws_run.interface import N_WHEELS
from fourws_sim.errors import NonFiniteError
from fourws_sim.params import GRAVITY_MPS2

_ENCAPSULATION = 4
_LITTLE = 1


class CdrError(ValueError):
    """The bytes are not a message of the expected layout."""


def _fmt(data: bytes | memoryview) -> str:
    if len(data) < _ENCAPSULATION:
        raise CdrError("shorter than the CDR encapsulation header")
    return "<" if data[1] == _LITTLE else ">"


def _align(pos: int, size: int) -> int:
    rel = pos - _ENCAPSULATION
    return pos + (-rel) % size


def _string_end(data: bytes | memoryview, pos: int, e: str) -> tuple[int, bytes]:
    pos = _align(pos, 4)
    (length,) = struct.unpack_from(e + "I", data, pos)
    start = pos + 4
    if start + length > len(data):
        raise CdrError("string runs past the end of the message")
    return start + length, bytes(data[start:start + max(length - 1, 0)])


def _header(data: bytes | memoryview, e: str) -> tuple[int, int]:
    """(stamp ns, position after frame_id)."""
    sec, nanosec = struct.unpack_from(e + "iI", data, _ENCAPSULATION)
    pos, _ = _string_end(data, _ENCAPSULATION + 8, e)
    return sec * NS_PER_S + nanosec, pos


_N_SCALARS = len(STATE_SCALARS)
_N_WHEEL_VALUES = len(STATE_WHEELS) * N_WHEELS


def parse_state(data: bytes | memoryview) -> dict[str, Any]:
    """A ``VehicleState`` as the ``Simulator.outputs()`` mapping plus ``stamp_ns``.

    Keys: ``stamp_ns`` (int), ``step`` (int), ``sim_time_s``, every name of
    :data:`~fourws_ros.conversions.STATE_SCALARS` (float) and of ``STATE_WHEELS`` (float64
    arrays of 4), ``model`` (str).

    Raises
    ------
    CdrError
        If the bytes are too short for the layout.
    """
    try:
        e = _fmt(data)
        stamp, pos = _header(data, e)
        pos = _align(pos, 8)
        step, sim_time = struct.unpack_from(e + "Qd", data, pos)
        pos, model = _string_end(data, pos + 16, e)
        pos = _align(pos, 8)
        scalars = struct.unpack_from(e + "%dd" % _N_SCALARS, data, pos)
        pos += 8 * _N_SCALARS
        wheels = np.frombuffer(data, dtype=e + "f8", count=_N_WHEEL_VALUES,
                               offset=pos).reshape(len(STATE_WHEELS), N_WHEELS)
    except (struct.error, ValueError) as exc:
        raise CdrError(f"not a VehicleState: {exc}") from None
    out: dict[str, Any] = dict(zip(STATE_SCALARS, scalars))
    for k, key in enumerate(STATE_WHEELS):
        out[key] = wheels[k]
    out["stamp_ns"] = stamp
    out["step"] = step
    out["sim_time_s"] = sim_time
    out["model"] = model.decode("utf-8", errors="replace")
    return out


def parse_driver_input(data: bytes | memoryview) -> tuple[int, Any]:
    """``(stamp ns, DriverCommand)`` of a serialized ``DriverInput``.

    Raises
    ------
    CdrError
        Wrong layout.
    """
    from fourws_sim.drivers import DriverCommand

    try:
        e = _fmt(data)
        stamp, pos = _header(data, e)
        pos = _align(pos, 8)
        v = struct.unpack_from(e + "11d", data, pos)
    except (struct.error, ValueError) as exc:
        raise CdrError(f"not a DriverInput: {exc}") from None
    return stamp, DriverCommand(steering_wheel_angle_rad=v[0], front_wheel_angle_rad=v[1],
                                steering_torque_nm=v[2], drive_torque_nm=v[3:7],
                                brake_torque_nm=v[7:11])


def parse_rear_steer_command(data: bytes | memoryview) -> dict[str, Any]:
    """Fields of a serialized ``RearSteerCommand``: ``angle_rad``, ``rate_radps``, ``law``,
    ``state_stamp_ns``, ``state_step``.

    Raises
    ------
    CdrError
        Wrong layout.
    """
    try:
        e = _fmt(data)
        _, pos = _header(data, e)
        pos = _align(pos, 8)
        angle, rate = struct.unpack_from(e + "dd", data, pos)
        pos, law = _string_end(data, pos + 16, e)
        pos = _align(pos, 4)
        sec, nanosec = struct.unpack_from(e + "iI", data, pos)
        pos = _align(pos + 8, 8)
        (step,) = struct.unpack_from(e + "Q", data, pos)
    except (struct.error, ValueError) as exc:
        raise CdrError(f"not a RearSteerCommand: {exc}") from None
    return {"angle_rad": angle, "rate_radps": rate, "law": law.decode("utf-8", "replace"),
            "state_stamp_ns": sec * NS_PER_S + nanosec, "state_step": step}


# ============================================================================ encoders
# The answer chain's messages serialized straight into a preallocated buffer: the same bytes
# rclpy's serializer produces (``test/test_ros_nodes.py`` compares them byte for byte), without
# building a Python message and converting it to C first (about 30 us per state).
_LE_HEADER = b"\x00\x01\x00\x00"  # plain CDR, little endian, no options
_STAMP = struct.Struct("<iI")
_STEP_TIME = struct.Struct("<Qd")
_DRIVER_VALUES = struct.Struct("<11d")
_ANGLE_RATE = struct.Struct("<dd")
_STEP = struct.Struct("<Q")


def _cdr_string(pos: int, text: str) -> tuple[int, bytes]:
    """(position after, bytes) of a CDR string written at ``pos`` (payload-relative
    alignment): padding to 4, uint32 length with the NUL, the bytes, the NUL."""
    raw = text.encode("utf-8") + b"\x00"
    pad = _align(pos, 4) - pos
    return pos + pad + 4 + len(raw), b"\x00" * pad + struct.pack("<I", len(raw)) + raw


def _header_template(frame_id: str) -> bytearray:
    """Encapsulation header + ``std_msgs/Header`` with a zero stamp and ``frame_id``."""
    _, frame = _cdr_string(_ENCAPSULATION + _STAMP.size, frame_id)
    return bytearray(_LE_HEADER + b"\x00" * _STAMP.size + frame)


def _pad_to(buf: bytearray, size: int) -> None:
    buf.extend(b"\x00" * (_align(len(buf), size) - len(buf)))


def _split_ns(stamp_ns: int) -> tuple[int, int]:
    return divmod(stamp_ns, NS_PER_S)


class StateEncoder:
    """Serializes ``VehicleState`` from a ``Simulator.outputs()`` mapping (the fields
    :func:`fourws_ros.conversions.state_msg` fills, in the same way).

    Parameters
    ----------
    model : str
        ``VehicleState.model`` (fixed for an encoder).
    frame_id : str
        ``header.frame_id``.
    """

    def __init__(self, model: str, frame_id: str) -> None:
        buf = _header_template(frame_id)
        _pad_to(buf, 8)
        self._step_at = len(buf)
        buf.extend(b"\x00" * 16)  # step, sim_time_s
        _, model_bytes = _cdr_string(len(buf), model)
        buf.extend(model_bytes)
        _pad_to(buf, 8)
        self._buf = buf
        n = _N_SCALARS + _N_WHEEL_VALUES
        values_at = len(buf)
        buf.extend(b"\x00" * (8 * n))
        self._values = np.frombuffer(buf, dtype="<f8", count=n, offset=values_at)
        self._wheels = self._values[_N_SCALARS:].reshape(len(STATE_WHEELS), N_WHEELS)

    def encode(self, outputs: Any, time_s: float, step: int) -> bytes:
        """CDR bytes of the state ``outputs`` at ``time_s`` (s; stamp rounded to the ns) and
        integration step ``step``. Fields missing from ``outputs`` are zero.

        Raises
        ------
        NonFiniteError
            If a value is NaN or infinite (names the field), as ``conversions.state_msg``.
        """
        values = self._values
        get = outputs.get
        for k, key in enumerate(STATE_SCALARS):
            value = get(key)
            values[k] = 0.0 if value is None else value
        wheels = self._wheels
        for k, key in enumerate(STATE_WHEELS):
            value = get(key)
            wheels[k] = 0.0 if value is None else value
        if not math.isfinite(values.sum()):
            bad = outputs_finite(outputs)
            if bad:
                raise NonFiniteError(f"state field {bad} is not finite at t = {time_s} s")
        buf = self._buf
        _STAMP.pack_into(buf, _ENCAPSULATION, *_split_ns(time_to_ns(time_s)))
        _STEP_TIME.pack_into(buf, self._step_at, int(step), float(time_s))
        return bytes(buf)


class DriverInputEncoder:
    """Serializes ``DriverInput`` from a :class:`fourws_sim.drivers.DriverCommand` (the fields
    :func:`fourws_ros.conversions.driver_msg` fills).

    Parameters
    ----------
    frame_id : str
        ``header.frame_id``.
    """

    def __init__(self, frame_id: str) -> None:
        buf = _header_template(frame_id)
        _pad_to(buf, 8)
        self._values_at = len(buf)
        buf.extend(b"\x00" * _DRIVER_VALUES.size)
        self._buf = buf

    def encode(self, cmd: Any, time_s: float) -> bytes:
        """CDR bytes of driver command ``cmd`` stamped ``time_s`` (s, rounded to the ns).

        Raises
        ------
        NonFiniteError
            If a field is NaN or infinite (names the field), as ``conversions.driver_msg``.
        """
        drive, brake = cmd.drive_torque_nm, cmd.brake_torque_nm
        values = (cmd.steering_wheel_angle_rad, cmd.front_wheel_angle_rad,
                  cmd.steering_torque_nm, *drive, *brake)
        if len(drive) != N_WHEELS or len(brake) != N_WHEELS:
            raise CdrError(f"drive and brake torques need {N_WHEELS} values each")
        if not math.isfinite(sum(values)):
            check_finite_mapping(cmd.to_dict(), "driver input")
        buf = self._buf
        _STAMP.pack_into(buf, _ENCAPSULATION, *_split_ns(time_to_ns(time_s)))
        _DRIVER_VALUES.pack_into(buf, self._values_at, *values)
        return bytes(buf)


class RearSteerCommandEncoder:
    """Serializes ``RearSteerCommand`` (the fields :func:`fourws_ros.conversions.rear_cmd_msg`
    fills); one buffer per law name, made on first use.

    Parameters
    ----------
    frame_id : str
        ``header.frame_id``.
    """

    def __init__(self, frame_id: str) -> None:
        self._frame_id = frame_id
        self._layouts: dict[str, tuple[bytearray, int, int, int]] = {}

    def _layout(self, law: str) -> tuple[bytearray, int, int, int]:
        buf = _header_template(self._frame_id)
        _pad_to(buf, 8)
        values_at = len(buf)
        buf.extend(b"\x00" * _ANGLE_RATE.size)
        _, law_bytes = _cdr_string(len(buf), law)
        buf.extend(law_bytes)
        _pad_to(buf, 4)
        stamp_at = len(buf)
        buf.extend(b"\x00" * _STAMP.size)
        _pad_to(buf, 8)
        step_at = len(buf)
        buf.extend(b"\x00" * _STEP.size)
        layout = (buf, values_at, stamp_at, step_at)
        self._layouts[law] = layout
        return layout

    def encode(self, angle_rad: float, rate_radps: float, law: str, state_stamp_ns: int,
               state_step: int) -> bytes:
        """CDR bytes of the command answering the state stamped ``state_stamp_ns`` (ns; also
        the header stamp) with step ``state_step``.

        Raises
        ------
        NonFiniteError
            If the angle or the rate is NaN or infinite, as ``conversions.rear_cmd_msg``.
        """
        if not (math.isfinite(angle_rad) and math.isfinite(rate_radps)):
            raise NonFiniteError(f"rear steer command of law {law} is not finite "
                                 f"(angle {angle_rad!r}, rate {rate_radps!r})")
        layout = self._layouts.get(law)
        buf, values_at, stamp_at, step_at = layout if layout is not None else self._layout(law)
        sec, nanosec = _split_ns(int(state_stamp_ns))
        _STAMP.pack_into(buf, _ENCAPSULATION, sec, nanosec)
        _ANGLE_RATE.pack_into(buf, values_at, float(angle_rad), float(rate_radps))
        _STAMP.pack_into(buf, stamp_at, sec, nanosec)
        _STEP.pack_into(buf, step_at, int(state_step))
        return bytes(buf)


def encode_clock(time_s: float) -> bytes:
    """CDR bytes of a ``rosgraph_msgs/Clock`` at ``time_s`` (s, rounded to the ns)."""
    return _LE_HEADER + _STAMP.pack(*_split_ns(time_to_ns(time_s)))


def _float(outputs: Any, key: str) -> float:
    """``float(outputs[key])``, 0 for a field the model does not have (as a message field)."""
    value = outputs.get(key)
    return 0.0 if value is None else float(value)


_POSE = struct.Struct("<7d")  # position x, y, z; orientation x, y, z, w
_VECTOR3 = struct.Struct("<3d")
_QUATERNION = struct.Struct("<4d")
#: Doubles of a PoseWithCovariance before its twist: 7 pose values and 36 covariances.
_POSE_WITH_COVARIANCE = 7 + 36
#: Doubles of a TwistWithCovariance: 6 twist values and 36 covariances.
_TWIST_WITH_COVARIANCE = 6 + 36
#: Doubles of a Quaternion plus its 3x3 covariance, and of a Vector3 plus its covariance.
_QUATERNION_WITH_COVARIANCE = 4 + 9
_VECTOR3_WITH_COVARIANCE = 3 + 9


class OdometryEncoder:
    """Serializes the ``nav_msgs/Odometry`` :func:`fourws_ros.conversions.odometry_msg` makes of
    a state, straight from the state's outputs mapping (covariances zero).

    Parameters
    ----------
    frame_id, child_frame_id : str
        Earth-fixed and body frames.
    """

    def __init__(self, frame_id: str, child_frame_id: str) -> None:
        buf = _header_template(frame_id)
        _, child = _cdr_string(len(buf), child_frame_id)
        buf.extend(child)
        _pad_to(buf, 8)
        self._pose_at = len(buf)
        self._twist_at = self._pose_at + 8 * _POSE_WITH_COVARIANCE
        buf.extend(b"\x00" * (8 * (_POSE_WITH_COVARIANCE + _TWIST_WITH_COVARIANCE)))
        self._buf = buf

    def encode(self, outputs: Any, stamp_ns: int) -> bytes:
        """CDR bytes of the odometry of ``outputs`` (a state's outputs mapping) stamped
        ``stamp_ns`` (ns, the state's header stamp)."""
        buf = self._buf
        heading = _float(outputs, "heading_rad")
        q = _quaternion_from_euler(_float(outputs, "roll_rad"), 0.0, heading)
        _STAMP.pack_into(buf, _ENCAPSULATION, *_split_ns(stamp_ns))
        _POSE.pack_into(buf, self._pose_at, _float(outputs, "x_m"), _float(outputs, "y_m"),
                        0.0, *q)
        _VECTOR3.pack_into(buf, self._twist_at, _float(outputs, "speed_mps"),
                           _float(outputs, "lateral_velocity_mps"), 0.0)
        _VECTOR3.pack_into(buf, self._twist_at + _VECTOR3.size,
                           _float(outputs, "roll_rate_radps"), 0.0,
                           _float(outputs, "yaw_rate_radps"))
        return bytes(buf)


class ImuEncoder:
    """Serializes the ``sensor_msgs/Imu`` :func:`fourws_ros.conversions.imu_msg` makes of a
    state, straight from the state's outputs mapping (covariances zero).

    Parameters
    ----------
    frame_id : str
        Body frame.
    """

    def __init__(self, frame_id: str) -> None:
        buf = _header_template(frame_id)
        _pad_to(buf, 8)
        self._orientation_at = len(buf)
        self._angular_at = self._orientation_at + 8 * _QUATERNION_WITH_COVARIANCE
        self._linear_at = self._angular_at + 8 * _VECTOR3_WITH_COVARIANCE
        buf.extend(b"\x00" * (self._linear_at + 8 * _VECTOR3_WITH_COVARIANCE - len(buf)))
        self._buf = buf

    def encode(self, outputs: Any, stamp_ns: int) -> bytes:
        """CDR bytes of the IMU reading of ``outputs`` stamped ``stamp_ns`` (ns)."""
        buf = self._buf
        q = _quaternion_from_euler(_float(outputs, "roll_rad"), 0.0,
                                   _float(outputs, "heading_rad"))
        _STAMP.pack_into(buf, _ENCAPSULATION, *_split_ns(stamp_ns))
        _QUATERNION.pack_into(buf, self._orientation_at, *q)
        _VECTOR3.pack_into(buf, self._angular_at, _float(outputs, "roll_rate_radps"), 0.0,
                           _float(outputs, "yaw_rate_radps"))
        _VECTOR3.pack_into(buf, self._linear_at, _float(outputs, "longitudinal_accel_mps2"),
                           _float(outputs, "lateral_accel_mps2"), GRAVITY_MPS2)
        return bytes(buf)
