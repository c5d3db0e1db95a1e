# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The graph's messages as CDR bytes: the encoders and decoders of the lockstep answer chain.

Lockstep runs are bounded by the per-tick cost of the answer chain simulator -> maneuver ->
controller -> simulator. rclpy's deserializer builds a full Python message with a numpy array
per wheel field for every state (about 50 us), and filling a Python message and serializing it
costs 10-30 us. The codecs here work on the serialized bytes instead (raw subscriptions, and
``Publisher.publish(bytes)``), with :mod:`struct` at offsets derived once from the message
definitions (:mod:`fourws_run.cdr`): a few microseconds per message, and the same Python floats
(a float64 is copied bit for bit, so lockstep runs stay identical to the offline runner).
A subscriber cannot tell the bytes from rclpy's (``test/test_codecs.py`` compares them byte
for byte, and the decoders field for field).

No layout is written here: a field's place comes from its ``.msg`` definition. What is written
here is fourws knowledge, once: which model output fills which field of ``VehicleState``
(the same name, :data:`fourws_run.interface.STATE_SCALARS`), of ``DriverInput`` (the fields of
:class:`fourws_sim.drivers.DriverCommand`, by name), of ``nav_msgs/Odometry`` and
``sensor_msgs/Imu`` (:func:`odometry_values`, :func:`imu_values`, also used by
:mod:`fourws_ros.conversions`).

Each encoder keeps one buffer with the message's fixed bytes (encapsulation, frame ids, model or
law name) and writes only the changing fields into it; an encoder is not shared between
threads.
"""

from __future__ import annotations

import dataclasses
import math
from functools import lru_cache, partial
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from fourws_run.cdr import CodecError, Decoder, Layout, layout
from fourws_run.interface import (CLOCK, DRIVER_INPUT, IMU, NS_PER_S, ODOM, REAR_STEER_CMD, STATE,
                                  STATE_SCALARS, STATE_WHEELS, TOPIC_TYPES, time_to_ns)
from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import NonFiniteError
from fourws_sim.params import GRAVITY_MPS2

STATE_TYPE = TOPIC_TYPES[STATE]
DRIVER_INPUT_TYPE = TOPIC_TYPES[DRIVER_INPUT]
REAR_STEER_COMMAND_TYPE = TOPIC_TYPES[REAR_STEER_CMD]
ODOMETRY_TYPE = TOPIC_TYPES[ODOM]
IMU_TYPE = TOPIC_TYPES[IMU]
CLOCK_TYPE = TOPIC_TYPES[CLOCK]

_HEADER_STAMP = ("header.stamp.sec", "header.stamp.nanosec")


# ============================================================================ values
def quaternion_from_euler(roll: float, pitch: float, yaw: float) -> tuple[float, ...]:
    """(x, y, z, w) of the rotation R = Rz(yaw) Ry(pitch) Rx(roll), angles in rad."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)


def _float(outputs: Any, key: str) -> float:
    """``float(outputs[key])``, 0 for a field the model does not have (as a message field)."""
    value = outputs.get(key)
    return 0.0 if value is None else float(value)


#: ``nav_msgs/Odometry`` fields set from a state, in the order of :func:`odometry_values`
#: (covariances and the rest stay zero).
ODOMETRY_FIELDS = (
    "pose.pose.position.x", "pose.pose.position.y", "pose.pose.position.z",
    "pose.pose.orientation.x", "pose.pose.orientation.y", "pose.pose.orientation.z",
    "pose.pose.orientation.w",
    "twist.twist.linear.x", "twist.twist.linear.y", "twist.twist.linear.z",
    "twist.twist.angular.x", "twist.twist.angular.y", "twist.twist.angular.z")


def odometry_values(outputs: Any) -> tuple[float, ...]:
    """The :data:`ODOMETRY_FIELDS` of the body (``base_link``) in ``odom`` for a state's
    outputs (a mapping with ``get``; missing fields are 0): position in m, orientation as a
    quaternion, body-frame velocities in m/s and rad/s.

    Roll enters the orientation (REP-103 roll about +x: positive roll lowers the right side,
    which is the fourws sign convention).
    """
    q = quaternion_from_euler(_float(outputs, "roll_rad"), 0.0,
                              _float(outputs, "heading_rad"))
    return (_float(outputs, "x_m"), _float(outputs, "y_m"), 0.0, *q,
            _float(outputs, "speed_mps"), _float(outputs, "lateral_velocity_mps"), 0.0,
            _float(outputs, "roll_rate_radps"), 0.0, _float(outputs, "yaw_rate_radps"))


#: ``sensor_msgs/Imu`` fields set from a state, in the order of :func:`imu_values`.
IMU_FIELDS = (
    "orientation.x", "orientation.y", "orientation.z", "orientation.w",
    "angular_velocity.x", "angular_velocity.y", "angular_velocity.z",
    "linear_acceleration.x", "linear_acceleration.y", "linear_acceleration.z")


def imu_values(outputs: Any) -> tuple[float, ...]:
    """The :data:`IMU_FIELDS` of an IMU at the CG for a state's outputs (missing fields 0).

    Linear acceleration is the specific force an IMU measures (REP-145): the body-frame
    accelerations plus gravity on +z (the small roll tilt of gravity is neglected), m/s^2.
    """
    q = quaternion_from_euler(_float(outputs, "roll_rad"), 0.0,
                              _float(outputs, "heading_rad"))
    return (*q, _float(outputs, "roll_rate_radps"), 0.0, _float(outputs, "yaw_rate_radps"),
            _float(outputs, "longitudinal_accel_mps2"), _float(outputs, "lateral_accel_mps2"),
            GRAVITY_MPS2)


def outputs_finite(outputs: Mapping[str, Any]) -> str:
    """Name of the first non-finite state output field, or ``""`` if all are finite."""
    # fast path: a sum is finite iff every term is (barring overflow, which is reported too)
    total = 0.0
    for key in STATE_SCALARS:
        if key in outputs:
            total += float(outputs[key])
    for key in STATE_WHEELS:
        if key in outputs:
            value = outputs[key]
            total += float(value.sum() if isinstance(value, np.ndarray) else sum(value))
    if math.isfinite(total):
        return ""
    for key in STATE_SCALARS:
        if key in outputs and not math.isfinite(float(outputs[key])):
            return key
    for key in STATE_WHEELS:
        if key in outputs and not np.all(np.isfinite(np.asarray(outputs[key], float))):
            return key
    return ""


def check_finite_mapping(values: Mapping[str, Any], what: str) -> None:
    """Raise :class:`NonFiniteError` naming the first non-finite field of ``values``."""
    for key, value in values.items():
        if isinstance(value, str):
            continue
        if not np.all(np.isfinite(np.asarray(value, dtype=np.float64))):
            raise NonFiniteError(f"{what}: field {key} is not finite ({value!r})")


@lru_cache(maxsize=None)
def driver_input_fields() -> tuple[str, ...]:
    """The ``DriverInput`` fields after its header, in message order: each is the
    :class:`~fourws_sim.drivers.DriverCommand` field of the same name.

    Raises
    ------
    CodecError
        The message has a field ``DriverCommand`` lacks, or lacks one it has.
    """
    lay = layout(DRIVER_INPUT_TYPE, {"header.frame_id": ""})
    names = tuple(s.name for s in lay.slots if not s.name.startswith("header."))
    command = tuple(f.name for f in dataclasses.fields(DriverCommand))
    if sorted(names) != sorted(command):
        raise CodecError(f"{DRIVER_INPUT_TYPE} fields {list(names)} are not the DriverCommand "
                         f"fields {list(command)}")
    return names


# ============================================================================ decoders
# Made at import, with the typestore: a node pays for deriving the layouts while it starts,
# not inside its first answer of a run (loading the typestore takes a few hundred ms).
_STATE_DECODER = Decoder(STATE_TYPE, numpy_arrays=True)
_DRIVER_DECODER = Decoder(DRIVER_INPUT_TYPE)
_REAR_DECODER = Decoder(REAR_STEER_COMMAND_TYPE)
_DRIVER_FIELDS = driver_input_fields()


def parse_state(data: bytes | memoryview) -> dict[str, Any]:
    """A serialized ``VehicleState`` as the ``Simulator.outputs()`` mapping plus its envelope.

    Keys: ``stamp_ns`` (int, the header stamp), ``step`` (int), ``sim_time_s`` (float),
    ``model`` (str), every name of :data:`~fourws_run.interface.STATE_SCALARS` (float) and of
    ``STATE_WHEELS`` (read-only float64 arrays of 4, views of ``data``).

    Raises
    ------
    CodecError
        Not a ``VehicleState`` (too short for its layout, not plain CDR).
    """
    out = _STATE_DECODER.decode(data)
    out["stamp_ns"] = out.pop("header.stamp.sec") * NS_PER_S + out.pop("header.stamp.nanosec")
    del out["header.frame_id"]
    return out


def parse_driver_input(data: bytes | memoryview) -> tuple[int, DriverCommand]:
    """``(header stamp in ns, DriverCommand)`` of a serialized ``DriverInput``.

    Raises
    ------
    CodecError
        Not a ``DriverInput``.
    """
    out = _DRIVER_DECODER.decode(data)
    return (out["header.stamp.sec"] * NS_PER_S + out["header.stamp.nanosec"],
            DriverCommand(**{name: out[name] for name in _DRIVER_FIELDS}))


def parse_rear_steer_command(data: bytes | memoryview) -> dict[str, Any]:
    """Fields of a serialized ``RearSteerCommand``: ``angle_rad``, ``rate_radps`` (float),
    ``law`` (str), ``state_stamp_ns``, ``state_step`` (int).

    Raises
    ------
    CodecError
        Not a ``RearSteerCommand``.
    """
    out = _REAR_DECODER.decode(data)
    return {"angle_rad": out["angle_rad"], "rate_radps": out["rate_radps"], "law": out["law"],
            "state_stamp_ns": out["state_stamp.sec"] * NS_PER_S + out["state_stamp.nanosec"],
            "state_step": out["state_step"]}


# ============================================================================ encoders
def field_packer(buf: bytearray, lay: Layout, names: Sequence[str]) -> Callable[..., None]:
    """``pack(*values)`` writing the fields ``names`` (wire order) of ``lay`` into ``buf``
    (also the encoders of :mod:`fourws_run.scene_codecs`)."""
    runs = lay.runs(names)
    if len(runs) == 1:  # the usual case: adjacent fields, one struct call
        offset, fmt, _, _ = runs[0]
        return partial(fmt.pack_into, buf, offset)

    writes = tuple((partial(fmt.pack_into, buf, offset), first, stop)
                   for offset, fmt, first, stop in runs)

    def pack(*values: Any) -> None:
        for write, first, stop in writes:
            write(*values[first:stop])

    return pack


class StateEncoder:
    """Serializes ``VehicleState`` from a ``Simulator.outputs()`` mapping: each field of
    :data:`~fourws_run.interface.STATE_SCALARS` and ``STATE_WHEELS`` from the output of the
    same name (0 where the model has none).

    Parameters
    ----------
    model : str
        ``VehicleState.model`` (fixed for an encoder).
    frame_id : str
        ``header.frame_id``.
    """

    def __init__(self, model: str, frame_id: str) -> None:
        lay = layout(STATE_TYPE, {"header.frame_id": frame_id, "model": model})
        self._buf = buf = lay.template()
        self._stamp = field_packer(buf, lay, _HEADER_STAMP)
        self._step_time = field_packer(buf, lay, ("step", "sim_time_s"))
        # the outputs go straight into float64 views of the buffer (numpy copies a wheel
        # array in one call); one view per run of adjacent fields
        wanted = set(STATE_SCALARS) | set(STATE_WHEELS)
        names = [s.name for s in lay.slots if s.name in wanted]
        self._views: list[np.ndarray] = []
        self._scalars: list[tuple[np.ndarray, int, str]] = []
        self._wheels: list[tuple[np.ndarray, int, int, str]] = []
        for offset, fmt, first, stop in lay.runs(names):
            view = np.frombuffer(buf, dtype="<f8", count=stop - first, offset=offset)
            if fmt.size != view.nbytes:
                raise CodecError(f"{STATE_TYPE}: outputs {names[first:stop]} are not adjacent "
                                 "float64 fields")
            self._views.append(view)
            for name in names:
                slot = lay.slot(name)
                if not offset <= slot.offset < offset + fmt.size:
                    continue
                at = (slot.offset - offset) // 8
                if slot.count:
                    self._wheels.append((view, at, at + slot.count, name))
                else:
                    self._scalars.append((view, at, name))

    def encode(self, outputs: Any, time_s: float, step: int) -> bytes:
        """CDR bytes of the state ``outputs`` at ``time_s`` (s; stamp rounded to the ns) and
        integration step ``step``. Fields missing from ``outputs`` are zero.

        Raises
        ------
        NonFiniteError
            If a value is NaN or infinite (names the field), as ``conversions.state_msg``.
        """
        get = outputs.get
        for view, at, key in self._scalars:
            value = get(key)
            view[at] = 0.0 if value is None else value
        for view, first, stop, key in self._wheels:
            value = get(key)
            view[first:stop] = 0.0 if value is None else value
        for view in self._views:
            if not math.isfinite(view.sum()):
                bad = outputs_finite(outputs)
                if bad:
                    raise NonFiniteError(f"state field {bad} is not finite at t = {time_s} s")
        self._stamp(*divmod(time_to_ns(time_s), NS_PER_S))
        self._step_time(int(step), float(time_s))
        return bytes(self._buf)


class DriverInputEncoder:
    """Serializes ``DriverInput`` from a :class:`fourws_sim.drivers.DriverCommand` (each field
    from the command's field of the same name, :func:`driver_input_fields`).

    Parameters
    ----------
    frame_id : str
        ``header.frame_id``.
    """

    def __init__(self, frame_id: str) -> None:
        lay = layout(DRIVER_INPUT_TYPE, {"header.frame_id": frame_id})
        self._buf = lay.template()
        self._stamp = field_packer(self._buf, lay, _HEADER_STAMP)
        names = driver_input_fields()
        self._fields = tuple((name, lay.slot(name).count) for name in names)
        self._values = field_packer(self._buf, lay, names)

    def encode(self, cmd: DriverCommand, time_s: float) -> bytes:
        """CDR bytes of driver command ``cmd`` stamped ``time_s`` (s, rounded to the ns).

        Raises
        ------
        NonFiniteError
            If a field is NaN or infinite (names the field), as ``conversions.driver_msg``.
        CodecError
            A per-wheel field without one value per element of the message's array.
        """
        values: list[Any] = []
        for name, count in self._fields:
            value = getattr(cmd, name)
            if count:
                if len(value) != count:
                    raise CodecError(f"driver input: {name} needs {count} values, got "
                                     f"{len(value)}")
                values.extend(value)
            else:
                values.append(value)
        if not math.isfinite(sum(values)):
            check_finite_mapping(cmd.to_dict(), "driver input")
        self._stamp(*divmod(time_to_ns(time_s), NS_PER_S))
        self._values(*values)
        return bytes(self._buf)


class RearSteerCommandEncoder:
    """Serializes ``RearSteerCommand``; one buffer per law name, made on first use.

    Parameters
    ----------
    frame_id : str
        ``header.frame_id``.
    """

    def __init__(self, frame_id: str) -> None:
        self._frame_id = frame_id
        self._buffers: dict[str, tuple[bytearray, Callable[..., None], Callable[..., None],
                                       Callable[..., None]]] = {}

    def _buffer(self, law: str) -> tuple[bytearray, Callable[..., None], Callable[..., None],
                                         Callable[..., None]]:
        lay = layout(REAR_STEER_COMMAND_TYPE, {"header.frame_id": self._frame_id, "law": law})
        buf = lay.template()
        entry = (buf, field_packer(buf, lay, _HEADER_STAMP),
                 field_packer(buf, lay, ("angle_rad", "rate_radps")),
                 field_packer(buf, lay, ("state_stamp.sec", "state_stamp.nanosec", "state_step")))
        self._buffers[law] = entry
        return entry

    def encode(self, angle_rad: float, rate_radps: float, law: str, state_stamp_ns: int,
               state_step: int) -> bytes:
        """CDR bytes of the command of ``law`` answering the state stamped ``state_stamp_ns``
        (ns; also the header stamp) with step ``state_step``: angle in rad, rate in rad/s.

        Raises
        ------
        NonFiniteError
            If the angle or the rate is NaN or infinite, as ``conversions.rear_cmd_msg``.
        """
        if not (math.isfinite(angle_rad) and math.isfinite(rate_radps)):
            raise NonFiniteError(f"rear steer command of law {law} is not finite "
                                 f"(angle {angle_rad!r}, rate {rate_radps!r})")
        entry = self._buffers.get(law)
        buf, stamp, angle_rate, answers = entry if entry is not None else self._buffer(law)
        sec, nanosec = divmod(int(state_stamp_ns), NS_PER_S)
        stamp(sec, nanosec)
        angle_rate(float(angle_rad), float(rate_radps))
        answers(sec, nanosec, int(state_step))
        return bytes(buf)


class ClockEncoder:
    """Serializes ``rosgraph_msgs/Clock``; immutable, so one encoder serves every thread."""

    def __init__(self) -> None:
        lay = layout(CLOCK_TYPE)
        runs = lay.runs(("clock.sec", "clock.nanosec"))
        if len(runs) != 1:
            raise CodecError(f"{CLOCK_TYPE}: clock.sec and clock.nanosec are not adjacent")
        offset, fmt, _, _ = runs[0]
        template = bytes(lay.template())
        self._head, self._tail = template[:offset], template[offset + fmt.size:]
        self._pack = fmt.pack

    def encode(self, time_s: float) -> bytes:
        """CDR bytes of the clock at ``time_s`` (s, rounded to the ns)."""
        out = self._head + self._pack(*divmod(time_to_ns(time_s), NS_PER_S))
        return out + self._tail if self._tail else out


_CLOCK_ENCODER = ClockEncoder()


def encode_clock(time_s: float) -> bytes:
    """CDR bytes of a ``rosgraph_msgs/Clock`` at ``time_s`` (s, rounded to the ns)."""
    return _CLOCK_ENCODER.encode(time_s)


class OdometryEncoder:
    """Serializes ``nav_msgs/Odometry`` (:func:`odometry_values`) straight from a state's
    outputs mapping (covariances zero).

    Parameters
    ----------
    frame_id, child_frame_id : str
        Earth-fixed and body frames.
    """

    def __init__(self, frame_id: str, child_frame_id: str) -> None:
        lay = layout(ODOMETRY_TYPE, {"header.frame_id": frame_id,
                                     "child_frame_id": child_frame_id})
        self._buf = lay.template()
        self._stamp = field_packer(self._buf, lay, _HEADER_STAMP)
        self._values = field_packer(self._buf, lay, ODOMETRY_FIELDS)

    def encode(self, outputs: Any, stamp_ns: int) -> bytes:
        """CDR bytes of the odometry of ``outputs`` stamped ``stamp_ns`` (ns, the state's
        header stamp)."""
        self._stamp(*divmod(int(stamp_ns), NS_PER_S))
        self._values(*odometry_values(outputs))
        return bytes(self._buf)


class ImuEncoder:
    """Serializes ``sensor_msgs/Imu`` (:func:`imu_values`) straight from a state's outputs
    mapping (covariances zero).

    Parameters
    ----------
    frame_id : str
        Body frame.
    """

    def __init__(self, frame_id: str) -> None:
        lay = layout(IMU_TYPE, {"header.frame_id": frame_id})
        self._buf = lay.template()
        self._stamp = field_packer(self._buf, lay, _HEADER_STAMP)
        self._values = field_packer(self._buf, lay, IMU_FIELDS)

    def encode(self, outputs: Any, stamp_ns: int) -> bytes:
        """CDR bytes of the IMU reading of ``outputs`` stamped ``stamp_ns`` (ns)."""
        self._stamp(*divmod(int(stamp_ns), NS_PER_S))
        self._values(*imu_values(outputs))
        return bytes(self._buf)


__all__ = ["CLOCK_TYPE", "ClockEncoder", "CodecError", "DRIVER_INPUT_TYPE", "DriverInputEncoder",
           "IMU_FIELDS", "IMU_TYPE", "ImuEncoder", "ODOMETRY_FIELDS", "ODOMETRY_TYPE",
           "OdometryEncoder", "REAR_STEER_COMMAND_TYPE", "RearSteerCommandEncoder",
           "STATE_TYPE", "StateEncoder", "check_finite_mapping", "driver_input_fields",
           "encode_clock", "field_packer", "imu_values", "odometry_values", "outputs_finite",
           "parse_driver_input", "parse_rear_steer_command", "parse_state",
           "quaternion_from_euler"]
