"""Fast decoding of the graph's hot-path messages from raw CDR bytes.

Lockstep runs are bounded by the per-tick cost of the answer chain simulator -> maneuver ->
controller -> simulator; rclpy's deserializer builds a full Python message with a numpy array
per wheel field for every state (about 50 us). These decoders read the fields straight from
the serialized bytes (raw subscriptions) with :mod:`struct`, in a few microseconds, and return
the same Python floats (a float64 is copied bit for bit, so lockstep runs stay identical to the
offline runner). ``test/test_ros_nodes.py`` checks them field by field against rclpy.

Layout (plain CDR, XCDR1): a 4-byte encapsulation header (byte 1 is 1 for little endian), then
the fields in order, each aligned to its size relative to the payload start; a string is a
uint32 length (including the terminating NUL) followed by its bytes.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

from fourws_ros.conversions import N_WHEELS, NS_PER_S, STATE_SCALARS, STATE_WHEELS

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
