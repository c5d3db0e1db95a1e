# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The simulator's two clock modes, without ROS: :class:`LockstepClock` and
:class:`RealtimeClock`.

The simulator node (:mod:`fourws_ros.simulator_node`) owns the ROS objects and converts
messages; what it does with a driver input, a rear-steer command, the recorder's progress and
the passing of time depends on the clock mode, and is one of these two classes. Both drive a
:class:`fourws_run.ticks.TickEngine` and tell the node what to publish through a
:class:`TickSink` (the node's publishers), so the tick sequence itself is the one of
:mod:`fourws_run.ticks`, shared with the offline twin.

``lockstep`` (deterministic, faster than real time)
    Tick ``k``: the sink publishes state ``y_k``; the clock waits until the maneuver's
    ``DriverInput`` stamped ``y_k``'s stamp and the controller's ``RearSteerCommand`` naming
    ``y_k``'s step and stamp have arrived (:class:`~fourws_run.ticks.LockstepAnswers`),
    integrates one control period holding them and hands ``y_{k+1}`` to the sink. With a
    recorder window the next tick waits while the recorder is more than that many messages
    behind on a recorded topic (:class:`~fourws_run.ticks.FlowWindow`). A tick never runs on
    anything but its answers, so a loaded machine cannot change the numbers: after
    ``answer_timeout_s`` of wall time without them the run stops as failed, naming the node,
    and after ``recorder_timeout_s`` of a tick held for the recorder, naming the recorder.
``realtime`` (paced by the wall clock)
    The first state is published and answered as in lockstep (the wall clock starts once the
    driver input and the command of state 0 are in, so a node that is slow to start cannot
    make the run fail or go without rear steer at its beginning; after ``answer_timeout_s``
    without them the run stops as failed, naming the node). Then a thread integrates one step
    every ``integration_step_s`` of wall time
    (:class:`~fourws_run.ticks.Pacer`), holds the latest valid driver input and command
    (:class:`~fourws_run.ticks.RealtimeAnswers`) and hands a state to the sink every
    ``state_period_s``: the state at once, the state's side publications (scene, odometry,
    status) one per integration step after it, so no step carries them all. A command is
    fresh while the state it answers is at most ``command_stale_periods`` control periods old
    (simulation time, from the simulator's own record of that state); a control tick without
    a fresh command applies zero rear steer and is counted (``stale_commands``).
    ``driver_timeout_s`` of simulation time without a driver input stops the run, naming the
    maneuver node.
"""

from __future__ import annotations

import ctypes
import gc
import os
import sys
import threading
import time
from collections import deque
from typing import Any, Callable, Mapping, Protocol

from fourws_run.ticks import (FlowWindow, InputLimits, LockstepAnswers, Pacer,
                              RealtimeAnswers, Rejections, Tick, TickEngine)
from fourws_sim.drivers import DriverCommand

CLOCK_MODES = ("lockstep", "realtime")
#: A lockstep tick (or a tick held for the recorder) waiting this long reports what it waits
#: for in a status message, s of wall time.
LONG_WAIT_S = 1.0
#: GIL switch interval while the realtime thread runs, s (Python's default 5 ms would let a
#: subscriber callback delay a step by up to 5 ms).
SWITCH_INTERVAL_S = 1e-4
#: Who answers what, for the messages that name a silent node.
DRIVER_INPUT = "driver input"
REAR_STEER_COMMAND = "rear-steer command"


class TickSink(Protocol):
    """What a clock needs of the simulator node."""

    def publish_state(self, tick: Tick) -> bool:
        """Publish the state of ``tick`` (the answers' critical path starts there); False if
        it could not be encoded (the sink has ended the run)."""

    def side_publications(self, tick: Tick) -> list[Callable[[], bool]]:
        """What else ``tick`` publishes (the scene, odometry, IMU and status when due, ...),
        in order, each one call; a call returns False when the sink ended the run
        (an end time reached), and nothing after it is called."""

    def report_wait(self, t: float) -> None:
        """Publish a status now: a tick has waited :data:`LONG_WAIT_S`."""

    def end(self, reason: str, failed: bool) -> None:
        """The simulation ended (``failed``: the run failed for ``reason``)."""

    def silent_node(self, missing: str) -> str:
        """The node whose answer ``missing`` (:data:`DRIVER_INPUT`, ...) did not come, named
        for a reader ("the controller node (fourws_controller)")."""


def publish_tick(sink: TickSink, tick: Tick) -> bool:
    """Publish ``tick`` whole, now: its state, then its side publications; False if the sink
    ended the run."""
    if not sink.publish_state(tick):
        return False
    return all(publish() for publish in sink.side_publications(tick))


def _silent_nodes(sink: TickSink, missing: str) -> str:
    """The nodes whose answers ``missing`` names ("driver input and rear-steer command": both,
    "the maneuver node (...) and the controller node (...)"): a node that stopped can hold up
    another's answer (seen: a maneuver's driver input 2.6 s late while the controller was
    stopped, most likely its publish waiting on the stopped reader's shared-memory port), so
    the verdict names every answer that did not come, not only the first."""
    nodes = [sink.silent_node(kind) for kind in (DRIVER_INPUT, REAR_STEER_COMMAND)
             if kind in missing]
    return " and ".join(nodes) if nodes else sink.silent_node(REAR_STEER_COMMAND)


class Clock:
    """What both modes share: the engine, the input limits, the counters of the statuses."""

    mode = ""

    def __init__(self, engine: TickEngine, sink: TickSink) -> None:
        self.engine = engine
        self.sink = sink
        self.paused = True
        self.started = False
        #: Control ticks run with zero rear steer because no fresh command was there.
        self.stale_commands = 0
        #: The last control tick ran without a fresh command.
        self.command_timed_out = False
        #: Control ticks run.
        self.ticks = 0
        self.pacer = Pacer(engine.sim.dt_s)
        self._wall_start: float | None = None
        self._wall_stop: float | None = None

    def _started_now(self) -> None:
        if self._wall_start is None:
            self._wall_start = time.monotonic()

    @property
    def wall_time_s(self) -> float:
        """Wall time since the simulation started running (to its end once it ended), s."""
        if self._wall_start is None:
            return 0.0
        end = self._wall_stop if self._wall_stop is not None else time.monotonic()
        return end - self._wall_start

    @property
    def book(self) -> LockstepAnswers | RealtimeAnswers:
        """The answer book (accepted counts, refusals)."""
        raise NotImplementedError

    def pause(self) -> None:
        """Stop advancing (the run ended, or /fourws/pause)."""
        self.paused = True
        if self._wall_start is not None and self._wall_stop is None:
            self._wall_stop = time.monotonic()

    @property
    def rejections(self) -> Rejections:
        """Inputs refused so far."""
        return self.book.rejections

    def waiting_for(self) -> str:
        """What the simulation waits for ('' when it does not)."""
        return ""

    def summary(self) -> str:
        """One log line on the run's timing ('' if nothing ran)."""
        return ""


class LockstepClock(Clock):
    """Lockstep (module docstring).

    Parameters
    ----------
    engine : TickEngine
    sink : TickSink
    limits : InputLimits
    window : FlowWindow
        The recorder flow control (window 0: none).
    sent_counts : callable
        The messages the run has sent per recorded topic that the simulator knows of (its own
        and the answers it accepted).
    answer_timeout_s : callable
        The current wall-time limit on a tick's answers, s (a live parameter).
    recorder_timeout_s : callable
        The current wall-time limit on a tick held for the recorder, s (a live parameter;
        a separate limit, since a recorder behind on a slow disk is not a node that stopped
        answering).
    monotonic : callable
        Wall clock, s (tests pass their own).
    """

    mode = "lockstep"

    def __init__(self, engine: TickEngine, sink: TickSink, limits: InputLimits,
                 window: FlowWindow, sent_counts: Callable[[], Mapping[str, int]],
                 answer_timeout_s: Callable[[], float],
                 recorder_timeout_s: Callable[[], float],
                 monotonic: Callable[[], float] = time.monotonic) -> None:
        super().__init__(engine, sink)
        self.answers = LockstepAnswers(limits)
        self.window = window
        self._sent_counts = sent_counts
        self._timeout = answer_timeout_s
        self._recorder_timeout = recorder_timeout_s
        self._now = monotonic
        self.held: Tick | None = None  # a tick held back by flow control
        self._held_since = 0.0
        self._await_since = 0.0
        self._reported_wait = False
        self._sent_at = 0.0
        #: Wall time the simulator waited for the recorder, for the answers, and worked, s.
        self.held_s = 0.0
        self.answer_wait_s = 0.0
        self.tick_work_s = 0.0

    @property
    def book(self) -> LockstepAnswers:
        return self.answers

    # -- the tick sequence
    def start(self) -> None:
        """Publish the first tick (once)."""
        if self.started:
            return
        self.started = True
        self._started_now()
        self._publish(self.engine.tick)

    def resume(self) -> None:
        """Un-paused: run on (answers that came while paused count now)."""
        self.paused = False
        if not self.started:
            self.start()
        elif self.answers.complete:
            self._advance()

    def offer_driver(self, stamp_ns: int, cmd: DriverCommand) -> None:
        """A driver input arrived."""
        if self.answers.offer_driver(stamp_ns, cmd) and self.answers.complete:
            self._advance()

    def offer_command(self, step: int, stamp_ns: int, angle_rad: float) -> None:
        """A rear-steer command arrived."""
        if self.answers.offer_command(step, stamp_ns, angle_rad) and self.answers.complete:
            self._advance()

    def is_awaited(self, stamp_ns: int) -> bool:
        """Whether ``stamp_ns`` is the state the simulation waits on (a maneuver's 'done'
        counts only for it)."""
        tick = self.answers.awaited
        return tick is not None and tick.stamp_ns == stamp_ns

    def recorder_stored(self, stored: Mapping[str, int]) -> None:
        """The recorder's stored counts: a held tick may go."""
        self.window.update(stored)
        if self.held is not None and not self.holding_back():
            self._send(self.held)

    def holding_back(self) -> str:
        """The recorded topic the recorder is too far behind on ('' if none)."""
        return self.window.holding_back(self._sent_counts())

    def _publish(self, tick: Tick) -> None:
        if self.holding_back():
            self.held = tick  # the recorder's next status releases it
            self._held_since = self._now()
            self._reported_wait = False
            return
        self._send(tick)

    def _send(self, tick: Tick) -> None:
        if self.held is not None:
            self.held_s += self._now() - self._held_since
        self.held = None
        self.answers.expect(tick)
        self._await_since = self._now()
        self._reported_wait = False
        self._sent_at = time.perf_counter()
        if not publish_tick(self.sink, tick):
            self.answers.awaited = None

    def _advance(self) -> None:
        if self.paused or self.answers.awaited is None or self.answers.driver is None:
            return
        now = time.perf_counter()
        self.answer_wait_s += now - self._sent_at
        driver, rear, timed_out = self.answers.close()
        self.command_timed_out = timed_out
        self.stale_commands += timed_out
        self.ticks += 1
        if self.engine.advance(driver, rear):
            self._publish(self.engine.tick)
        else:
            self.sink.end(self.engine.diverged, True)
        self.tick_work_s += time.perf_counter() - now

    # -- the passing of wall time
    def housekeeping(self) -> None:
        """Report a long wait; stop the run once a tick's answers are later than the answer
        timeout (a node has stopped working: lockstep never runs a tick on other inputs), or
        once a tick has been held for the recorder longer than the recorder timeout."""
        tick = self.answers.awaited or self.held
        if tick is None or self.paused:
            return
        since = self._await_since if self.held is None else self._held_since
        if not self._reported_wait and self._now() - since > LONG_WAIT_S:
            self._reported_wait = True
            self.sink.report_wait(tick.t)
        limit = self._recorder_timeout()
        if self.held is not None and self._now() - self._held_since > limit:
            self.sink.end(f"the recorder did not catch up within {limit:g} s (wall "
                          f"time) at t = {self.held.t:.2f} s: it is behind on "
                          f"{self.holding_back()} by more than the flow-control window "
                          "(stopped or starved?)", True)
            return
        awaited = self.answers.awaited
        if awaited is not None and self._now() - self._await_since > self._timeout():
            missing = self.answers.waiting_for
            silent = _silent_nodes(self.sink, missing)
            self.sink.end(f"no {missing} for the state at t = {awaited.t:.2f} s within "
                          f"{self._timeout():g} s (wall time); {silent} did not answer", True)

    def waiting_for(self) -> str:
        if self.held is not None:
            return f"recorder ({self.holding_back()})"
        missing = self.answers.waiting_for
        return missing.replace(DRIVER_INPUT, f"{DRIVER_INPUT} (maneuver node)").replace(
            REAR_STEER_COMMAND, f"{REAR_STEER_COMMAND} (controller node)")

    def summary(self) -> str:
        if not self.ticks:
            return ""
        return (f"lockstep: {self.ticks} ticks, mean answer wait "
                f"{self.answer_wait_s / self.ticks * 1e3:.3f} ms, mean own work "
                f"{self.tick_work_s / self.ticks * 1e3:.3f} ms per tick; waited for the "
                f"recorder {self.window.holds} times, {self.held_s:.3f} s in all")


class RealtimeClock(Clock):
    """Realtime (module docstring).

    Parameters
    ----------
    engine : TickEngine
    sink : TickSink
    limits : InputLimits
    state_steps : int
        Integration steps per published state.
    stale_after_s : callable
        The current command freshness limit, s of simulation time (``command_stale_periods``
        control periods; a live parameter).
    driver_timeout_s : callable
        The current driver-input timeout, s of simulation time.
    priority : int
        SCHED_FIFO priority of the integration thread (0: normal scheduling).
    warn : callable
        Where a refused priority is reported.
    """

    mode = "realtime"

    def __init__(self, engine: TickEngine, sink: TickSink, limits: InputLimits, state_steps: int,
                 stale_after_s: Callable[[], float], driver_timeout_s: Callable[[], float],
                 answer_timeout_s: Callable[[], float] = lambda: 60.0, priority: int = 0,
                 warn: Callable[[str], None] = print) -> None:
        super().__init__(engine, sink)
        self.answers = RealtimeAnswers(limits)
        self._answer_timeout = answer_timeout_s
        #: The first state, published and waiting for its answers (None once running).
        self._first: Tick | None = None
        self._first_since = 0.0
        self.state_steps = int(state_steps)
        self._stale_after = stale_after_s
        self._driver_timeout = driver_timeout_s
        self._priority = int(priority)
        self._warn = warn
        self.lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._stop = False

    @property
    def book(self) -> RealtimeAnswers:
        return self.answers

    def start(self) -> None:
        """Publish the first state; the thread starts once it is answered (once)."""
        if self.started:
            return
        self.started = True
        tick = self.engine.tick
        with self.lock:
            self.answers.published(tick)
        self._first, self._first_since = tick, time.monotonic()
        if not publish_tick(self.sink, tick):
            self._first = None

    def _first_answered(self) -> None:
        """The first state has both answers: the wall clock starts."""
        if self._first is None or self.paused:
            return
        if self.answers.driver_time_s < self._first.t \
                or self.answers.rear_state_time_s < self._first.t:
            return
        self._first = None
        self._start_thread()

    def _start_thread(self) -> None:
        if self._thread is not None:
            return
        self._stop = False
        self._thread = threading.Thread(target=self._thread_main, daemon=True,
                                        name="fourws-realtime")
        self._thread.start()

    def resume(self) -> None:
        """Un-paused: the thread runs again (or the first state goes out)."""
        self.paused = False
        if not self.started:
            self.start()
        elif self._first is None:
            self._start_thread()
        else:
            self._first_answered()

    def stop(self) -> None:
        """Stop and join the integration thread (from any other thread)."""
        self._stop = True
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=2.0)
            self._thread = None
            self.started = False

    def pause(self) -> None:
        """Pause (the thread stops)."""
        super().pause()
        self.stop()

    def offer_driver(self, stamp_ns: int, cmd: DriverCommand) -> None:
        """A driver input arrived (held if valid)."""
        with self.lock:
            self.answers.offer_driver(stamp_ns, cmd)
        if self._first is not None:
            self._first_answered()

    def offer_command(self, step: int, stamp_ns: int, angle_rad: float) -> None:
        """A rear-steer command arrived (held if valid)."""
        with self.lock:
            self.answers.offer_command(step, stamp_ns, angle_rad)
        if self._first is not None:
            self._first_answered()

    def is_awaited(self, stamp_ns: int) -> bool:
        """Whether ``stamp_ns`` is a published state's (a maneuver's 'done' must answer one)."""
        return self.answers.was_published(stamp_ns)

    def recorder_stored(self, stored: Mapping[str, int]) -> None:
        """Realtime has no flow control (it cannot wait)."""

    def housekeeping(self) -> None:
        """While the first state waits for its answers: stop the run after the answer timeout,
        naming the node (once running, the thread paces itself)."""
        first = self._first
        if first is None or self.paused:
            return
        if time.monotonic() - self._first_since > self._answer_timeout():
            missing = self.waiting_for()
            node = _silent_nodes(self.sink, missing)
            self.sink.end(f"no {missing.split(' (')[0]} for the first state within "
                          f"{self._answer_timeout():g} s (wall time); {node} did not answer",
                          True)

    def waiting_for(self) -> str:
        if self._first is not None:
            if self.answers.driver_time_s < self._first.t:
                return f"{DRIVER_INPUT} (maneuver node)"
            if self.answers.rear_state_time_s < self._first.t:
                return f"{REAR_STEER_COMMAND} (controller node)"
            return ""
        age = self.engine.sim.time_s - self.answers.driver_time_s
        return f"{DRIVER_INPUT} (maneuver node)" if age > self._driver_timeout() else ""

    def summary(self) -> str:
        pacer, steps = self.pacer, self.engine.sim.step_count
        if not steps:
            return ""
        return (f"realtime: {steps} steps, step lateness p99 {pacer.percentile(99.0) * 1e3:.3f}"
                f" ms, max {pacer.max_lateness_s * 1e3:.3f} ms at t = "
                f"{pacer.max_lateness_at_s:.3f} s, {pacer.overruns} overruns"
                + (" (t/late ms: " + ", ".join(f"{t:.3f}/{late * 1e3:.2f}"
                                               for t, late in pacer.first_overruns) + ")"
                   if pacer.first_overruns else ""))

    # -- the integration thread
    def _thread_main(self) -> None:
        # Objects alive now (modules, numba, rclpy) leave the collector's generations, so a
        # full collection during the run has little to scan (it holds the GIL meanwhile).
        gc.collect()
        gc.freeze()
        make_thread_realtime(self._priority, self._warn)
        old_interval = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_INTERVAL_S)
        try:
            self._run()
        finally:
            sys.setswitchinterval(old_interval)

    def _run(self) -> None:
        # A state's side publications (scene, odometry, IMU, status) are spread over
        # the integration steps that follow it, one per step, instead of all going out with
        # the state: together they took about 1 ms at a 10 Hz status with a 50 Hz scene
        # (measured: state 0.17 ms, transforms and markers 0.34 ms, odometry and IMU 0.10
        # ms, status 0.42 ms), a whole integration step, so with any hiccup on top the next
        # step started late (1.3 overruns per second of a 60 s run with the scene, 0.2
        # without). Every one of them still goes out before the next state, and before
        # the thread ends (the final status is published after it has).
        pending: deque[Callable[[], bool]] = deque()
        try:
            self._integrate(pending)
        finally:
            with self.lock:  # (never taken by a caller of stop(), which waits for this)
                while pending:
                    if not pending.popleft()():
                        pending.clear()

    def _integrate(self, pending: deque[Callable[[], bool]]) -> None:
        engine, book, pacer = self.engine, self.answers, self.pacer
        sim = engine.sim
        n_control = engine.n_control
        self._started_now()
        pacer.start(sim.time_s)
        k = 0
        rear = 0.0
        driver = book.driver

        def flush() -> bool:
            while pending:
                if not pending.popleft()():
                    pending.clear()
                    return False
            return True

        while not self.paused and not self._stop:
            pacer.wait(sim.time_s)
            with self.lock:
                if k % n_control == 0:
                    t = sim.time_s
                    stale_s = self._stale_after()
                    rear, timed_out = book.rear_at(t, stale_s)
                    # the controller's first command may come one freshness limit after the
                    # run's first state
                    timed_out = timed_out and (book.commands_accepted > 0 or t > stale_s)
                    self.stale_commands += timed_out
                    self.command_timed_out = timed_out
                    self.ticks += 1
                    driver = book.driver
                    quiet = t - max(book.driver_time_s, 0.0)
                    if quiet > self._driver_timeout():
                        if not flush():
                            return
                        self.sink.end(f"no driver input for {quiet:.2f} s of simulation time "
                                      f"at t = {t:.2f} s: {self.sink.silent_node(DRIVER_INPUT)}"
                                      " stopped answering", True)
                        return
                if not engine.advance(driver, rear, n_steps=1):
                    if flush():
                        self.sink.end(engine.diverged, True)
                    return
                k += 1
                if k % self.state_steps == 0:
                    if not flush():  # what the steps since the last state had no turn for
                        return
                    tick = engine.tick
                    book.published(tick)
                    if not self.sink.publish_state(tick):
                        return
                    pending.extend(self.sink.side_publications(tick))
                elif pending and not pending.popleft()():
                    pending.clear()
                    return


def make_clock(mode: str, **kwargs: Any) -> LockstepClock | RealtimeClock:
    """The clock of ``mode`` (:data:`CLOCK_MODES`) built with its keyword arguments.

    Raises
    ------
    ValueError
        Unknown mode.
    """
    classes = {"lockstep": LockstepClock, "realtime": RealtimeClock}
    if mode not in classes:
        raise ValueError(f"clock mode must be one of {', '.join(CLOCK_MODES)}, got {mode!r}")
    return classes[mode](**kwargs)


def make_thread_realtime(priority: int, warn: Callable[[str], None]) -> None:
    """SCHED_FIFO ``priority`` for the calling thread (0: keep normal scheduling) and 1 ns
    timer slack (sleep wakes on time). Speed only: a refused priority is reported through
    ``warn`` and the run goes on."""
    pr_set_timerslack = 29
    try:
        ctypes.CDLL(None).prctl(pr_set_timerslack, 1, 0, 0, 0)
    except (OSError, AttributeError):
        pass
    if priority <= 0:
        return
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (PermissionError, OSError) as exc:
        warn(f"realtime priority {priority} not granted ({exc}); running with normal "
             "scheduling, expect more step lateness under load")


__all__ = ["CLOCK_MODES", "Clock", "DRIVER_INPUT", "LONG_WAIT_S", "LockstepClock",
           "REAR_STEER_COMMAND", "RealtimeClock", "SWITCH_INTERVAL_S", "TickSink",
           "make_clock", "make_thread_realtime"]
