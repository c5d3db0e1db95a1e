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

import os
import shutil
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import String
from std_srvs.srv import SetBool

from fourws_ros import node_params, topics
from fourws_ros.domains import DomainError, domain_for_run, graph_env
from fourws_ros.identity import PublisherNames, drain
from fourws_ros.processes import (ProcessGroup, describe_exit, node_command, ros_args,
                                  set_fifo, user_command)
from fourws_run.accounting import RunAccount
from fourws_run.bagfile import BagError, verify_bag
from fourws_run.config import RunConfig
from fourws_run.record import Outcome, RunRecord
from fourws_run.ticks import NOT_AFTER_PREVIOUS, SECOND_ANSWER, SKIPS_STATES
from fourws_sim.errors import FourwsError

Role = topics.Role
NODE_NAMES = topics.NODE_NAMES
#: Time allowed for every node to come up and discover the others, s.
STARTUP_TIMEOUT_S = 60.0
#: A run whose simulation time has not advanced for this long (wall) is stopped as stalled, s
#: (beyond the simulator's own 60 s wait for a lockstep answer, which names the silent node;
#: this one catches a simulator that cannot report, e.g. a stopped one).
STALL_TIMEOUT_S = 75.0
#: After the simulation ended: how long (wall) the recorder may take to store everything and
#: close the bag. A timeout fails the run; the bag is never closed short silently.
RECORDER_GRACE_S = 90.0
#: After the simulation ended: how long the nodes may take to deliver and exit, s.
NODE_EXIT_S = 40.0
#: Realtime: simulation time beyond the maneuver's duration after which a run the maneuver
#: did not end fails, s.
REALTIME_OVERRUN_S = 2.0
#: SCHED_FIFO priority of the lockstep answer chain (simulator, maneuver, controller) and of
#: the realtime simulator, when permitted (speed only; correctness never depends on it).
FIFO_PRIORITY = 10


class LaunchError(FourwsError):
    """The run could not be started or did not end well; the message says why."""


@dataclass
class _RunState:
    """What the launcher knows of the running graph (from the run's own nodes only)."""

    sim: Any = None
    sim_final: Any = None
    maneuver: Any = None
    maneuver_end: Any = None
    recorder: Any = None
    events: list[str] = field(default_factory=list)
    foreign: int = 0
    last_advance: float = 0.0
    sim_time_s: float = 0.0
    t_start: float = 0.0
    t_end: float = 0.0


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


class _LauncherNode:
    """The launcher's ROS side: run description, status subscriptions, the pause service."""

    def __init__(self, domain_id: int, config_json: str, writers: dict[Role, str],
                 state: _RunState) -> None:
        # the domain goes to rclpy.init; the process environment keeps the user's
        # ROS_DOMAIN_ID (a later run in this process must see what the user set, not ours)
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        for key in ("FASTDDS_DEFAULT_PROFILES_FILE",):
            value = graph_env(domain_id).get(key)
            if value and not os.environ.get(key):
                os.environ[key] = value
        self.context = Context()
        rclpy.init(args=[], context=self.context, domain_id=domain_id,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node(NODE_NAMES[Role.LAUNCHER], context=self.context)
        # message info (publisher identity) needs the single-threaded executor
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.state = state
        self.writers = writers
        self.names = PublisherNames(self.node)
        self.config_pub = self.node.create_publisher(String, topics.RUN_CONFIG,
                                                     topics.LATCHED_QOS)
        self.config_pub.publish(String(data=config_json))
        for topic, handler in ((topics.MANEUVER_STATUS, self._on_maneuver),
                               (topics.SIM_STATUS, self._on_sim),
                               (topics.RECORDER_STATUS, self._on_recorder)):
            self._subscribe(topic, handler)
        self.pause = self.node.create_client(SetBool, topics.SRV_PAUSE)

    def _subscribe(self, topic: str, handler: Callable[[Any, Any], None]) -> None:
        """Subscribe ``handler(msg, info)``, taking every queued message per wake-up (a
        foreign node flooding a status topic cannot push the run's own messages out)."""
        msg_type = topics.message_class(topic)
        holder: list[Any] = []

        def callback(msg: Any, info: Any) -> None:
            handler(msg, info)
            drain(holder[0], msg_type, False, handler)

        holder.append(self.node.create_subscription(msg_type, topic, callback,
                                                    topics.STATUS_QOS))

    def spin(self, seconds: float) -> None:
        """Run callbacks for up to ``seconds``."""
        self.names.refresh(topics.MANEUVER_STATUS, topics.SIM_STATUS, topics.RECORDER_STATUS)
        self.executor.spin_once(timeout_sec=seconds)

    def _from(self, topic: str, info: Any, role: Role) -> bool:
        ok = self.names.of(topic, info) == self.writers[role]
        if not ok:
            self.state.foreign += 1
        return ok

    def _on_maneuver(self, msg: Any, info: Any) -> None:
        if not self._from(topics.MANEUVER_STATUS, info, Role.MANEUVER):
            return
        self.state.maneuver = msg
        if msg.event:
            self.state.events.append(msg.event)
        if msg.done:
            self.state.maneuver_end = msg

    def _on_sim(self, msg: Any, info: Any) -> None:
        if not self._from(topics.SIM_STATUS, info, Role.SIMULATOR):
            return
        state = self.state
        if msg.sim_time_s > state.sim_time_s:
            state.last_advance = time.monotonic()
        state.sim_time_s = max(state.sim_time_s, float(msg.sim_time_s))
        state.sim = msg
        if msg.final:
            state.sim_final = msg
            state.t_end = state.t_end or time.monotonic()

    def _on_recorder(self, msg: Any, info: Any) -> None:
        if self._from(topics.RECORDER_STATUS, info, Role.RECORDER):
            self.state.recorder = msg

    def has_endpoint(self, topic: str, kind: str, node_name: str) -> bool:
        """Whether ``node_name`` publishes (``kind`` "pub") or subscribes ``topic``."""
        infos = (self.node.get_publishers_info_by_topic(topic) if kind == "pub"
                 else self.node.get_subscriptions_info_by_topic(topic))
        return any(i.node_name == node_name for i in infos)

    def start_simulation(self) -> bool:
        """Un-pause the simulator; False if it did not answer."""
        future = self.pause.call_async(SetBool.Request(data=False))
        self.executor.spin_until_future_complete(future, timeout_sec=10.0)
        return future.done()

    def close(self) -> None:
        """Destroy the node and its context."""
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.context.try_shutdown()


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
              on_running: Callable[[ProcessGroup], None] | None = None) -> RunRecord:
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
    params = node_params.node_parameters(config, bag_path)
    sim_name, man_name = NODE_NAMES[Role.SIMULATOR], NODE_NAMES[Role.MANEUVER]
    ctrl_name, rec_name = config.controller.node_name, NODE_NAMES[Role.RECORDER]
    driver_node = "maneuver"
    if replay_driver_from is not None:
        driver_node = "replay"
        params[man_name] = {"bag_path": str(replay_driver_from),
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
    state = _RunState()
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
        ros: _LauncherNode | None = None
        try:
            starts = []
            if bag_path is not None:
                starts.append((rec_name, node_command("recorder", params_file)))
            if config.controller.builtin:
                starts.append((ctrl_name, node_command("controller", params_file,
                                                       node_name=ctrl_name)))
            else:
                starts.append((ctrl_name, user_command(config.controller.command)
                               + ros_args(params_file, node_name=ctrl_name)))
            starts.append((man_name, node_command(driver_node, params_file,
                                                  node_name=man_name)))
            starts.append((sim_name, node_command("simulator", params_file)))
            for name, cmd in starts:
                try:
                    group.start(name, cmd)
                except OSError as exc:
                    raise LaunchError(f"cannot start {name} ({' '.join(cmd[:3])}...): "
                                      f"{exc.strerror or exc}") from None
            echo(f"fourws run {config.scenario or 'run'} / {config.law}: {len(starts)} nodes "
                 f"on ROS domain {lease.domain_id} ({config.clock_mode}), logs in "
                 f"{run_dir / 'logs'}")
            writers = {Role.SIMULATOR: sim_name, Role.MANEUVER: man_name,
                       Role.CONTROLLER: ctrl_name, Role.RECORDER: rec_name}
            ros = _LauncherNode(lease.domain_id, node_params.dumps_config(config.to_dict()),
                                writers, state)
            failure = _drive(config, group, ros, state, interrupt, bag_path is not None, echo,
                             on_running)
        except LaunchError as exc:
            failure = str(exc)
        finally:
            failure = _finish(config, group, ros, state, interrupt, failure, bag_path,
                              (sim_name, man_name, ctrl_name, rec_name), echo)
            if ros is not None:
                ros.close()
            lease.release()
        record.exit_codes = group.exit_codes()
    _conclude(record, config, state, interrupt, failure)
    _write_record(record, echo)
    return record


def _write_record(record: RunRecord, echo: Callable[[str], None]) -> None:
    try:
        record.write()
    except OSError as exc:
        echo(f"  cannot write {record.run_dir / 'run.json'}: {exc.strerror or exc}")


def _wait(condition: Callable[[], bool], timeout_s: float, ros: _LauncherNode,
          interrupt: _Interrupt, group: ProcessGroup) -> str:
    """Spin until ``condition()``; '' or why not (timeout, signal, a node failed)."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if interrupt.set:
            return "interrupted (Ctrl-C / SIGTERM)"
        dead = group.failed()
        if dead is not None:
            return describe_exit(dead)
        if time.monotonic() > deadline:
            return "timeout"
        ros.spin(0.05)
    return ""


def _drive(config: RunConfig, group: ProcessGroup, ros: _LauncherNode, state: _RunState,
           interrupt: _Interrupt, recorded: bool, echo: Callable[[str], None],
           on_running: Callable[[ProcessGroup], None] | None) -> str:
    """Wait for the graph, start the simulation, follow it to its final status; '' or the
    failure."""
    expected = node_params.expected_endpoints(config, recorded)
    if recorded:
        expected.append((topics.RUN_CONFIG, "sub", NODE_NAMES[Role.RECORDER]))

    def missing() -> list[tuple[str, str, str]]:
        return [e for e in expected if not ros.has_endpoint(*e)]

    why = _wait(lambda: not missing(), STARTUP_TIMEOUT_S, ros, interrupt, group)
    if why == "timeout":
        what = ", ".join(f"{n} {'publishing' if k == 'pub' else 'subscribing to'} {t}"
                         for t, k, n in missing())
        return f"graph incomplete after {STARTUP_TIMEOUT_S:.0f} s; missing: {what}"
    if why:
        return why
    why = _wait(ros.pause.service_is_ready, STARTUP_TIMEOUT_S, ros, interrupt, group)
    if why:
        return ("the simulator's /fourws/pause service did not appear" if why == "timeout"
                else why)
    chain = ([NODE_NAMES[Role.SIMULATOR], NODE_NAMES[Role.MANEUVER],
              config.controller.node_name] if config.lockstep
             else [NODE_NAMES[Role.SIMULATOR]])
    granted = [set_fifo(c.proc.pid, FIFO_PRIORITY) for c in group.children
               if c.name in chain and c.proc is not None]
    if not all(granted):
        echo("  (real-time priority not permitted: expect more latency under load)")
    if not ros.start_simulation():
        return "the simulator did not answer the start request"
    echo(f"  graph up after {time.monotonic() - group.started_at:.1f} s; running "
         f"{config.maneuver.name} ({config.maneuver.duration_s} s simulated)")
    state.last_advance = state.t_start = time.monotonic()
    reported = -1
    called = False
    tty = sys.stderr.isatty()
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
            stopped = [c.name for c in group.children if c.stopped()]
            return (f"simulation stalled at t = {state.sim_time_s:.2f} s (no progress for "
                    f"{STALL_TIMEOUT_S:.0f} s)"
                    + (f"; node {', '.join(stopped)} is stopped (SIGSTOP)" if stopped else "")
                    + (f"; the simulator waits for: {waiting}" if waiting else ""))
        if not config.lockstep and state.sim_time_s > (config.maneuver.duration_s
                                                       + REALTIME_OVERRUN_S):
            return (f"the maneuver node did not end the run (t = {state.sim_time_s:.2f} s, "
                    f"maneuver duration {config.maneuver.duration_s} s)")
        if on_running is not None and not called and state.sim_time_s > 0.0:
            called = True
            on_running(group)
        progress = state.maneuver.progress if state.maneuver is not None else 0.0
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
    return ""


def _finish(config: RunConfig, group: ProcessGroup, ros: _LauncherNode | None,
            state: _RunState, interrupt: _Interrupt, failure: str, bag_path: Path | None,
            names: tuple[str, str, str, str], echo: Callable[[str], None]) -> str:
    """End the run: let the nodes deliver and the recorder close when the simulation ended,
    stop them otherwise; returns the failure (the recorder's problem added if it could not
    close the bag complete)."""
    sim, man, ctrl, rec = names
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
            left = group.wait_exit([sim, man], NODE_EXIT_S, poll)
            if left:
                echo(f"  {', '.join(left)} did not exit after the run; stopping")
                group.stop(left)
            # the recorder can only close a complete bag once the maneuver's final counts
            # are in; without them (a stopped or dead maneuver node) it is stopped below and
            # closes the bag with what it has
            if bag_path is not None and group.has(rec) and state.maneuver_end is not None:
                left = group.wait_exit([rec], RECORDER_GRACE_S, poll)
                if left:
                    detail = (state.recorder.detail if state.recorder is not None
                              else "no recorder status")
                    failure = (f"the recorder did not hold every message {RECORDER_GRACE_S:.0f}"
                               f" s after the simulation ended ({detail})")
            # the controller is stopped once the recorder has its messages (a user's own may
            # never exit by itself)
            if config.controller.builtin:
                group.wait_exit([ctrl], 5.0, poll)
            group.stop([ctrl])
        else:
            # stopped early: the nodes publish their final counts and deliver on SIGINT; the
            # recorder drains and closes the bag with what it has
            group.stop([sim, man, ctrl])
        if group.has(rec):
            group.stop([rec], grace_s=RECORDER_GRACE_S)
    except BaseException:
        group.kill_all()
        raise
    if interrupt.count > 1:
        echo("  (more signals arrived while stopping; the nodes were stopped in order so the "
             "bag is closed)")
    return failure


def _conclude(record: RunRecord, config: RunConfig, state: _RunState, interrupt: _Interrupt,
              failure: str) -> None:
    """Outcome, reason and numbers of the record from what happened and the closed bag."""
    sim = state.sim_final or state.sim
    if sim is not None:
        record.sim_time_s = float(sim.sim_time_s)
        record.max_lateness_s = float(sim.max_lateness_s)
        record.p99_lateness_s = float(sim.p99_lateness_s)
        record.overruns = int(sim.overruns)
        record.stale_commands = int(sim.stale_commands)
        for reason, n in zip(sim.rejected_reasons, sim.rejected_counts):
            record.rejections[f"{NODE_NAMES[Role.SIMULATOR]}: {reason}"] = int(n)
    man = state.maneuver_end or state.maneuver
    if man is not None:
        for reason, n in zip(man.rejected_reasons, man.rejected_counts):
            record.rejections[f"{NODE_NAMES[Role.MANEUVER]}: {reason}"] = int(n)
    if state.t_start:
        record.wall_time_s = max(state.t_end - state.t_start, 0.0)
    problems = []
    if record.bag_path is not None:
        try:
            check = verify_bag(record.bag_path)
        except BagError as exc:
            problems.append(str(exc))
        else:
            record.message_counts = check.counts
            if check.accounting:
                record.account = RunAccount.from_dict(check.accounting)
            problems.extend(check.problems)
            if check.complete is None and not check.problems:
                problems.append("the bag carries no recording accounting")
    record.reason = failure
    if interrupt.set or failure.startswith("interrupted"):
        record.outcome = Outcome.INTERRUPTED
        record.reason = "interrupted (Ctrl-C / SIGTERM)"
        return
    if failure:
        record.outcome = Outcome.FAILED
        return
    assert state.sim_final is not None
    end = str(state.sim_final.end_reason)
    ambiguous = {k: n for k, n in record.rejections.items() if SECOND_ANSWER in k}
    # states refused for not continuing the run although they were on its clock: a second
    # publisher sends states of this run, and the nodes cannot tell which one they answered
    # (the simulator's own may have been the refused one)
    maneuver = NODE_NAMES[Role.MANEUVER]
    doubled = {k: n for k, n in record.rejections.items() if k.startswith(maneuver) and (
        NOT_AFTER_PREVIOUS in k or (config.lockstep and SKIPS_STATES in k))}
    stop = str(state.sim_final.stop_reason)
    if doubled:  # whatever followed, the run's inputs are not certain
        record.outcome = Outcome.FAILED
        record.reason = ("a second publisher sent states on this run's clock ("
                         + "; ".join(f"{n}x {k}" for k, n in doubled.items())
                         + "): the answers applied may be to its states"
                         + (f"; then: {stop}" if stop else ""))
    elif stop:
        diverged = "diverged" in stop and not problems
        record.outcome = Outcome.DIVERGED if diverged else Outcome.FAILED
        record.reason = stop + ("" if not problems else
                                "; recording incomplete: " + "; ".join(problems))
    elif problems:
        record.outcome = Outcome.FAILED
        record.reason = "recording incomplete: " + "; ".join(problems)
    elif ambiguous:
        record.outcome = Outcome.FAILED
        record.reason = ("a second publisher answered states of this run ("
                         + "; ".join(f"{n}x {k}" for k, n in ambiguous.items())
                         + "): the inputs applied are not certain")
    elif record.stale_commands:
        record.outcome = Outcome.FAILED
        record.reason = (f"the controller did not answer in time or sent unusable commands "
                         f"for {record.stale_commands} control ticks (node "
                         f"{config.controller.node_name}; zero rear steer was applied then; "
                         f"see {record.run_dir / 'logs' / NODE_NAMES[Role.SIMULATOR]}.log)")
    elif state.maneuver_end is not None and state.maneuver_end.end == "aborted":
        record.outcome = Outcome.ABORTED
        record.reason = (f"the maneuver was aborted at t = {record.sim_time_s:.2f} s of "
                         f"{config.maneuver.duration_s} s: {state.maneuver_end.event}")
    elif state.maneuver_end is None:
        record.outcome = Outcome.FAILED
        record.reason = f"the simulation ended without the maneuver's end ({end})"
    elif state.maneuver_end.end == "stopped":
        # the maneuver node was not done: the simulator ended on an end it did not send
        # (a foreign 'done' status on the run's domain) or for a reason of its own
        record.outcome = Outcome.FAILED
        record.reason = (f"the simulation ended ({end}) at t = {record.sim_time_s:.2f} s "
                         f"before the maneuver node was done ({state.maneuver_end.event}); "
                         "a foreign maneuver status on the run's domain?")
    else:
        record.outcome = Outcome.COMPLETED
        record.reason = end


__all__ = ["LaunchError", "NODE_EXIT_S", "RECORDER_GRACE_S", "STALL_TIMEOUT_S",
           "STARTUP_TIMEOUT_S", "prepare_run_dir", "run_graph"]
