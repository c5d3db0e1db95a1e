# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The simulator's clock modes without ROS (fourws_run.clock_modes): the node's adapter is
replaced by a sink that records what it is told to publish, the wall clock by a counter."""

from __future__ import annotations

import time

import pytest

from fourws_run.clock_modes import LockstepClock, RealtimeClock
from fourws_run.ticks import FlowWindow, InputLimits, TickEngine
from fourws_sim.drivers import DriverCommand
from fourws_sim.params import load_vehicle
from fourws_sim.simulator import Simulator


class Sink:
    """Records ticks, waits and the end."""

    def __init__(self) -> None:
        self.ticks = []
        self.waits = []
        self.ended: tuple[str, bool] | None = None

    def publish_state(self, tick) -> bool:
        self.ticks.append(tick)
        return True

    def side_publications(self, tick) -> list:
        return []

    def report_wait(self, t: float) -> None:
        self.waits.append(t)

    def end(self, reason: str, failed: bool) -> None:
        self.ended = (reason, failed)

    def silent_node(self, missing: str) -> str:
        return f"the node of the {missing}"


class WallClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _engine() -> TickEngine:
    vehicle = load_vehicle("table_4_1_set_1")
    sim = Simulator(vehicle, model="2dof", integrator="rk4", dt_s=1e-3)
    engine = TickEngine(sim, 0.01)
    engine.reset(20.0)
    return engine


def _lockstep(window: int = 0, sent=None):
    engine, sink, wall = _engine(), Sink(), WallClock()
    limits = InputLimits(0.1, 1e5)
    clock = LockstepClock(engine, sink, limits, FlowWindow(window, ["/fourws/state"]),
                          sent_counts=sent or (lambda: {}), answer_timeout_s=lambda: 60.0,
                          recorder_timeout_s=lambda: 90.0, monotonic=wall)
    return clock, sink, wall


def test_lockstep_runs_a_tick_only_on_both_answers():
    """Tick 0 goes out on resume; a driver input alone does not advance it, the command
    completes it and tick 1 (10 integration steps later) goes out."""
    clock, sink, _ = _lockstep()
    clock.resume()
    assert [t.step for t in sink.ticks] == [0]
    t0 = sink.ticks[0]
    clock.offer_driver(t0.stamp_ns, DriverCommand(0.0, 0.01))
    assert len(sink.ticks) == 1
    clock.offer_command(t0.step, t0.stamp_ns, 0.0)
    assert [t.step for t in sink.ticks] == [0, 10] and clock.ticks == 1


def test_lockstep_answer_timeout_names_the_silent_node():
    """No command for 60 s of wall time (the answer timeout): one status after 1 s says what
    the tick waits for, then the run ends as failed naming the controller's answer."""
    clock, sink, wall = _lockstep()
    clock.resume()
    t0 = sink.ticks[0]
    clock.offer_driver(t0.stamp_ns, DriverCommand(0.0, 0.01))
    wall.now = 1.5
    clock.housekeeping()
    assert sink.waits == [0.0] and sink.ended is None
    assert clock.waiting_for() == "rear-steer command (controller node)"
    wall.now = 60.5
    clock.housekeeping()
    reason, failed = sink.ended
    assert failed and "no rear-steer command for the state at t = 0.00 s within 60 s" in reason
    assert "the node of the rear-steer command did not answer" in reason


def test_lockstep_held_tick_waits_for_the_recorder_then_fails():
    """With a window of 2 and the recorder storing nothing, the third tick is held (flow
    control); the recorder's report releases it; a recorder that never reports fails the run
    after the answer timeout, naming the recorder."""
    sent = {"/fourws/state": 0}
    clock, sink, wall = _lockstep(window=2, sent=lambda: sent)

    def answer():
        t = sink.ticks[-1]
        sent["/fourws/state"] = len(sink.ticks)
        clock.offer_driver(t.stamp_ns, DriverCommand(0.0, 0.0))
        clock.offer_command(t.step, t.stamp_ns, 0.0)

    clock.resume()
    sent["/fourws/state"] = 1
    for _ in range(3):
        answer()
    assert len(sink.ticks) == 3 and clock.held is not None  # 3 sent, 0 stored > 2
    clock.recorder_stored({"/fourws/state": 3})
    assert len(sink.ticks) == 4 and clock.held is None
    for _ in range(3):  # 6 states out, 3 stored: the seventh is held
        answer()
    assert len(sink.ticks) == 6 and clock.held is not None
    wall.now = 61.0
    clock.housekeeping()
    assert sink.ended is None  # past the answer timeout, within the recorder's
    wall.now = 91.0
    clock.housekeeping()
    reason, failed = sink.ended
    assert failed and "the recorder did not catch up within 90 s" in reason


def test_realtime_starts_its_wall_clock_only_on_the_first_answers():
    """Realtime: the first state goes out at once, nothing runs until its driver input and
    command are in (the thread then integrates); without them the run ends after the answer
    timeout naming what is missing."""
    engine, sink = _engine(), Sink()
    clock = RealtimeClock(engine, sink, InputLimits(0.1, 1e5), state_steps=5,
                          stale_after_s=lambda: 0.1, driver_timeout_s=lambda: 1.0,
                          answer_timeout_s=lambda: 0.2)
    clock.resume()
    assert [t.step for t in sink.ticks] == [0]
    t0 = sink.ticks[0]
    clock.offer_driver(t0.stamp_ns, DriverCommand(0.0, 0.01))
    time.sleep(0.05)
    assert len(sink.ticks) == 1 and engine.sim.step_count == 0  # still waiting
    assert clock.waiting_for() == "rear-steer command (controller node)"
    clock.offer_command(t0.step, t0.stamp_ns, 0.0)
    deadline = time.monotonic() + 5.0
    while len(sink.ticks) < 3 and time.monotonic() < deadline:
        time.sleep(0.01)
    clock.pause()
    assert [t.step for t in sink.ticks[:3]] == [0, 5, 10]
    # a first state that is never answered
    engine, sink = _engine(), Sink()
    clock = RealtimeClock(engine, sink, InputLimits(0.1, 1e5), state_steps=5,
                          stale_after_s=lambda: 0.1, driver_timeout_s=lambda: 1.0,
                          answer_timeout_s=lambda: 0.05)
    clock.resume()
    time.sleep(0.1)
    clock.housekeeping()
    reason, failed = sink.ended
    assert failed and "no driver input for the first state" in reason
    assert engine.sim.step_count == 0


class SpreadSink(Sink):
    """Each state has ``n_side`` side publications; the log says in which order states and
    side publications went out and at which integration step; side publication ``stop_at``
    (a (step, index) pair) ends the run as an end time does."""

    def __init__(self, engine, n_side: int, stop_at=None) -> None:
        super().__init__()
        self.engine, self.n_side, self.stop_at = engine, n_side, stop_at
        self.log: list[tuple] = []

    def publish_state(self, tick) -> bool:
        self.log.append(("state", tick.step, self.engine.sim.step_count))
        return super().publish_state(tick)

    def side_publications(self, tick) -> list:
        def side(j: int):
            def publish() -> bool:
                self.log.append(("side", tick.step, j, self.engine.sim.step_count))
                if (tick.step, j) == self.stop_at:
                    self.end("end time reached", False)
                    return False
                return True
            return publish
        return [side(j) for j in range(self.n_side)]


def _realtime_run(sink_of, ticks: int):
    """A realtime clock run until ``ticks`` states went out (or its sink ended it)."""
    engine = _engine()
    sink = sink_of(engine)
    clock = RealtimeClock(engine, sink, InputLimits(0.1, 1e5), state_steps=5,
                          stale_after_s=lambda: 0.1, driver_timeout_s=lambda: 10.0)
    clock.resume()
    t0 = sink.ticks[0]
    clock.offer_driver(t0.stamp_ns, DriverCommand(0.0, 0.01))
    clock.offer_command(t0.step, t0.stamp_ns, 0.0)
    deadline = time.monotonic() + 30.0
    while len(sink.ticks) < ticks and sink.ended is None and time.monotonic() < deadline:
        time.sleep(0.005)
    clock.pause()
    return sink


def test_realtime_spreads_a_states_side_publications_over_the_next_steps():
    """Realtime: the first state goes out whole; after that each state's side publications
    go out one per integration step after it (3 of them: steps +1, +2, +3), in order, all
    before the next state -- and none is left behind when the clock stops."""
    sink = _realtime_run(lambda engine: SpreadSink(engine, 3), ticks=6)
    states = [e for e in sink.log if e[0] == "state"]
    assert len(states) >= 6
    expected = []
    for _, step, at in states:
        expected.append(("state", step, at))
        first = 0 if step == 0 else 1  # the first state's go out with it
        expected += [("side", step, j, at + (first and j + 1)) for j in range(3)]
    # the last state's: those the stop came before went out as the thread ended
    last = states[-1]
    n = len(sink.log) - 3
    assert sink.log[:n] == expected[:n]
    tail = sink.log[n:]
    assert [e[:3] for e in tail] == [("side", last[1], j) for j in range(3)]
    assert [e[3] for e in tail] == sorted(e[3] for e in tail)
    assert all(last[2] <= e[3] <= x[3] for e, x in zip(tail, expected[n:]))


def test_realtime_publishes_what_a_state_could_not_spread_before_the_next():
    """Seven side publications and four integration steps to the next state: four go out
    one per step, the other three just before the next state, in order."""
    sink = _realtime_run(lambda engine: SpreadSink(engine, 7), ticks=4)
    states = [e for e in sink.log if e[0] == "state"]
    assert len(states) >= 4
    _, step, at = states[1]
    sides = [e for e in sink.log if e[0] == "side" and e[1] == step]
    assert [e[2] for e in sides] == list(range(7))
    assert [e[3] for e in sides] == [at + 1, at + 2, at + 3, at + 4, at + 5, at + 5, at + 5]
    nxt = sink.log.index(states[2])
    assert sink.log.index(sides[-1]) == nxt - 1


def test_realtime_side_publication_that_ends_the_run_is_the_last():
    """A side publication that ends the run (an end time): nothing is integrated or published
    after it, not even the rest of that state's side publications."""
    sink = _realtime_run(lambda engine: SpreadSink(engine, 3, stop_at=(10, 1)), ticks=100)
    assert sink.ended == ("end time reached", False)
    assert sink.log[-1] == ("side", 10, 1, 12)
    assert [e[1] for e in sink.log if e[0] == "state"] == [0, 5, 10]


@pytest.mark.parametrize("mode", ["nothing"])
def test_make_clock_refuses_an_unknown_mode(mode):
    from fourws_run.clock_modes import make_clock

    with pytest.raises(ValueError, match="lockstep, realtime"):
        make_clock(mode)
