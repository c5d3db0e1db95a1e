# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Bag typestore, writer, reader and resampling (fourws_analysis/bag.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fourws_analysis import bag as B
from fourws_run.cdr import decode_many


def _write_state_bag(path: Path, n: int, dt_s: float, jitter_s: float = 0.0,
                     config: dict | None = None) -> np.ndarray:
    """Bag with ``n`` VehicleState messages, yaw rate sin(t); returns the stamps (s)."""
    rng = np.random.default_rng(1)
    times = np.arange(n) * dt_s + rng.uniform(-jitter_s, jitter_s, n) * (np.arange(n) > 0)
    store = B.typestore()
    mt = B.TOPIC_TYPES[B.TOPIC_STATE]
    with B.BagWriter(path) as bag:
        bag.write_run_config(config or {"maneuver": {"type": "step_steer"}, "law": "fws"})
        for i, t in enumerate(times):
            msg = B.make_message(mt, header={"stamp": B.stamp(t), "frame_id": "base_link"},
                                 step=i, model="2dof", yaw_rate_radps=np.sin(t),
                                 fy_n=np.full(4, float(i)))
            bag.write_raw(B.TOPIC_STATE, store.serialize_cdr(msg, mt), int(t * 1e9) + 1000)
    return times


def test_roundtrip_values_and_config(tmp_path: Path) -> None:
    """Written values come back exactly (fast bulk decoder), config JSON and maneuver too."""
    times = _write_state_bag(tmp_path / "b", 200, 1e-3)
    run = B.load_bag(tmp_path / "b")
    state = run.topics[B.TOPIC_STATE]
    assert len(state) == 200
    np.testing.assert_allclose(state.time_s, times, atol=1e-9)  # ns stamp resolution
    np.testing.assert_allclose(state.fields["yaw_rate_radps"], np.sin(state.time_s), atol=1e-9)
    np.testing.assert_array_equal(state.fields["fy_n"][:, 2], np.arange(200.0))
    assert state.fields["model"][5] == "2dof"
    assert run.maneuver == "step_steer" and run.law == "fws"


def test_fast_decoder_equals_rosbags_deserializer(tmp_path: Path) -> None:
    """The numpy bulk decoder gives the same numbers as the rosbags CDR deserializer."""
    _write_state_bag(tmp_path / "b", 50, 1e-3)
    mt = B.TOPIC_TYPES[B.TOPIC_STATE]
    from rosbags.rosbag2 import Reader
    with Reader(tmp_path / "b") as reader:
        raws = [raw for c, _, raw in reader.messages() if c.topic == B.TOPIC_STATE]
    fast = decode_many(mt, raws)
    slow = B._decode_generic(mt, raws)
    assert fast is not None
    assert set(fast) == set(slow)
    for key in fast:
        if fast[key].dtype == object:
            assert list(fast[key]) == list(slow[key])
        else:
            np.testing.assert_array_equal(fast[key], slow[key])


def test_resample_uniform_grid_recovers_signal(tmp_path: Path) -> None:
    """Jittered stamps resampled to a uniform grid: sin(t) within linear-interpolation error
    (h^2/8 max|f''| with h = 2 ms spacing -> 5e-7)."""
    _write_state_bag(tmp_path / "b", 400, 1e-3, jitter_s=3e-4)
    uni = B.resample(B.load_bag(tmp_path / "b"), dt_s=1e-3)
    assert np.allclose(np.diff(uni.time_s), 1e-3, atol=1e-12)
    err = np.abs(uni.channels["yaw_rate_radps"] - np.sin(uni.time_s))
    assert err.max() < (2e-3) ** 2 / 8 * 1.0 + 1e-9


def test_missing_bag_named(tmp_path: Path) -> None:
    """A missing bag is a BagError naming the path."""
    with pytest.raises(B.BagError, match="nope.*does not exist"):
        B.load_bag(tmp_path / "nope")


def test_truncated_bag_refused_or_read_up_to_its_damage(tmp_path: Path) -> None:
    """A bag cut at 50 % (recorder killed) is refused, naming the damage; with
    ``allow_incomplete`` it gives the messages of its complete chunks, flagged incomplete; cut
    to its first 100 bytes nothing is readable: an error naming the bag."""
    _write_state_bag(tmp_path / "b", 20000, 1e-3)
    mcap = next((tmp_path / "b").glob("*.mcap"))
    data = mcap.read_bytes()
    mcap.write_bytes(data[: len(data) // 2])
    with pytest.raises(B.BagError, match=r"b' is incomplete or damaged: b.mcap damaged"):
        B.load_bag(tmp_path / "b")
    run = B.load_bag(tmp_path / "b", allow_incomplete=True)
    n = len(run.topics[B.TOPIC_STATE])
    assert 0 < n < 20000
    assert run.complete is False and "damaged" in run.warnings[0]
    # the metadata's count disagrees with the file: named too
    assert any("metadata.yaml says 20000 messages" in p for p in run.problems)
    # recovered messages are intact and in order
    np.testing.assert_allclose(run.topics[B.TOPIC_STATE].fields["yaw_rate_radps"],
                               np.sin(np.arange(n) * 1e-3), atol=1e-9)
    # a recorder killed by SIGKILL leaves no metadata.yaml either
    (tmp_path / "b" / "metadata.yaml").unlink()
    run = B.load_bag(tmp_path / "b", allow_incomplete=True)
    assert len(run.topics[B.TOPIC_STATE]) == n
    assert run.maneuver == "step_steer"
    mcap.write_bytes(data[:100])
    with pytest.raises(B.BagError, match=r"b' holds no readable message"):
        B.load_bag(tmp_path / "b", allow_incomplete=True)


def test_changed_byte_is_caught_by_the_checksum(tmp_path: Path) -> None:
    """One overwritten yaw-rate value (8 bytes inside a chunk): the chunk CRC fails, the bag
    is refused instead of giving a plausible wrong number; the values before that chunk are
    what was written."""
    _write_state_bag(tmp_path / "b", 2000, 1e-3)
    mcap = next((tmp_path / "b").glob("*.mcap"))
    data = bytearray(mcap.read_bytes())
    value = np.float64(np.sin(1000 * 1e-3)).tobytes()  # message 1000's yaw rate
    pos = data.find(value)
    assert pos > 0
    data[pos:pos + 8] = np.float64(45.9).tobytes()
    mcap.write_bytes(bytes(data))
    with pytest.raises(B.BagError, match=r"damaged.*(CRC|crc)"):
        B.load_bag(tmp_path / "b")
    run = B.load_bag(tmp_path / "b", allow_incomplete=True)
    yaw = run.topics[B.TOPIC_STATE].fields["yaw_rate_radps"]
    assert 0 < yaw.size <= 1000 and 45.9 not in yaw
    np.testing.assert_allclose(yaw, np.sin(np.arange(yaw.size) * 1e-3), atol=1e-9)


def test_writer_accounting_makes_the_bag_complete(tmp_path: Path) -> None:
    """A bag whose writer recorded its accounting loads as complete; one without it loads
    with its completeness unknown and a warning saying so."""
    from fourws_run.accounting import RunAccount, TopicAccount

    _write_state_bag(tmp_path / "b", 10, 1e-3)
    run = B.load_bag(tmp_path / "b")
    assert run.complete is None and "not verified" in run.warnings[0]
    with B.BagWriter(tmp_path / "c") as bag:
        bag.write_run_config({"law": "fws"})
        account = RunAccount({t: TopicAccount(t, n, n) for t, n in bag.counts.items()})
        bag.set_accounting(account.to_dict(), account.complete)
    run = B.load_bag(tmp_path / "c")
    assert run.complete is True and not run.warnings


def test_junk_file_is_clear_error(tmp_path: Path) -> None:
    """A file that is not MCAP at all: BagError naming it."""
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not a bag" * 50)
    with pytest.raises(B.BagError, match="junk.mcap"):
        B.load_bag(junk)


def test_missing_topic_named(tmp_path: Path) -> None:
    """A bag without /fourws/driver_input: require() names the topic and the bag."""
    _write_state_bag(tmp_path / "b", 10, 1e-3)
    run = B.load_bag(tmp_path / "b")
    with pytest.raises(B.BagError, match="/fourws/driver_input"):
        run.require(B.TOPIC_DRIVER)
    with pytest.raises(B.BagError, match="no field 'banana'"):
        run.require(B.TOPIC_STATE, "banana")


def test_resample_holds_each_command_at_its_own_stamp_on_a_long_record(tmp_path: Path) -> None:
    """A 60 s record at 100 Hz: the driver command resampled at grid point k is the one
    stamped k * 10 ms, to the end. (The grid t0 + k dt drifts from the float stamps by about
    1e-12 s after 47 s; a fixed tolerance of 1e-12 s handed over the previous command from
    there on, a one-sample delay of the input in the second half of a 60 s sweep.)"""
    n, dt = 6001, 0.01
    t = dt * np.arange(n)
    command = np.arange(n, dtype=float)  # the command is its own sample number
    state = {"yaw_rate_radps": np.zeros(n), "speed_mps": np.full(n, 20.0)}
    driver = {"steering_wheel_angle_rad": command, "front_wheel_angle_rad": command}
    B.write_run(tmp_path / "long", t, state, {"maneuver": {"type": "random_steer"}},
                driver=driver, model="2dof")
    run = B.resample(B.load_bag(tmp_path / "long"))
    assert run.time_s.size == n
    np.testing.assert_array_equal(run.channels["steering_wheel_angle_rad"], command)
    np.testing.assert_array_equal(run.channels["front_wheel_angle_cmd_rad"], command)
