# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Message codecs derived from the definitions (fourws_run/cdr.py, fourws_run/codecs.py).

References: rclpy's serializer (``rclpy.serialization``, the bytes the graph really sends) and
rosbags' independent CDR serializer; the CDR (XCDR1) alignment rule for hand-computed offsets.
rclpy leaves alignment padding uninitialized, so bytes are compared with rclpy everywhere but
in the padding (plus equal length and an exact rclpy round trip), and with rosbags (which
zeroes padding) byte for byte.
"""

from __future__ import annotations

import importlib
import math
import string

import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from fourws_ros import conversions, topics
from fourws_run import cdr, codecs, interface
from fourws_run.bagfile import typestore
from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import NonFiniteError

#: Every type the hot path encodes or decodes, and the standard ones the simulator sends.
FIXED_TOPICS = (topics.STATE, topics.DRIVER_INPUT, topics.REAR_STEER_CMD, topics.ODOM,
                topics.IMU, topics.CLOCK)


# ----------------------------------------------------------------------------- helpers
def _rclpy_class(type_name: str):
    """rclpy message class of ``pkg/Name`` or ``pkg/msg/Name``."""
    package, *_, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


_INTS = {"int32": (-2**31, 2**31), "uint32": (0, 2**32), "int64": (-2**63, 2**63),
         "uint64": (0, 2**64), "uint8": (0, 256), "octet": (0, 256), "int8": (-128, 128),
         "int16": (-2**15, 2**15), "uint16": (0, 2**16)}


def _random_text(rng: np.random.Generator) -> str:
    """0-11 characters, some of them two-byte UTF-8: every alignment after a string."""
    alphabet = string.ascii_letters + "_é"
    return "".join(rng.choice(list(alphabet), size=int(rng.integers(0, 12))))


def _fill(msg, rng: np.random.Generator, prefix: str = "") -> dict:
    """Fill every field of an rclpy message with random values; return them by dotted path
    (rclpy's own field list, independent of fourws' layouts)."""
    leaves: dict = {}
    for name, kind in msg.get_fields_and_field_types().items():
        path = f"{prefix}{name}"
        if kind.startswith("sequence<"):
            raise AssertionError(f"{path}: sequences have no fixed layout")
        if "[" in kind:
            base, count = kind[:-1].split("[")
            assert base == "double", kind
            value = rng.normal(size=int(count)) * 100.0
            setattr(msg, name, value)
            leaves[path] = tuple(float(v) for v in value)
        elif "/" in kind:
            leaves.update(_fill(getattr(msg, name), rng, f"{path}."))
        elif kind == "string":
            leaves[path] = _random_text(rng)
            setattr(msg, name, leaves[path])
        elif kind == "double":
            leaves[path] = float(rng.normal() * 100.0)
            setattr(msg, name, leaves[path])
        elif kind == "boolean":
            leaves[path] = bool(rng.integers(0, 2))
            setattr(msg, name, leaves[path])
        else:
            low, high = _INTS[kind]
            leaves[path] = int(rng.integers(low, high, dtype=np.int64 if low < 0 else np.uint64))
            setattr(msg, name, leaves[path])
    return leaves


def _same_as_rclpy(raw: bytes, msg) -> bool:
    """``raw`` is ``msg`` as rclpy serializes it: same length, rclpy reads it back as ``msg``,
    and every byte that is not alignment padding is equal."""
    reference = serialize_message(msg)
    if len(raw) != len(reference) or deserialize_message(raw, type(msg)) != msg:
        return False
    msgtype = topics.TOPIC_TYPES[next(t for t in topics.TOPIC_TYPES
                                      if topics.message_class(t) is type(msg))]
    lay = cdr.Decoder(msgtype).layout_of(raw)
    covered = np.zeros(len(raw), dtype=bool)
    covered[:cdr.ENCAPSULATION_BYTES] = True
    for slot in lay.slots:
        covered[slot.offset:slot.end] = True
    gaps = np.flatnonzero(~covered)
    # padding only ever aligns to at most 8 bytes; ours is zero
    assert gaps.size < 8 * len(lay.slots)
    assert all(raw[i] == 0 for i in gaps)
    a, b = np.frombuffer(raw, np.uint8), np.frombuffer(reference, np.uint8)
    return bool(np.array_equal(a[covered], b[covered]))


def _outputs(rng: np.random.Generator, wheels: bool = True) -> dict:
    out = {k: float(rng.normal() * 100.0) for k in interface.STATE_SCALARS}
    if wheels:
        out.update({k: rng.normal(size=4) * 1e3 for k in interface.STATE_WHEELS})
    return out


# ----------------------------------------------------------------------------- generic decoder
@pytest.mark.parametrize("topic", FIXED_TOPICS)
def test_decoder_equals_rclpy_field_for_field(topic: str) -> None:
    """Random messages (random string lengths shift every later offset) decode to exactly the
    values rclpy serialized, every field of rclpy's field list and no other."""
    rng = np.random.default_rng(FIXED_TOPICS.index(topic))
    msgtype = topics.TOPIC_TYPES[topic]
    as_tuples = cdr.Decoder(msgtype)
    as_arrays = cdr.Decoder(msgtype, numpy_arrays=True)
    for _ in range(25):
        msg = topics.message_class(topic)()
        leaves = _fill(msg, rng)
        raw = serialize_message(msg)
        decoded = as_tuples.decode(raw)
        assert decoded == leaves  # bit-identical floats, exact ints and strings
        arrays = as_arrays.decode(raw)
        assert set(arrays) == set(leaves)
        for key, value in leaves.items():
            if isinstance(value, tuple):
                np.testing.assert_array_equal(arrays[key], value)
        # rosbags' deserializer reads the same bytes the same way
        ref = typestore().deserialize_cdr(raw, msgtype)
        for key, value in leaves.items():
            obj = ref
            for part in key.split("."):
                obj = getattr(obj, part)
            assert (tuple(obj) if isinstance(obj, np.ndarray) else obj) == value


def test_decoder_refuses_what_is_not_the_message() -> None:
    """Bytes that are not the type end in a CodecError naming the type, never a wrong
    number; a type with a sequence has no fixed layout (named)."""
    msgtype = topics.TOPIC_TYPES[topics.STATE]
    dec = cdr.Decoder(msgtype, numpy_arrays=True)
    msg = topics.message_class(topics.STATE)(model="8dof")
    raw = serialize_message(msg)
    assert dec.decode(raw)["model"] == "8dof"
    for bad, reason in ((raw[:-1], "not a fourws/msg/VehicleState"),
                        (raw[:3], "VehicleState"),
                        (b"\x00\x03" + raw[2:], "not plain CDR"),
                        (raw[:12] + b"\x00\x00\x00\xf0" + raw[16:], "runs past the end"),
                        (raw[:12] + b"\xff\x00\x00\x00" + raw[16:], "380 bytes.* has 628"),
                        (raw + bytes(4), "384 bytes"),
                        (b"\x00\x01\x00\x00\x01", "VehicleState")):
        with pytest.raises(cdr.CodecError, match=reason):
            dec.decode(bad)
    assert dec.decode(raw + bytes(3))["model"] == "8dof"  # padding to a multiple of 4
    with pytest.raises(cdr.CodecError, match="overrun_times_s.*sequence"):
        cdr.Decoder(topics.TOPIC_TYPES[topics.SIM_STATUS])
    with pytest.raises(cdr.CodecError, match="unknown message type"):
        cdr.layout("fourws/msg/Nothing")
    with pytest.raises(cdr.CodecError, match="header.frame_id"):
        cdr.layout(msgtype, {"model": "8dof"})  # a string without text
    with pytest.raises(cdr.CodecError, match="no string fields.*frame"):
        cdr.layout(msgtype, {"header.frame_id": "", "model": "", "frame": ""})


def test_big_endian_messages_decode_too() -> None:
    """A big-endian CDR message (encapsulation 0x0000; rosbags writes one) decodes to the
    same values."""
    msgtype = topics.TOPIC_TYPES[topics.REAR_STEER_CMD]
    store = typestore()
    msg = store.types[msgtype](
        header=store.types["std_msgs/msg/Header"](
            stamp=store.types["builtin_interfaces/msg/Time"](sec=-5, nanosec=123),
            frame_id="base_link"),
        angle_rad=-0.0125, rate_radps=0.5, law="rwc2_3dof",
        state_stamp=store.types["builtin_interfaces/msg/Time"](sec=7, nanosec=9),
        state_step=2**61 + 3)
    little = bytes(store.serialize_cdr(msg, msgtype))
    big = bytes(store.serialize_cdr(msg, msgtype, little_endian=False))
    assert big[1] == 0 and little[1] == 1
    dec = cdr.Decoder(msgtype)
    assert dec.decode(big) == dec.decode(little) == {
        "header.stamp.sec": -5, "header.stamp.nanosec": 123, "header.frame_id": "base_link",
        "angle_rad": -0.0125, "rate_radps": 0.5, "law": "rwc2_3dof", "state_stamp.sec": 7,
        "state_stamp.nanosec": 9, "state_step": 2**61 + 3}
    assert cdr.stamp_ns(big, msgtype) == cdr.stamp_ns(little, msgtype) == -5 * 10**9 + 123


# ----------------------------------------------------------------------------- layouts
_SYNTHETIC = {
    # the same fields in two orders: only the definition differs
    "test_msgs/msg/A": "uint8 flag\nfloat64 value\nstring name\nint32 count\nfloat64[2] pair\n",
    "test_msgs/msg/B": "float64 value\nuint8 flag\nint32 count\nstring name\nfloat64[2] pair\n",
}


def _synthetic_store():
    store = get_typestore(Stores.EMPTY)
    for name, text in _SYNTHETIC.items():
        store.register(get_types_from_msg(text, name))
    return store


def test_layout_follows_the_definition_order() -> None:
    """Reordering fields in a definition moves them: offsets from the CDR rule by hand (each
    primitive aligned to its size relative to the payload, which starts at byte 4; a string is
    a uint32 length then its bytes with a NUL), and the codecs built on each layout agree
    byte for byte with rosbags' serializer."""
    store = _synthetic_store()
    a = cdr.layout("test_msgs/msg/A", {"name": "ab"}, store)
    b = cdr.layout("test_msgs/msg/B", {"name": "ab"}, store)
    # A: flag payload 0; value 1 -> 8; name 16 (+4+3 = 23); count 23 -> 24; pair 28 -> 32
    assert [(s.name, s.offset) for s in a.slots] == [
        ("flag", 4), ("value", 12), ("name", 20), ("count", 28), ("pair", 36)]
    assert a.size == 4 + 32 + 16
    # B: value 0; flag 8; count 9 -> 12; name 16 (+7 = 23); pair 23 -> 24
    assert [(s.name, s.offset) for s in b.slots] == [
        ("value", 4), ("flag", 12), ("count", 16), ("name", 20), ("pair", 28)]
    assert b.size == 4 + 24 + 16
    values = {"flag": 200, "value": -1.25, "count": -7, "pair": (0.5, 3.0)}
    for lay in (a, b):
        buf = lay.template()
        flat = {"flag": (200,), "value": (-1.25,), "count": (-7,), "pair": (0.5, 3.0)}
        numeric = [s.name for s in lay.slots if s.type != "string"]
        for offset, fmt, _, _ in lay.runs(numeric):
            names = [s.name for s in lay.slots if offset <= s.offset < offset + fmt.size]
            fmt.pack_into(buf, offset, *[v for n in names for v in flat[n]])
        cls = store.types[lay.msgtype]
        msg = cls(flag=200, value=-1.25, name="ab", count=-7, pair=np.array([0.5, 3.0]))
        reference = bytes(store.serialize_cdr(msg, lay.msgtype))
        assert bytes(buf) == reference
        decoded = cdr.Decoder(lay.msgtype, store=store).decode(reference)
        assert decoded == {**values, "name": "ab"}
    # the runs of adjacent fields follow the order too: A's numbers are split by the string
    assert len(a.runs(["flag", "value"])) == 1 and len(a.runs(["value", "count"])) == 2
    with pytest.raises(cdr.CodecError, match="wire order"):
        a.runs(["value", "flag"])


def test_state_fields_come_from_the_definition(tmp_path) -> None:
    """STATE_SCALARS and STATE_WHEELS are VehicleState's fields outside its envelope, in the
    order and with the types rclpy generated from the same .msg; a field the simulator cannot
    fill is an error naming the field and the file."""
    fields = topics.message_class(topics.STATE).get_fields_and_field_types()
    assert list(fields)[:len(interface.STATE_ENVELOPE)] == list(interface.STATE_ENVELOPE)
    outputs = [name for name in fields if name not in interface.STATE_ENVELOPE]
    assert outputs == [*interface.STATE_SCALARS, *interface.STATE_WHEELS]
    assert {fields[n] for n in interface.STATE_SCALARS} == {"double"}
    assert {fields[n] for n in interface.STATE_WHEELS} == {f"double[{interface.N_WHEELS}]"}
    text = (interface.MSG_DIR / "VehicleState.msg").read_text()
    moved = tmp_path / "VehicleState.msg"
    moved.write_text(text.replace("float64 x_m\n", "") + "float64 x_m\nfloat64[4] camber_rad\n")
    scalars, wheels = interface.state_output_fields(moved)
    assert scalars == (*interface.STATE_SCALARS[1:], "x_m")
    assert wheels == (*interface.STATE_WHEELS, "camber_rad")
    moved.write_text(text + "uint8 gear\n")
    with pytest.raises(interface.MessageDefinitionError, match="VehicleState.msg.*'gear'"):
        interface.state_output_fields(moved)


def test_driver_input_carries_the_driver_command() -> None:
    """Every DriverInput field after the header is the DriverCommand field of that name."""
    fields = list(topics.message_class(topics.DRIVER_INPUT).get_fields_and_field_types())
    assert list(codecs.driver_input_fields()) == fields[1:]
    assert set(codecs.driver_input_fields()) == set(DriverCommand.__dataclass_fields__)


# ----------------------------------------------------------------------------- hot path
def test_parsers_equal_rclpy():
    """parse_state / parse_driver_input / parse_rear_steer_command give the values of the
    message rclpy serialized, bit for bit, as the types the nodes use."""
    rng = np.random.default_rng(7)
    outputs = _outputs(rng)
    for model in ("8dof", "2dof-lagged"):  # string lengths shift every later offset
        msg = conversions.state_msg(outputs, time_s=12.3456789, step=12345, model=model)
        msg.header.frame_id = "base_link_x"
        parsed = codecs.parse_state(serialize_message(msg))
        assert set(parsed) == {*interface.STATE_SCALARS, *interface.STATE_WHEELS, "stamp_ns",
                               "step", "sim_time_s", "model"}
        assert parsed["step"] == 12345 and parsed["sim_time_s"] == 12.3456789
        assert parsed["stamp_ns"] == conversions.stamp_to_ns(msg.header.stamp)
        assert parsed["model"] == model
        for key in interface.STATE_SCALARS:
            assert type(parsed[key]) is float and parsed[key] == outputs[key]  # bit-identical
        for key in interface.STATE_WHEELS:
            assert parsed[key].dtype == np.float64
            np.testing.assert_array_equal(parsed[key], outputs[key])
    cmd = DriverCommand(0.3, 0.02, 1.5, (1.0, 2.0, 3.0, 4.0), (0.0, 0.5, 0.25, 0.125))
    stamp, back = codecs.parse_driver_input(serialize_message(conversions.driver_msg(cmd, 7.25)))
    assert back == cmd and stamp == 7_250_000_000
    assert all(type(v) is float for v in back.drive_torque_nm + back.brake_torque_nm)
    state = conversions.state_msg(outputs, time_s=3.0, step=3000, model="8dof")
    for law in ("sol1", "rwc2_3dof"):
        raw = serialize_message(conversions.rear_cmd_msg(
            -0.0123, 0.5, law, conversions.stamp_to_ns(state.header.stamp), state.step))
        back = codecs.parse_rear_steer_command(raw)
        assert back == {"angle_rad": -0.0123, "rate_radps": 0.5, "law": law,
                        "state_stamp_ns": 3_000_000_000, "state_step": 3000}
    with pytest.raises(codecs.CodecError):
        codecs.parse_state(b"\x00\x01\x00\x00\x01")
    # CDR does not name its type: another message is refused by its size
    with pytest.raises(codecs.CodecError, match="not a fourws/msg/DriverInput"):
        codecs.parse_driver_input(serialize_message(state))


def test_encoders_equal_rclpy():
    """The encoders' bytes are rclpy's serialization of the message the conversions build
    (every byte but rclpy's uninitialized padding; same length; rclpy reads them back as that
    message) and rosbags' serialization byte for byte."""
    rng = np.random.default_rng(11)
    odom = codecs.OdometryEncoder(topics.FRAME_ODOM, topics.FRAME_BODY)
    imu = codecs.ImuEncoder(topics.FRAME_BODY)
    store = typestore()
    for model in ("8dof", "2dof", "3dof-lagged"):  # string lengths shift every later offset
        encoder = codecs.StateEncoder(model, topics.FRAME_BODY)
        for _ in range(20):
            outputs = _outputs(rng, wheels=model == "8dof")  # single-track: wheels stay zero
            t, step = float(rng.uniform(0.0, 1e3)), int(rng.integers(0, 2**50))
            msg = conversions.state_msg(outputs, time_s=t, step=step, model=model)
            raw = encoder.encode(outputs, t, step)
            assert _same_as_rclpy(raw, msg)
            msgtype = topics.TOPIC_TYPES[topics.STATE]
            assert bytes(store.serialize_cdr(store.deserialize_cdr(raw, msgtype),
                                             msgtype)) == raw
            stamp = conversions.stamp_to_ns(msg.header.stamp)
            assert _same_as_rclpy(odom.encode(outputs, stamp), conversions.odometry_msg(msg))
            assert _same_as_rclpy(imu.encode(outputs, stamp), conversions.imu_msg(msg))
            assert _same_as_rclpy(codecs.encode_clock(t), conversions.clock_msg(t))
    driver = codecs.DriverInputEncoder(topics.FRAME_BODY)
    rear = codecs.RearSteerCommandEncoder(topics.FRAME_BODY)
    for _ in range(50):
        v = [float(x) for x in rng.normal(size=11)]
        cmd = DriverCommand(v[0], v[1], v[2], tuple(v[3:7]), tuple(v[7:11]))
        t = float(rng.uniform(0.0, 1e3))
        assert _same_as_rclpy(driver.encode(cmd, t), conversions.driver_msg(cmd, t))
        for law in ("sol1", "fws", "rwc2_3dof", "x"):  # each alignment of the later fields
            stamp, step = int(rng.integers(0, 2**40)), int(rng.integers(0, 2**50))
            assert _same_as_rclpy(rear.encode(v[0], v[1], law, stamp, step),
                                  conversions.rear_cmd_msg(v[0], v[1], law, stamp, step))
    # a changed value is seen by the comparison (the check above can fail)
    changed = conversions.state_msg(outputs, time_s=t, step=step, model="8dof")
    changed.fy_n[3] += 1.0
    assert not _same_as_rclpy(
        codecs.StateEncoder("8dof", topics.FRAME_BODY).encode(outputs, t, step), changed)
    # nothing non-finite leaves a node, as with the message conversions
    with pytest.raises(NonFiniteError, match="yaw_rate_radps"):
        codecs.StateEncoder("8dof", topics.FRAME_BODY).encode(
            {**outputs, "yaw_rate_radps": math.nan}, 1.0, 1)
    with pytest.raises(NonFiniteError, match="front_wheel_angle_rad"):
        driver.encode(DriverCommand(0.0, math.inf), 1.0)
    with pytest.raises(NonFiniteError):
        rear.encode(math.nan, 0.0, "sol1", 0, 0)
    with pytest.raises(codecs.CodecError, match="drive_torque_nm needs 4"):
        driver.encode(DriverCommand(0.0, 0.0, 0.0, (1.0, 2.0)), 1.0)


def test_odometry_and_imu_fields_of_a_state():
    """REP-103/145 meaning of the standard messages, field by field: position and heading
    (yaw q = (0, 0, sin(psi/2), cos(psi/2)) with no roll), body velocities, specific force
    with gravity on +z (g = 9.80665 m/s^2)."""
    outputs = {"x_m": 3.0, "y_m": -2.0, "heading_rad": 0.5, "roll_rad": 0.0,
               "speed_mps": 20.0, "lateral_velocity_mps": 0.25, "roll_rate_radps": 0.125,
               "yaw_rate_radps": -0.375, "longitudinal_accel_mps2": 1.5,
               "lateral_accel_mps2": -4.0}
    odom = deserialize_message(codecs.OdometryEncoder("odom", "base_link").encode(outputs, 5),
                               topics.message_class(topics.ODOM))
    assert (odom.header.frame_id, odom.child_frame_id, odom.header.stamp.nanosec) == (
        "odom", "base_link", 5)
    p, q = odom.pose.pose.position, odom.pose.pose.orientation
    assert (p.x, p.y, p.z) == (3.0, -2.0, 0.0)
    assert (q.x, q.y) == (0.0, 0.0)
    assert q.z == pytest.approx(math.sin(0.25), abs=1e-15)
    assert q.w == pytest.approx(math.cos(0.25), abs=1e-15)
    lin, ang = odom.twist.twist.linear, odom.twist.twist.angular
    assert (lin.x, lin.y, lin.z, ang.x, ang.y, ang.z) == (20.0, 0.25, 0.0, 0.125, 0.0, -0.375)
    assert not any(odom.pose.covariance) and not any(odom.twist.covariance)
    imu = deserialize_message(codecs.ImuEncoder("base_link").encode(outputs, 5),
                              topics.message_class(topics.IMU))
    a, w = imu.linear_acceleration, imu.angular_velocity
    assert (a.x, a.y, a.z) == (1.5, -4.0, 9.80665)
    assert (w.x, w.y, w.z) == (0.125, 0.0, -0.375)
    assert imu.orientation == odom.pose.pose.orientation


def test_decode_many_equals_one_by_one(tmp_path) -> None:
    """The bulk decoder gives, per message, the values of the one-message decoder; messages
    whose strings differ are left to the one-by-one path (None)."""
    rng = np.random.default_rng(5)
    msgtype = topics.TOPIC_TYPES[topics.STATE]
    encoder = codecs.StateEncoder("8dof", topics.FRAME_BODY)
    raws = [encoder.encode(_outputs(rng), 0.001 * k, k) for k in range(30)]
    bulk = cdr.decode_many(msgtype, raws)
    one = [cdr.Decoder(msgtype).decode(raw) for raw in raws]
    assert bulk is not None and set(bulk) == set(one[0])
    for key in bulk:
        assert [tuple(v) if isinstance(v, np.ndarray) else v for v in bulk[key]] == [
            m[key] for m in one]
    assert bulk["fy_n"].shape == (30, 4)
    other = codecs.StateEncoder("2dof", topics.FRAME_BODY).encode(_outputs(rng), 0.5, 500)
    assert cdr.decode_many(msgtype, raws + [other]) is None
    assert cdr.decode_many(topics.TOPIC_TYPES[topics.SIM_STATUS], raws) is None


def test_stamps_of_an_array_round_as_one_stamp_does():
    """interface.times_to_ns (the study's stamps of a whole run) equals time_to_ns element by
    element, near-ties and negative times included."""
    t = np.concatenate([np.arange(0, 5001) * 1e-3, [0.5e-9, 1.5e-9, 2.5e-9, -0.5e-9, 1e4 / 3,
                                                    1234.5678901234567]])
    assert interface.times_to_ns(t).tolist() == [interface.time_to_ns(v) for v in t]
