# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Driving the car from outside: a driver written from docs/driver-contract.md
(test/contract_driver.py) and another stack's Ackermann commands through ``fourws node
ackermann_driver`` (test/ackermann_stack.py) each drive a lockstep run, and the bag equals the
offline twin fed the same driver inputs bit for bit; the driver cores refuse and count what
cannot be a command.

Sources: the bags' own ``/fourws/driver_input`` replayed through
:func:`fourws_run.closed_loop.run_closed_loop` (the twin of the lockstep graph), the steering
laws the two test nodes state in their docstrings, float32 rounding of
``ackermann_msgs/AckermannDrive`` (numpy), and the speed-hold and Joy mappings' formulas.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fourws_ros import graph_run, topics
from fourws_run.bagfile import read_bag, typestore
from fourws_run.closed_loop import run_closed_loop
from fourws_run.config import RunConfig
from fourws_run.scenario import load_scenario
from fourws_sim.config_yaml import read_yaml
from fourws_sim.drivers import DriverCommand
from fourws_sim.input_drivers import (AckermannDriver, JoyDriver, JoyMapping, KeyboardAxes,
                                      joy_mapping_from)
from fourws_sim.params import CONFIG_DIR, load_vehicle

HERE = Path(__file__).resolve().parent


def _bag(record):
    messages, check = read_bag(record.bag_path)
    assert check.complete, check.problems
    store = typestore()
    out = {}
    for m in sorted(messages, key=lambda m: m.log_time_ns):
        if m.topic in (topics.STATE, topics.DRIVER_INPUT):
            out.setdefault(m.topic, []).append(store.deserialize_cdr(m.data, m.msgtype))
    return out[topics.STATE], out[topics.DRIVER_INPUT]


def _replayed(config, states, inputs):
    """The twin fed the bag's driver inputs, one per integrated state; equal to the bag."""
    n = len(states) - 1
    commands = [DriverCommand(float(d.steering_wheel_angle_rad), float(d.front_wheel_angle_rad),
                              float(d.steering_torque_nm), tuple(map(float, d.drive_torque_nm)),
                              tuple(map(float, d.brake_torque_nm))) for d in inputs[:n]]
    twin = config
    result = run_closed_loop(
        twin.vehicle, twin.maneuver, twin.law, model=twin.model, dt_s=twin.integration_step_s,
        control_period_s=twin.control_period_s, belief_vehicle=twin.belief,
        integrator=twin.integrator, law_options=twin.law_options, driver_inputs=commands)
    assert result.time_s.size == n
    for name in ("yaw_rate_radps", "lateral_velocity_mps", "speed_mps", "roll_rad", "x_m",
                 "y_m", "front_wheel_angle_rad", "rear_wheel_angle_rad"):
        np.testing.assert_array_equal([getattr(s, name) for s in states[:n]], result[name],
                                      err_msg=name)
    return result


@pytest.fixture
def run_domain(monkeypatch):
    monkeypatch.setenv("ROS_DOMAIN_ID", "197")
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")


def test_a_driver_from_the_contract_drives_a_lockstep_run(tmp_path, run_domain):
    config = RunConfig.from_scenario(load_scenario("default"), "sol1").replace(
        driver=(str(HERE / "contract_driver.py"),))
    record = graph_run.run_graph(config, tmp_path, run_name="driver")
    assert record.ok, record.reason
    assert record.reason == "end time 5 s reached"
    states, inputs = _bag(record)
    # the driver answered every state (the last one after the run's end as well)
    assert len(inputs) == len(states) == 501
    for s, d in zip(states, inputs):
        assert d.front_wheel_angle_rad == 0.02 * math.sin(2 * math.pi * 0.5 * s.sim_time_s)
        assert tuple(d.drive_torque_nm) == (0.0, 0.0, 40.0, 40.0)
        assert d.steering_wheel_angle_rad == d.front_wheel_angle_rad * 16.3  # table_8_1 K_sr
    _replayed(config, states, inputs)


def test_an_ackermann_stack_drives_a_lockstep_run(tmp_path, run_domain):
    stack = subprocess.Popen([sys.executable, str(HERE / "ackermann_stack.py")],
                             env={**os.environ}, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE)
    try:
        config = RunConfig.from_scenario(load_scenario("default"), "sol1").replace(
            driver=("ackermann",))
        record = graph_run.run_graph(config, tmp_path, run_name="ackermann")
    finally:
        stack.terminate()
        stack.communicate(timeout=30)
    assert record.ok, record.reason
    states, inputs = _bag(record)
    assert len(inputs) == len(states) - 1 == 500
    for s, d in zip(states, inputs):
        # the stack's steering angle, through the float32 of AckermannDrive
        assert d.front_wheel_angle_rad == float(np.float32(
            0.03 * math.sin(2 * math.pi * 0.4 * s.sim_time_s)))
    result = _replayed(config, states, inputs)
    # the speed-hold loop holds the stack's 20 m/s from 23.6 m/s: it brakes down to it
    assert result["speed_mps"][-1] == pytest.approx(20.0, abs=0.3)


def test_the_ackermann_core_refuses_absurd_and_stale_commands():
    car = load_vehicle("table_8_1")
    drive = AckermannDriver(car, timeout_s=0.5)
    assert not drive.offer(float("nan"), 10.0, 0.0)
    assert not drive.offer(2.0, 10.0, 0.0)          # 115 deg of road-wheel angle
    assert not drive.offer(0.1, 1e4, 0.0)           # beyond MAX_SPEED_MPS
    assert drive.book.rejections == {"not finite": 1, "impossible values": 2}
    assert drive.offer(0.1, 10.0, 0.0)
    cmd = drive.command(0.0, {"speed_mps": 10.0}, now_s=0.2)
    assert cmd.front_wheel_angle_rad == 0.1 and cmd.steering_wheel_angle_rad == 0.1 * 16.3
    cmd = drive.command(0.01, {"speed_mps": 10.0}, now_s=0.8)   # 0.8 s old: stale
    assert drive.book.stale_ticks == 1 and cmd.front_wheel_angle_rad == 0.0
    assert sum(cmd.brake_torque_nm) > 0.0                       # target 0 m/s: it brakes


def test_the_joy_mapping():
    """Full left stick, half right trigger (axis reads 0), no brake (+1): steering wheel
    pi/2, drive m a R / 2 per rear wheel at a = 1.5 m/s^2 (half of 3)."""
    car = load_vehicle("table_8_1")
    joy = JoyDriver(car, JoyMapping())
    axes = [1.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    assert joy.offer(axes, now_s=0.0)
    cmd = joy.command(0.0, {}, now_s=0.1)
    assert cmd.steering_wheel_angle_rad == math.pi / 2
    assert cmd.front_wheel_angle_rad == math.pi / 2 / 16.3
    assert cmd.drive_torque_nm[2] == pytest.approx(1298.857 * 1.5 * 0.29 / 2)
    assert not joy.offer([1.5, 0.0, 1.0, 0.0, 0.0, 0.0], now_s=0.2)   # beyond [-1, 1]
    assert not joy.offer([0.0, 0.0], now_s=0.2)                        # too few axes
    assert joy.book.rejections == {"impossible values": 2}


def test_the_keyboard_gives_the_pads_axes():
    """Two presses of d, three of w: steer -0.2, throttle 0.75 (trigger axis 1 - 2 * 0.75);
    s releases the throttle; through the joy mapping the steering wheel turns -0.2 * pi/2."""
    keys = KeyboardAxes()
    for key in "ddwww":
        assert keys.press(key)
    axes = keys.axes()
    assert (axes[0], axes[5], axes[2]) == (-0.2, -0.5, 1.0)
    joy = JoyDriver(load_vehicle("table_8_1"))
    assert joy.offer(axes, now_s=0.0)
    assert joy.command(0.0, {}, 0.0).steering_wheel_angle_rad == pytest.approx(-0.2 * math.pi / 2)
    keys.press("s")
    assert keys.throttle == 0.0 and keys.brake == 0.25 and not keys.press("x")


def test_the_shipped_pad_mapping_is_the_default():
    """config/drivers/joy.yaml holds JoyMapping's defaults (the common pad layout)."""
    path = Path(CONFIG_DIR) / "drivers" / "joy.yaml"
    assert joy_mapping_from(read_yaml(path)["joy_mapping"], str(path)) == JoyMapping()
