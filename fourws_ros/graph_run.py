# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""One run through the real node graph, accounted for: what ``fourws run`` does.

:func:`run_graph` takes a :class:`~fourws_run.config.RunConfig`, starts the node processes on
a ROS domain of its own (:mod:`fourws_ros.domains`, :mod:`fourws_ros.processes`), publishes the
run description, waits until the graph is complete, starts the simulation and follows it. The
run ends when the simulator sends its final status (the maneuver is done, the simulation
diverged, or a node it depends on stopped answering). Then every node delivers what it
published and exits; the recorder closes the bag once it holds every message the run's
nodes published, by their own counts and by their publishers' sequence numbers
(:mod:`fourws_run.accounting`). The launcher checks the closed bag again
(:func:`fourws_run.bagfile.verify_bag`) and writes the run record (``run.json``,
:class:`fourws_run.record.RunRecord`).

Nothing here rests on timing: a run is ``ok`` only if the recorder's accounting and the bag
agree that nothing is missing. Timeouts only turn a stuck run into a failure that names the
node at fault (the simulator's status says what it waits for).

The launcher's own ROS node (``fourws_launcher``) takes status messages only from the run's
nodes (publisher identity from rclpy message info): a foreign status cannot end a run.
"""

from __future__ import annotations

import shutil
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from fourws_ros import node_params, topics
from fourws_ros.domains import DomainError, domain_for_run, graph_env
from fourws_ros.launcher_node import CLOSE_TIMEOUT_S, CLOSED, STUCK, LauncherNode, RunState
from fourws_ros.processes import (ProcessGroup, describe_exit, last_line, node_command,
                                  ros_args, set_fifo, user_command)
from fourws_ros.runtime import TEARDOWN_BACKSTOP_S, TEARDOWN_TIMEOUT_S
from fourws_ros.startup import wait_for_graph
from fourws_run.bagfile import BagError, read_bag, verify_bag
from fourws_run.codecs import CodecError, parse_rear_steer_command
from fourws_run.config import USER_LAW, RunConfig
from fourws_run.record import Outcome, RunRecord
from fourws_run.verdict import RECORDER_LATE, BagCheck, conclude
from fourws_sim.errors import FourwsError

Role = topics.Role
NODE_NAMES = topics.NODE_NAMES
#: A run whose simulation time has not advanced for this long (wall) is stopped as stalled, s
#: (beyond the simulator's own 60 s wait for a lockstep answer, which names the silent node;
#: this one catches a simulator that cannot report, e.g. a stopped one).
STALL_TIMEOUT_S = 75.0
#: After the simulation ended: how long (wall) the recorder may take to store everything and
#: close the bag. A timeout fails the run; the bag is never closed short silently.
RECORDER_GRACE_S = 90.0
#: A recorder that closed the bag exits within its teardown limit (the node's own, and its
#: backstop); later than this it is stuck and stopped, s.
RECORDER_TEARDOWN_S = TEARDOWN_TIMEOUT_S + TEARDOWN_BACKSTOP_S + 3.0
#: After the simulation ended: how long the nodes may take to deliver and exit, s.
NODE_EXIT_S = 40.0
#: Realtime: simulation time beyond the maneuver's duration after which a run the maneuver
#: did not end fails, s.
REALTIME_OVERRUN_S = 2.0
#: Process name of the live view (``fourws run --live``).
LIVE_VIEW = "fourws_live_view"
#: SCHED_FIFO priority of the answer chain (simulator, maneuver, controller), when permitted,
#: except in a lockstep run with a live view (speed only; the verdict never depends on it: a
#: realtime run whose answers come late says so, as stale commands).
FIFO_PRIORITY = 10


class LaunchError(FourwsError):
    """The run could not be started or did not end well; the message says why."""


class _Interrupt:
    """SIGINT/SIGTERM handler for the launcher: remembers the signal (raising inside rclpy
    callbacks is what made a Ctrl-C a traceback); the run then stops cleanly."""

    def __init__(self) -> None:
        self.count = 0
        self._previous: dict[int, Any] = {}

    def __call__(self, _signum: int, _frame: Any) -> None:
        self.count += 1

    def __enter__(self) -> "_Interrupt":
        for sig in (signal.SIGINT, signal.SIGTERM):
            self._previous[sig] = signal.getsignal(sig)
            signal.signal(sig, self)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)

    @property
    def set(self) -> bool:
        """A signal arrived."""
        return self.count > 0


def prepare_run_dir(out_dir: Path, run_name: str, overwrite: bool) -> Path:
    """Create ``out_dir/run_name``.

    Raises
    ------
    LaunchError
        It exists (and ``overwrite`` is false), or it cannot be created (names the OS reason).
    """
    run_dir = Path(out_dir) / run_name
    try:
        if run_dir.exists():
            if not overwrite:
                raise LaunchError(f"run folder {run_dir} exists already (use --overwrite, or "
                                  "another --out)")
            shutil.rmtree(run_dir)
        run_dir.mkdir(parents=True)
    except OSError as exc:
        raise LaunchError(f"cannot create run folder {run_dir}: "
                          f"{exc.strerror or exc}") from None
    return run_dir


def run_graph(config: RunConfig, out_dir: Path, *, run_name: str | None = None,
              overwrite: bool = False, echo: Callable[[str], None] | None = None,
              replay_driver_from: Path | None = None,
              node_overrides: dict[str, dict[str, Any]] | None = None,
              on_running: Callable[[ProcessGroup], None] | None = None,
              live_port: int | None = None) -> RunRecord:
    """Run ``config`` through the real node graph, recording a bag.

    Parameters
    ----------
    config : RunConfig
        The run (built with :meth:`RunConfig.from_scenario`).
    out_dir : Path
        Parent folder; the run gets ``out_dir/<run_name>/`` with ``bag/``, ``logs/``,
        ``params.yaml`` and ``run.json``.
    run_name : str, optional
        Default ``<scenario>-<law>-<UTC time>``.
    overwrite : bool
        Replace an existing run folder of that name.
    echo : callable, optional
        Progress output (default stderr).
    replay_driver_from : Path, optional
        A bag whose ``/fourws/driver_input`` drives this run instead of the maneuver node
        (replay node in answer mode; the run should be the recorded one, for the speed).
    node_overrides : dict, optional
        Extra parameters per ROS node name (tests, benchmarks).
    on_running : callable, optional
        Called once with the process group when the simulation has started (tests inject
        faults).
    live_port : int, optional
        Serve the run over the Foxglove WebSocket protocol on 127.0.0.1 at this port (the
        live view node beside the run's; its exit never fails the run).

    Returns
    -------
    RunRecord
        Also written to ``run.json``.

    Raises
    ------
    LaunchError
        The run folder cannot be created or the parameters cannot be written.
    """
    echo = echo or (lambda text: print(text, file=sys.stderr, flush=True))
    stamp = time.strftime("%Y%m%d-%H%M%S", time.gmtime())
    run_dir = prepare_run_dir(Path(out_dir), run_name or
                              f"{config.scenario or 'run'}-{config.law}-{stamp}", overwrite)
    bag_path = run_dir / "bag" if config.recorded_topics else None
    params = node_params.node_parameters(config, bag_path, replay_driver_from is not None)
    names = _node_names(config)
    driver_node = config.driver_node  # '' for a user's driver command
    if replay_driver_from is not None:
        driver_node = "replay"
        params[names.maneuver] = {"bag_path": str(replay_driver_from),
                                  "topics": [topics.DRIVER_INPUT], "mode": "answer",
                                  "publish_clock": False}
    for name, extra in (node_overrides or {}).items():
        params.setdefault(name, {}).update(extra)
    try:
        params_file = node_params.write_params_file(run_dir / "params.yaml", params)
    except OSError as exc:
        raise LaunchError(f"cannot write {run_dir / 'params.yaml'}: "
                          f"{exc.strerror or exc}") from None
    record = RunRecord(Outcome.FAILED, "", config.law, run_dir, bag_path,
                       config=config.to_dict())
    state = RunState()
    failure = ""
    with _Interrupt() as interrupt:
        try:
            lease = domain_for_run()
        except DomainError as exc:
            record.reason = str(exc)
            _write_record(record, echo)
            return record
        record.domain_id = lease.domain_id
        if lease.from_user:
            echo(f"  using ROS domain {lease.domain_id} (from ROS_DOMAIN_ID)")
        group = ProcessGroup(run_dir / "logs", graph_env(lease.domain_id), echo)
        ros: LauncherNode | None = None
        try:
            _start_nodes(config, group, params_file, names, driver_node, bag_path is not None)
            if live_port is not None:
                _start_live_view(group, live_port)
            echo(f"fourws run {config.scenario or 'run'} / {config.law}: "
                 f"{len(group.children)} nodes on ROS domain {lease.domain_id} "
                 f"({config.clock_mode}), logs in {run_dir / 'logs'}")
            writers = {Role.SIMULATOR: names.simulator, Role.MANEUVER: names.maneuver,
                       Role.CONTROLLER: names.controller, Role.RECORDER: names.recorder}
            ros = LauncherNode(lease.domain_id, node_params.dumps_config(config.to_dict()),
                               writers, state)
            failure = _drive(config, group, ros, state, interrupt, bag_path is not None, echo,
                             on_running, replay_driver_from is not None)
        except LaunchError as exc:
            failure = str(exc)
        finally:
            failure = _finish(config, group, ros, state, interrupt, failure, bag_path, names,
                              echo)
        record.exit_codes = group.exit_codes()
        if state.t_start:
            record.wall_time_s = max(state.t_end - state.t_start, 0.0)
            record.startup_s = max(state.t_start - group.started_at, 0.0)
        conclude(record, config, state.sim_report(), state.maneuver_report(), interrupt.set,
                 _with_last_words(failure, state), _check_bag(record.bag_path))
        _label_user_law(record, config)
        _write_record(record, echo)
        # the verdict is on disk before the launcher's participant is closed (a close that
        # never ends cannot take it along); the user's own domain is given back for the
        # command's next run (a demo's three), so its participant is destroyed, not kept
        closed = ros.close(keep=lease, destroy=lease.from_user) if ros is not None else CLOSED
        if closed == STUCK:  # the lease is kept with the stuck participant
            echo(f"  note: the launcher's ROS participant did not close within "
                 f"{CLOSE_TIMEOUT_S:.0f} s (a Fast DDS deadlock); domain {lease.domain_id} "
                 "held until this process exits")
        elif closed == CLOSED:
            lease.release()
    return record


@dataclass(frozen=True)
class _Names:
    """ROS node names of the run's roles."""

    simulator: str
    maneuver: str
    controller: str
    recorder: str


def _node_names(config: RunConfig) -> _Names:
    return _Names(NODE_NAMES[Role.SIMULATOR], NODE_NAMES[Role.MANEUVER],
                  config.controller.node_name, NODE_NAMES[Role.RECORDER])


def _start_nodes(config: RunConfig, group: ProcessGroup, params_file: Path, names: _Names,
                 driver_node: str, recorded: bool) -> None:
    """Start the node processes (recorder first, simulator last).

    Raises
    ------
    LaunchError
        A program cannot be started.
    """
    starts = []
    if recorded:
        starts.append((names.recorder, node_command("recorder", params_file)))
    if config.controller.builtin:
        starts.append((names.controller, node_command("controller", params_file,
                                                      node_name=names.controller)))
    else:
        starts.append((names.controller, user_command(config.controller.command)
                       + ros_args(params_file, node_name=names.controller)))
    if driver_node:
        starts.append((names.maneuver, node_command(driver_node, params_file,
                                                    node_name=names.maneuver)))
    else:  # a user's driver (docs/driver-contract.md) in the maneuver's role
        starts.append((names.maneuver, user_command(config.driver)
                       + ros_args(params_file, node_name=names.maneuver)))
    starts.append((names.simulator, node_command("simulator", params_file)))
    for name, cmd in starts:
        try:
            group.start(name, cmd)
        except OSError as exc:
            raise LaunchError(f"cannot start {name} ({' '.join(cmd[:3])}...): "
                              f"{exc.strerror or exc}") from None


def _start_live_view(group: ProcessGroup, port: int) -> None:
    """The live view node (:mod:`fourws_ros.live_view_node`), optional in the group.

    Raises
    ------
    LaunchError
        It cannot be started.
    """
    try:
        group.start(LIVE_VIEW, node_command("live_view", params={"port": int(port)}))
    except OSError as exc:
        raise LaunchError(f"cannot start the live view: {exc.strerror or exc}") from None
    group.optional.add(LIVE_VIEW)
    group.echo(f"  live view: ws://127.0.0.1:{port} (Foxglove: open connection, Foxglove "
               "WebSocket)")


def _write_record(record: RunRecord, echo: Callable[[str], None]) -> None:
    try:
        record.write()
    except OSError as exc:
        echo(f"  cannot write {record.run_dir / 'run.json'}: {exc.strerror or exc}")


def _check_bag(bag_path: Path | None) -> BagCheck | None:
    """The closed bag, checked again (its problems, not an exception)."""
    if bag_path is None:
        return None
    try:
        check = verify_bag(bag_path)
    except BagError as exc:
        return BagCheck(problems=[str(exc)])
    problems = list(check.problems)
    if check.complete is None and not check.problems:
        problems.append("the bag carries no recording accounting")
    return BagCheck(check.counts, check.accounting, problems)


def _with_last_words(failure: str, state: RunState) -> str:
    """A failure naming a node that did not answer, with what that node last said (a
    warning or an error on /rosout: what it was waiting for)."""
    if not failure:
        return failure
    for node, words in state.last_words.items():
        if f"({node})" in failure and "did not answer" in failure:
            return f"{failure}; {node} last said: {words}"
    return failure


def _label_user_law(record: RunRecord, config: RunConfig) -> None:
    """A user's controller names its law in every command: the record takes that name
    (the contract: the run's label is the law the commands name)."""
    if config.controller.builtin or record.law != USER_LAW or record.bag_path is None:
        return
    try:
        messages, _check = read_bag(record.bag_path)
    except (BagError, OSError):
        return
    for raw in messages:
        if raw.topic == topics.REAR_STEER_CMD:
            try:
                law = parse_rear_steer_command(raw.data)["law"]
            except CodecError:
                return
            if law:
                record.law = str(law)
                record.config = {**record.config, "law": str(law)}
            return


def _drive(config: RunConfig, group: ProcessGroup, ros: LauncherNode, state: RunState,
           interrupt: _Interrupt, recorded: bool, echo: Callable[[str], None],
           on_running: Callable[[ProcessGroup], None] | None, replay: bool = False) -> str:
    """Wait for the graph, start the simulation, follow it to its final status; '' or the
    failure."""
    why = wait_for_graph(config, group, ros, lambda: interrupt.set, recorded, replay)
    if why:
        return why
    # the answer chain: in lockstep it sets the pace, in realtime its answers must come
    # within the command freshness limit (the realtime thread raises itself higher). Not for
    # a lockstep run that someone watches live: its chain answering flat out at SCHED_FIFO
    # took both cores of a two-core machine from the live view and its client (3 % of the
    # frames reached the client in a test run; 80-100 % without FIFO beside a CPU hog); the
    # watcher gets the CPU, the run goes slower (2.3x real time instead of 3.8-4.7x here)
    if not (config.lockstep and group.has(LIVE_VIEW)):
        chain = [NODE_NAMES[Role.SIMULATOR], NODE_NAMES[Role.MANEUVER],
                 config.controller.node_name]
        granted = [set_fifo(c.proc.pid, FIFO_PRIORITY) for c in group.children
                   if c.name in chain and c.proc is not None]
        if not all(granted):
            echo("  (real-time priority not permitted: expect more latency under load)")
    if not ros.start_simulation():
        return "the simulator did not answer the start request"
    echo(f"  graph up after {time.monotonic() - group.started_at:.1f} s; running "
         f"{config.maneuver.name} ({config.maneuver.duration_s} s simulated)")
    echo(f"  start-up (s from launch): {group.startup_breakdown()}")
    state.last_advance = state.t_start = time.monotonic()
    reported = -1
    called = False
    tty = sys.stderr.isatty()
    duration = config.maneuver.duration_s
    while state.sim_final is None:
        ros.spin(0.05)
        if interrupt.set:
            return "interrupted (Ctrl-C / SIGTERM)"
        dead = group.failed()
        if dead is not None:
            ros.spin(0.2)  # the simulator's final status may be on its way
            if state.sim_final is None:
                return describe_exit(dead)
            break
        sim_proc = group.child(NODE_NAMES[Role.SIMULATOR])
        if sim_proc.proc is not None and not sim_proc.alive():
            grace = time.monotonic() + 2.0  # its last messages may still be on their way
            while state.sim_final is None and time.monotonic() < grace:
                ros.spin(0.05)
            if state.sim_final is None:
                # the simulator ended by itself (its final status was sent) but the status
                # never reached this process: it was stopped or starved while the
                # simulator waited for its acknowledgement. The bag's own check follows.
                return (f"the simulator exited (code {sim_proc.exit_code()}) but its final "
                        "status never reached the launcher (fourws run was stopped or "
                        "starved meanwhile); the outcome is the bag's alone")
            break
        now = time.monotonic()
        if now - state.last_advance > STALL_TIMEOUT_S:
            waiting = state.sim.waiting_for if state.sim is not None else ""
            stopped = group.stopped()
            # the simulator's own log says what it waits for, also where its status (or
            # rosout) cannot reach this process
            said = last_line(sim_proc.log_tail())
            return (f"simulation stalled at t = {state.sim_time_s:.2f} s (no progress for "
                    f"{STALL_TIMEOUT_S:.0f} s)"
                    + (f"; node {', '.join(stopped)} is stopped (SIGSTOP)" if stopped else "")
                    + (f"; the simulator waits for: {waiting}" if waiting else "")
                    + (f"; its log's last line: {said}" if said else ""))
        if not config.lockstep and state.sim_time_s > duration + REALTIME_OVERRUN_S:
            return (f"the maneuver node did not end the run (t = {state.sim_time_s:.2f} s, "
                    f"maneuver duration {duration} s)")
        if on_running is not None and not called and state.sim_time_s > 0.0:
            called = True
            on_running(group)
        # the share of the planned duration simulated (the maneuver's own progress comes
        # in its statuses, every 0.1 s of simulation time, and may lag the clock)
        progress = min(state.sim_time_s / duration, 1.0) if duration > 0 else 0.0
        decile = int(progress * 10)
        if decile != reported:
            reported = decile
            phase = state.maneuver.phase if state.maneuver is not None else "-"
            line = f"  [{progress * 100:5.1f} %] t = {state.sim_time_s:6.2f} s  phase {phase}"
            if tty:
                print("\r" + line, end="", file=sys.stderr, flush=True)
            else:
                echo(line)
    if tty:
        print(file=sys.stderr)
    dead = group.failed()
    if dead is not None and dead.exit_code() is not None and dead.exit_code() < 0:
        # a node was killed: the simulator may have ended the run first (a peer left), but
        # the kill is the cause
        return describe_exit(dead)
    stopped = group.stopped()
    stop = state.sim_final.stop_reason if state.sim_final is not None else ""
    if stopped and stop:
        # a stopped node is the cause of a missing answer, and can hold up another node's
        # (fourws_run.clock_modes._silent_nodes)
        return f"node {', '.join(stopped)} is stopped (SIGSTOP); then: {stop}"
    return ""


def _wait_recorder(group: ProcessGroup, rec: str, state: RunState,
                   poll: Callable[[float], None], echo: Callable[[str], None],
                   bag_path: Path | None = None) -> list[str]:
    """Wait up to :data:`RECORDER_GRACE_S` for the recorder to close the bag and exit; a
    recorder that closed the bag (its status said so, or the bag's ``metadata.yaml``, written
    at the close, is on disk) but has not exited :data:`RECORDER_TEARDOWN_S` later is stuck
    in its ROS teardown, and one that is stopped cannot exit: either is stopped, not a failure
    (the verdict reads the bag from disk). Returns ``[rec]`` if it neither exited nor closed
    the bag in time, or was stopped before it closed it."""
    deadline = time.monotonic() + RECORDER_GRACE_S
    closed_at = None
    recorder = group.child(rec)
    while recorder.alive():
        now = time.monotonic()
        if closed_at is None and ((state.recorder is not None and state.recorder.closed)
                                  or (bag_path is not None
                                      and (bag_path / "metadata.yaml").is_file())):
            closed_at = now
        stopped = recorder.stopped()
        if closed_at is not None and (stopped or now - closed_at > RECORDER_TEARDOWN_S):
            echo(f"  {rec} closed the bag but "
                 + ("is stopped (SIGSTOP)" if stopped else
                    f"did not exit within {RECORDER_TEARDOWN_S:.0f} s (stuck in its ROS "
                    "teardown)") + "; stopping it")
            group.stop([rec], grace_s=1.0)
            return []
        if now > deadline or (closed_at is None and stopped):
            return [rec]  # (a stopped process cannot close the bag by itself)
        poll(0.05)
    return []


def _finish(config: RunConfig, group: ProcessGroup, ros: LauncherNode | None,
            state: RunState, interrupt: _Interrupt, failure: str, bag_path: Path | None,
            names: _Names, echo: Callable[[str], None]) -> str:
    """End the run: let the nodes deliver and the recorder close when the simulation ended,
    stop them otherwise; returns the failure (the recorder's problem added if it could not
    close the bag complete)."""
    sim, man, ctrl, rec = names.simulator, names.maneuver, names.controller, names.recorder
    state.t_end = state.t_end or time.monotonic()

    def poll(seconds: float) -> None:
        if ros is not None:
            ros.spin(seconds)
        else:
            time.sleep(seconds)

    try:
        if not failure and state.sim_final is not None:
            # the simulation ended: the simulator, the maneuver and a built-in controller
            # deliver what they published and exit on their own, and the recorder closes the
            # bag once it holds everything
            # a user's driver, like a user's controller, may never exit by itself
            left = group.wait_exit([sim, man] if config.driver_node else [sim], NODE_EXIT_S,
                                   poll)
            if left:
                echo(f"  {', '.join(left)} did not exit after the run; stopping")
                group.stop(left)
            # the recorder can only close a complete bag once the maneuver's final counts
            # are in; without them (a stopped or dead maneuver node) it is stopped below and
            # closes the bag with what it has
            if bag_path is not None and group.has(rec) and (
                    state.maneuver_end is not None or not config.driver_node):
                left = _wait_recorder(group, rec, state, poll, echo, bag_path)
                if left:
                    detail = (state.recorder.detail if state.recorder is not None
                              else "no recorder status")
                    failure = (f"{RECORDER_LATE} {RECORDER_GRACE_S:.0f} s after the "
                               f"simulation ended ({detail})"
                               if not group.child(rec).stopped() else
                               f"the recorder was stopped (SIGSTOP) before it closed the bag "
                               f"({detail})")
            # the controller is stopped once the recorder has its messages (a user's own may
            # never exit by itself)
            if config.controller.builtin:
                group.wait_exit([ctrl], 5.0, poll)
            group.stop([ctrl] if config.driver_node else [ctrl, man])
        else:
            # stopped early: the nodes publish their final counts and deliver on SIGINT; the
            # recorder drains and closes the bag with what it has
            group.stop([sim, man, ctrl])
        if group.has(rec):
            group.stop([rec], grace_s=RECORDER_GRACE_S)
        if group.has(LIVE_VIEW):
            group.stop([LIVE_VIEW])
    except BaseException:
        group.kill_all()
        raise
    if interrupt.count > 1:
        echo("  (more signals arrived while stopping; the nodes were stopped in order so the "
             "bag is closed)")
    return failure


__all__ = ["LaunchError", "NODE_EXIT_S", "RECORDER_GRACE_S", "STALL_TIMEOUT_S",
           "prepare_run_dir", "run_graph"]
