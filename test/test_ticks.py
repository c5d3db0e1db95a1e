# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The tick sequence's trust rules, pacing and flow control (fourws_run.ticks), without ROS.

Every case here is one a rogue or broken node produced against the graph (issue reports):
the rules are checked on their own, with exact counts.
"""

from __future__ import annotations

import math

import pytest

from fourws_run import interface
from fourws_run.ticks import (FlowWindow, InputLimits, LockstepAnswers, Pacer, RealtimeAnswers,
                              StateGate, Tick, whole_multiple)
from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import ParameterError
from fourws_sim.params import GRAVITY_MPS2, load_vehicle

LIMITS = InputLimits.for_vehicle(load_vehicle("table_8_1"))
DT = 1e-3


def _tick(step: int) -> Tick:
    t = step * DT
    return Tick(step, t, interface.time_to_ns(t), {})


def _driver(front: float = 0.01) -> DriverCommand:
    return DriverCommand(16 * front, front)


def test_input_limits_from_the_vehicle() -> None:
    car = load_vehicle("table_8_1")
    assert LIMITS.rear_angle_limit_rad == car.actuators.rear_angle_limit_rad
    # twice the weight times the wheel radius (1298.857 kg, 0.29 m): 7388 N m
    assert LIMITS.torque_limit_nm == pytest.approx(
        2 * car.chassis.mass_kg * GRAVITY_MPS2 * car.body.wheel_radius_m)
    assert LIMITS.driver_problem(_driver()) == ""
    assert "front road-wheel angle 100" in LIMITS.driver_problem(DriverCommand(1600.0, 100.0))
    assert LIMITS.driver_problem(DriverCommand(0.0, math.nan)) == "not finite"
    assert "negative brake" in LIMITS.driver_problem(
        DriverCommand(0.0, 0.0, 0.0, (0.0,) * 4, (0.0, -1.0, 0.0, 0.0)))
    assert "torque 1e+06" in LIMITS.driver_problem(
        DriverCommand(0.0, 0.0, 0.0, (1e6, 0.0, 0.0, 0.0), (0.0,) * 4))
    assert LIMITS.command_problem(math.nan) == "not finite"
    assert "beyond the limit" in LIMITS.command_problem(0.1)  # 5.7 deg > 5 deg
    assert LIMITS.command_problem(0.08) == ""


def test_lockstep_takes_exactly_one_answer_of_each_per_tick() -> None:
    book = LockstepAnswers(LIMITS)
    tick = _tick(10)
    book.expect(tick)
    assert book.waiting_for == "driver input and rear-steer command"
    # another tick's stamp, a step of no state, a step/stamp mix-up: refused
    assert not book.offer_driver(tick.stamp_ns + 1, _driver())
    assert not book.offer_command(99, tick.stamp_ns, 0.0)
    assert not book.offer_command(10, tick.stamp_ns + 5, 0.0)
    # impossible values: refused, the tick still waits
    assert not book.offer_driver(tick.stamp_ns, DriverCommand(1600.0, 100.0))
    assert not book.offer_command(10, tick.stamp_ns, math.nan)
    assert book.waiting_for == "driver input and rear-steer command"
    assert book.offer_driver(tick.stamp_ns, _driver())
    assert book.offer_command(10, tick.stamp_ns, 0.02)
    assert book.complete
    # a second answer of either kind: refused and counted as such
    assert not book.offer_driver(tick.stamp_ns, _driver(0.02))
    assert not book.offer_command(10, tick.stamp_ns, 0.03)
    driver, rear, timed_out = book.close()
    assert (driver, rear, timed_out) == (_driver(), 0.02, False)
    # after the tick ran, another answer to it is a second publisher, not a late one
    assert not book.offer_driver(tick.stamp_ns, _driver())
    counts = book.rejections.counts
    assert counts[f"{interface.DRIVER_INPUT}: second answer to one state"] == 2
    assert counts[f"{interface.REAR_STEER_CMD}: second answer to one state"] == 1
    assert counts[f"{interface.DRIVER_INPUT}: stamp of no published state"] == 1
    assert counts[f"{interface.REAR_STEER_CMD}: step of no published state"] == 1
    assert counts[f"{interface.REAR_STEER_CMD}: step and stamp of different states"] == 1
    assert counts[f"{interface.DRIVER_INPUT}: impossible values"] == 1
    assert counts[f"{interface.REAR_STEER_CMD}: impossible values"] == 1
    assert book.rejections.total == 8
    assert book.driver_inputs_accepted == book.commands_accepted == 1


def test_lockstep_timeout_then_a_late_command_is_counted_late_not_foreign() -> None:
    book = LockstepAnswers(LIMITS)
    tick = _tick(10)
    book.expect(tick)
    book.offer_driver(tick.stamp_ns, _driver())
    _, rear, timed_out = book.close()  # the controller did not answer in time
    assert (rear, timed_out) == (0.0, True)
    book.expect(_tick(20))
    assert not book.offer_command(10, tick.stamp_ns, 0.01)  # its answer comes now
    assert book.late_commands == 1 and book.rejections.total == 0


def test_realtime_command_age_cannot_be_reset_by_a_message() -> None:
    """The issue's case: a command whose state stamp lies in the future kept a stopped
    controller's last command alive for 5.5 s. A command counts only for a state the
    simulator published; its age runs from that state's own time."""
    book = RealtimeAnswers(LIMITS)
    for step in range(0, 101, 10):
        book.published(_tick(step))
    assert book.offer_command(100, _tick(100).stamp_ns, 0.05)
    timeout = 0.1
    assert book.rear_at(0.15, timeout) == (0.05, False)
    # a command for a future state (stamp 1e5 s) or a state never published: refused
    assert not book.offer_command(10 ** 8, interface.time_to_ns(1e5), 0.08)
    assert not book.offer_command(105, _tick(105).stamp_ns, 0.08)
    # an older state's command does not go back in time
    assert not book.offer_command(50, _tick(50).stamp_ns, 0.07)
    assert book.late_commands == 1
    # 0.1 s after the state the held command answered, rear steer falls back to zero
    assert book.rear_at(0.1 + timeout + 1e-9, timeout) == (0.0, True)
    assert book.rejections.total == 2


def test_realtime_driver_input_only_newer_and_published() -> None:
    book = RealtimeAnswers(LIMITS)
    book.published(_tick(10))
    book.published(_tick(20))
    assert book.offer_driver(_tick(20).stamp_ns, _driver(0.02))
    assert not book.offer_driver(_tick(10).stamp_ns, _driver(0.01))  # older
    assert not book.offer_driver(interface.time_to_ns(1e5), _driver())  # future
    assert book.driver == _driver(0.02) and book.driver_time_s == pytest.approx(0.02)


def test_state_gate_follows_the_simulators_clock() -> None:
    gate = StateGate(DT, 0.01, lockstep=True)
    assert not gate.admit(10, 0.01, interface.time_to_ns(0.01))  # not the start
    assert gate.admit(0, 0.0, 0)
    assert gate.admit(10, 10 * DT, interface.time_to_ns(10 * DT))
    # the rogue state: t = 1e6 s
    assert not gate.admit(10 ** 9, 1e6, interface.time_to_ns(1e6))
    # skipped, repeated, off-period, wrong time or stamp
    assert not gate.admit(30, 30 * DT, interface.time_to_ns(30 * DT))
    assert not gate.admit(10, 10 * DT, interface.time_to_ns(10 * DT))
    assert not gate.admit(25, 25 * DT, interface.time_to_ns(25 * DT))
    assert not gate.admit(20, 0.0201, interface.time_to_ns(0.0201))
    assert not gate.admit(20, 20 * DT, interface.time_to_ns(20 * DT) + 7)
    assert gate.admit(20, 20 * DT, interface.time_to_ns(20 * DT))
    assert gate.rejections.total == 7
    # realtime: missed states are fine, a jump beyond max_gap_s is not
    rt = StateGate(DT, 0.005, lockstep=False, max_gap_s=1.0)
    assert rt.admit(5, 5 * DT, interface.time_to_ns(5 * DT))
    assert rt.admit(50, 50 * DT, interface.time_to_ns(50 * DT))
    assert not rt.admit(2000, 2000 * DT, interface.time_to_ns(2000 * DT))


def test_pacer_records_every_overrun_with_its_time() -> None:
    """Simulated clock: steps at 1 ms; the process loses 3 ms before step 3 (which then starts
    2 ms late: an overrun, kept with its time; the schedule is re-based, not raced) and 0.5 ms
    before step 7 (within the slack after the re-base: on time)."""
    now = [0.0]
    sleeps: list[float] = []

    def sleep(s: float) -> None:
        sleeps.append(s)
        now[0] += s

    pacer = Pacer(DT, clock=lambda: now[0], sleep=sleep)
    pacer.start(0.0)
    for k in range(10):
        if k == 3:
            now[0] += 0.003
        if k == 7:
            now[0] += 0.0005
        pacer.wait(k * DT)
    assert pacer.overruns == 1
    (t, late), = pacer.take_overruns()
    assert t == pytest.approx(3 * DT) and late == pytest.approx(0.002, abs=1e-12)
    assert pacer.take_overruns() == []
    assert pacer.max_lateness_s == pytest.approx(0.002, abs=1e-12)
    assert pacer.percentile(100.0) >= pacer.max_lateness_s


def test_flow_window_holds_with_hysteresis() -> None:
    window = FlowWindow(50, (interface.STATE, interface.DRIVER_INPUT))
    sent = {interface.STATE: 50, interface.DRIVER_INPUT: 50}
    assert window.holding_back(sent) == ""
    sent[interface.STATE] = 51
    assert window.holding_back(sent) == interface.STATE
    window.update({interface.STATE: 10})  # 41 ahead: still held until within 25
    assert window.holding_back(sent) == interface.STATE
    window.update({interface.STATE: 5})  # an older report changes nothing
    assert window.stored[interface.STATE] == 10
    window.update({interface.STATE: 26})  # 25 ahead on state, but driver input 50 ahead
    assert window.holding_back(sent) == interface.DRIVER_INPUT
    window.update({interface.DRIVER_INPUT: 30})
    assert window.holding_back(sent) == ""
    assert window.holds == 1
    assert FlowWindow(0, (interface.STATE,)).holding_back({interface.STATE: 10 ** 6}) == ""


def test_whole_multiple_is_one_check() -> None:
    assert whole_multiple(0.01, 0.001, "control_period_s") == 10
    with pytest.raises(ParameterError, match="control_period_s.*whole multiple"):
        whole_multiple(0.0105, 0.001, "control_period_s")
    with pytest.raises(ParameterError, match="integration_step_s.*> 0"):
        whole_multiple(0.01, 0.0, "control_period_s")
    with pytest.raises(ParameterError, match="state_period_s.*whole multiple"):
        whole_multiple(0.0005, 0.001, "state_period_s")


def test_state_gate_admits_only_a_final_status_of_its_own_run():
    """A final simulator status is the run's only at or after the last answered state and
    (lockstep) at most one state period (+ one step) later: the simulator cannot run further
    ahead of a node answering every state. Numbers: dt 1 ms, state period 10 ms."""
    gate = StateGate(1e-3, 1e-2, lockstep=True)
    assert gate.admits_final(0.0)  # the simulator ended before its first state
    assert not gate.admits_final(1e6) and not gate.admits_final(math.nan)
    for k in range(3):
        assert gate.admit(10 * k, 10 * k * 1e-3, interface.time_to_ns(10 * k * 1e-3))
    t_last = 20 * 1e-3
    assert gate.admits_final(t_last) and gate.admits_final(t_last + 0.011)
    assert not gate.admits_final(t_last + 0.0111)
    assert not gate.admits_final(t_last - 1e-3)  # before what was answered
    assert gate.rejections.counts[f"{interface.SIM_STATUS}: final status not of this run"] == 4
    realtime = StateGate(1e-3, 1e-2, lockstep=False, max_gap_s=1.0)
    assert realtime.admits_final(1.0) and not realtime.admits_final(1.002)
