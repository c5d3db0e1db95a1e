"""Process launcher of the fourws graph (the ``ros2 launch`` replacement for the PyPI wheels).

Each node runs as its own OS process (``python -m fourws_cli.main node NAME --ros-args ...``)
in its own process group, on a ROS domain reserved for this run (:func:`reserve_domain_id`)
with discovery limited to this machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``), so
parallel runs and tests never see each other and nothing leaves the machine.

Shutdown is by process group: SIGINT, then SIGTERM after ``grace_s``, then SIGKILL. Children
also get SIGTERM from the kernel if the launcher itself dies (``PR_SET_PDEATHSIG``), so neither
Ctrl-C, a crashing node nor a killed launcher leaves orphans.

The launcher process also hosts one small ROS node (``fourws_launcher``): it publishes the run
configuration (latched), watches the graph until every expected endpoint is there, starts the
simulator (``/fourws/pause`` false), follows maneuver and simulator status, and reports.
"""

from __future__ import annotations

import ctypes
import fcntl
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, TextIO

from fourws_ros import topics
from fourws_ros.runtime import EXIT_RUN_STOPPED, EXIT_USER_ERROR

#: Domain IDs handed out (Linux: 0..101 are safe with the default port mapping; 0 is the
#: default domain users' other ROS graphs live on, so it is never used).
DOMAIN_ID_RANGE = range(1, 101)
_LOCK_DIR = Path(tempfile.gettempdir()) / "fourws-domains"
_PR_SET_PDEATHSIG = 1
#: How many lines of a failed node's log the launcher repeats.
LOG_TAIL_LINES = 15


class LaunchError(RuntimeError):
    """The run could not be started or did not end well; the message says why."""


class DomainLease:
    """An exclusive lock on one ROS domain ID of this machine (released by :meth:`release`)."""

    def __init__(self, domain_id: int, handle: TextIO) -> None:
        self.domain_id = domain_id
        self._handle: TextIO | None = handle

    def release(self) -> None:
        """Give the domain ID back."""
        if self._handle is not None:
            fcntl.flock(self._handle, fcntl.LOCK_UN)
            self._handle.close()
            self._handle = None

    def __enter__(self) -> "DomainLease":
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def reserve_domain_id(start: int | None = None) -> DomainLease:
    """Lock a ROS domain ID no other fourws run or test on this machine holds.

    Parameters
    ----------
    start : int, optional
        First ID to try (default: spread by process id so parallel callers rarely collide).

    Raises
    ------
    LaunchError
        If every ID of :data:`DOMAIN_ID_RANGE` is taken.
    """
    _LOCK_DIR.mkdir(parents=True, exist_ok=True)
    ids = list(DOMAIN_ID_RANGE)
    first = (os.getpid() if start is None else start) % len(ids)
    for k in range(len(ids)):
        domain = ids[(first + k) % len(ids)]
        handle = open(_LOCK_DIR / f"{domain}.lock", "w")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.close()
            continue
        return DomainLease(domain, handle)
    raise LaunchError(f"no free ROS domain ID in {DOMAIN_ID_RANGE}")


def graph_env(domain_id: int, base: dict[str, str] | None = None) -> dict[str, str]:
    """Environment of a node process: isolated domain, discovery on this machine only."""
    env = dict(os.environ if base is None else base)
    env["ROS_DOMAIN_ID"] = str(domain_id)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.pop("ROS_STATIC_PEERS", None)
    env["PYTHONUNBUFFERED"] = "1"
    return env


def _child_setup(niceness: int = 0) -> None:
    """In the child before exec: die with the parent (SIGTERM); lower priority if asked."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    if niceness:
        os.nice(niceness)


def set_fifo(pid: int, priority: int) -> bool:
    """SCHED_FIFO ``priority`` for every thread of process ``pid``; False if not permitted
    (no CAP_SYS_NICE) — the process then keeps normal scheduling."""
    try:
        tids = [int(t) for t in os.listdir(f"/proc/{pid}/task")]
        for tid in tids:
            os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
    except (OSError, ValueError):
        return False
    return True


def node_command(node: str, params_file: Path | None = None,
                 params: dict[str, Any] | None = None) -> list[str]:
    """Command line that runs fourws node ``node`` with a parameter file and overrides."""
    cmd = [sys.executable, "-m", "fourws_cli.main", "node", node, "--ros-args"]
    if params_file is not None:
        cmd += ["--params-file", str(params_file)]
    for key, value in (params or {}).items():
        cmd += ["-p", f"{key}:={_param_text(value)}"]
    return cmd


def _param_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(_param_text(v) for v in value) + "]"
    return str(value)


@dataclass
class Child:
    """One node process."""

    name: str
    cmd: list[str]
    log_path: Path
    proc: subprocess.Popen[bytes] | None = None
    #: Whether the run fails if this process exits on its own during the run.
    required: bool = True

    def alive(self) -> bool:
        """True while the process runs."""
        return self.proc is not None and self.proc.poll() is None

    def log_tail(self, lines: int = LOG_TAIL_LINES) -> str:
        """Last ``lines`` lines of the node's log."""
        try:
            text = self.log_path.read_text(errors="replace").splitlines()
        except OSError:
            return ""
        return "\n".join(text[-lines:])


class Launcher:
    """Starts, watches and stops the node processes of one run.

    Parameters
    ----------
    log_dir : Path
        Folder for one log file per node.
    domain_id : int
        ROS domain of the run (see :func:`reserve_domain_id`).
    echo : callable, optional
        Where progress lines go (default: stderr).
    grace_s : float
        Time a node gets after SIGINT (and again after SIGTERM) before escalation, s.
    """

    def __init__(self, log_dir: Path, domain_id: int,
                 echo: Callable[[str], None] | None = None, grace_s: float = 5.0) -> None:
        self.log_dir = Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.domain_id = domain_id
        self.env = graph_env(domain_id)
        self.children: list[Child] = []
        self.grace_s = grace_s
        self.echo = echo or (lambda text: print(text, file=sys.stderr, flush=True))
        self._ros_context: Any = None
        self._node: Any = None

    # ------------------------------------------------------------------ processes
    def start(self, name: str, cmd: list[str], required: bool = True,
              niceness: int = 0) -> Child:
        """Start ``cmd`` as node process ``name`` (own process group, log file; ``niceness``
        > 0 lowers its CPU priority)."""
        if not self.children:
            self._t0 = time.monotonic()
        log_path = self.log_dir / f"{name}.log"
        child = Child(name, cmd, log_path, required=required)
        with open(log_path, "wb") as log:
            child.proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                          stdin=subprocess.DEVNULL, env=self.env,
                                          start_new_session=True,
                                          preexec_fn=lambda: _child_setup(niceness))
        self.children.append(child)
        return child

    def child(self, name: str) -> Child:
        """The child process called ``name``."""
        for c in self.children:
            if c.name == name:
                return c
        raise KeyError(name)

    def stop(self, names: Iterable[str] | None = None) -> dict[str, int | None]:
        """Stop children (in the given order, default reverse start order) by process group.

        SIGINT, then SIGTERM after ``grace_s``, then SIGKILL; returns the exit codes.
        """
        order = ([self.child(n) for n in names] if names is not None
                 else list(reversed(self.children)))
        codes: dict[str, int | None] = {}
        for child in order:
            codes[child.name] = self._stop_one(child)
        return codes

    def _stop_one(self, child: Child) -> int | None:
        proc = child.proc
        if proc is None:
            return None
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
            if proc.poll() is not None:
                break
            try:
                os.killpg(proc.pid, sig)
                os.killpg(proc.pid, signal.SIGCONT)  # a stopped node must run to handle it
            except ProcessLookupError:
                break
            try:
                proc.wait(timeout=self.grace_s)
            except subprocess.TimeoutExpired:
                self.echo(f"  {child.name} ignored {signal.Signals(sig).name}, escalating")
        # members of the group that outlived the leader
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        return proc.wait()

    def kill_all(self) -> None:
        """SIGKILL every child process group at once (last resort)."""
        for child in self.children:
            if child.proc is not None:
                try:
                    os.killpg(child.proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                child.proc.wait()

    def crashed(self) -> Child | None:
        """A required child that exited on its own, if any."""
        for child in self.children:
            if child.required and child.proc is not None and child.proc.poll() is not None:
                return child
        return None

    def describe_exit(self, child: Child) -> str:
        """One paragraph on why ``child`` ended, with the tail of its log."""
        code = child.proc.poll() if child.proc is not None else None
        if code == EXIT_USER_ERROR:
            what = "refused its configuration"
        elif code == EXIT_RUN_STOPPED:
            what = "stopped the run"
        elif code is not None and code < 0:
            what = f"was killed by {signal.Signals(-code).name}"
        else:
            what = f"exited with code {code}"
        tail = child.log_tail()
        return f"node {child.name} {what} (log {child.log_path}):\n{tail}"

    # ------------------------------------------------------------------ ROS side
    def open_ros(self) -> Any:
        """Create the launcher's own ROS node on the run's domain (after the children start,
        so no DDS thread exists while they fork)."""
        import rclpy
        from rclpy.context import Context

        os.environ.update({"ROS_DOMAIN_ID": str(self.domain_id),
                           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
        self._ros_context = Context()
        rclpy.init(args=[], context=self._ros_context, domain_id=self.domain_id,
                   signal_handler_options=_no_signals())
        self._node = rclpy.create_node("fourws_launcher", context=self._ros_context)
        return self._node

    @property
    def node(self) -> Any:
        """The launcher's ROS node (after :meth:`open_ros`)."""
        return self._node

    def close_ros(self) -> None:
        """Destroy the launcher's node and context."""
        if self._node is not None:
            self._node.destroy_node()
            self._node = None
        if self._ros_context is not None:
            self._ros_context.try_shutdown()
            self._ros_context = None

    def wait_for_endpoints(self, expected: list[tuple[str, str, str]], timeout_s: float,
                           spin: Callable[[float], None]) -> None:
        """Wait until every ``(topic, "pub"|"sub", node_name)`` is in the graph.

        Raises
        ------
        LaunchError
            On timeout (naming what is missing) or if a node process exits meanwhile.
        """
        deadline = time.monotonic() + timeout_s
        missing = list(expected)
        while True:
            missing = [e for e in expected if not self._has_endpoint(*e)]
            if not missing:
                return
            dead = self.crashed()
            if dead is not None:
                raise LaunchError(self.describe_exit(dead))
            if time.monotonic() > deadline:
                what = ", ".join(f"{n} {'publishing' if k == 'pub' else 'subscribing to'} {t}"
                                 for t, k, n in missing)
                raise LaunchError(f"graph incomplete after {timeout_s:.0f} s; missing: {what}")
            spin(0.05)

    def _has_endpoint(self, topic: str, kind: str, node_name: str) -> bool:
        infos = (self._node.get_publishers_info_by_topic(topic) if kind == "pub"
                 else self._node.get_subscriptions_info_by_topic(topic))
        return any(i.node_name == node_name for i in infos)


def _no_signals() -> Any:
    from rclpy.signals import SignalHandlerOptions
    return SignalHandlerOptions.NO


def write_params_file(path: Path, node_params: dict[str, dict[str, Any]]) -> Path:
    """Write a ROS 2 parameter file ``{node: {ros__parameters: {...}}}`` (YAML)."""
    import yaml

    data = {node: {"ros__parameters": params} for node, params in node_params.items()}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def dumps_config(config: dict[str, Any]) -> str:
    """JSON text of a run configuration (numpy scalars and paths made plain)."""
    def default(obj: Any) -> Any:
        if hasattr(obj, "tolist"):
            return obj.tolist()
        if isinstance(obj, Path):
            return str(obj)
        raise TypeError(f"not JSON serializable: {type(obj).__name__}")
    return json.dumps(config, default=default, sort_keys=True)


# ============================================================================ one graph run
#: Node name of each role (the ROS node names the processes take).
NODE_NAMES = {"simulator": "fourws_simulator", "maneuver": "fourws_maneuver",
              "controller": "fourws_controller", "recorder": "fourws_recorder"}
#: Time allowed for every node to come up and discover the others, s.
STARTUP_TIMEOUT_S = 60.0
#: A run whose simulation time has not advanced for this long (wall) is stopped as stalled, s.
STALL_TIMEOUT_S = 20.0
#: Lockstep flow control: the simulator runs at most this many ticks ahead of the recorder
#: (a quarter of the stream history depth, so a lagging recorder never loses a message).
RECORDER_WINDOW_TICKS = topics.STREAM_DEPTH // 4
#: SCHED_FIFO priority of the lockstep answer chain (simulator, maneuver, controller) and of
#: the realtime simulator; they block between messages, and the kernel's RT throttling keeps
#: 5 % of each CPU for everything else. The realtime integration thread raises itself above
#: it (simulator parameter ``realtime_priority``).
LOCKSTEP_FIFO_PRIORITY = 10
#: CPU niceness of the recorder process (lower priority than the answer chain).
RECORDER_NICENESS = 10
#: After the maneuver is done: how long the recorder may take to drain and close, s.
RECORDER_GRACE_S = 30.0


@dataclass
class GraphRun:
    """Result of :func:`run_graph`."""

    ok: bool
    reason: str
    law: str
    run_dir: Path
    bag_path: Path | None
    sim_time_s: float
    wall_time_s: float
    realtime_factor: float
    max_lateness_s: float
    p99_lateness_s: float
    overruns: int
    stale_commands: int
    message_counts: dict[str, int]
    exit_codes: dict[str, int | None]
    interrupted: bool = False

    def summary_lines(self) -> list[str]:
        """Human-readable summary (what ``fourws run`` prints)."""
        status = "ok" if self.ok else f"FAILED: {self.reason}"
        lines = [f"run {self.law}: {status}",
                 f"  simulated {self.sim_time_s:.2f} s in {self.wall_time_s:.2f} s of running "
                 f"(real-time factor {self.realtime_factor:.1f}x)"]
        if self.max_lateness_s > 0.0:
            lines.append(f"  step lateness p99 {self.p99_lateness_s * 1e3:.3f} ms, max "
                         f"{self.max_lateness_s * 1e3:.3f} ms, overruns {self.overruns}")
        if self.stale_commands:
            lines.append(f"  rear-steer commands timed out or rejected: {self.stale_commands}")
        if self.bag_path is not None:
            counts = ", ".join(f"{t} {n}" for t, n in sorted(self.message_counts.items()))
            lines.append(f"  bag: {self.bag_path}")
            lines.append(f"  messages: {counts}")
        lines.append(f"  logs: {self.run_dir / 'logs'}")
        return lines


def run_config(scenario: Any, law: str) -> dict[str, Any]:
    """The JSON-ready run configuration recorded on ``/fourws/run_config``.

    Keys follow :func:`fourws_sim.closed_loop.run_closed_loop`'s ``config`` (vehicle mapping,
    maneuver mapping, law, model, periods) plus the clock mode, the scenario and versions.
    """
    import platform
    from importlib.metadata import PackageNotFoundError, version

    vehicle = scenario.build_vehicle()
    belief = scenario.build_belief(vehicle)
    versions: dict[str, str] = {"python": platform.python_version()}
    for dist in ("fourws", "rosbags", "numpy", "ros-rclpy"):
        try:
            versions[dist] = version(dist)
        except PackageNotFoundError:
            versions[dist] = "unknown"
    return {
        "vehicle": vehicle.to_dict(), "belief_vehicle": belief.to_dict(),
        "maneuver": scenario.maneuver.to_dict(), "law": law,
        "law_options": dict(scenario.law_options.get(law, {})), "model": scenario.model,
        "tire": scenario.tire, "integrator": scenario.integrator,
        "integration_step_s": scenario.integration_step_s,
        "control_period_s": scenario.control_period_s,
        "state_period_s": scenario.state_period_s, "clock_mode": scenario.clock_mode,
        "speed_mps": float(scenario.maneuver.initial_speed_mps),
        "scenario": scenario.to_dict(), "versions": versions,
    }


def node_parameters(scenario: Any, law: str, bag_path: Path | None,
                    controller_name: str = NODE_NAMES["controller"]) -> dict[str, dict]:
    """Per-node ``ros__parameters`` of a run (written to the run's ``params.yaml``)."""
    from fourws_ros.recorder_node import DEFAULT_TOPICS

    lockstep = scenario.clock_mode == "lockstep"
    belief = scenario.belief
    # the controller is called once per published state: in lockstep once per control
    # period, in realtime once per state period — the interval of its rate limit
    answer_period = scenario.control_period_s if lockstep else scenario.state_period_s
    rec_topics = scenario.recording.topics
    recorded = list(DEFAULT_TOPICS if rec_topics == "all" else rec_topics)
    records_state = bag_path is not None and topics.STATE in recorded
    n_answering = 2 + (1 if records_state else 0)
    params: dict[str, dict[str, Any]] = {
        NODE_NAMES["simulator"]: {
            "vehicle": scenario.vehicle, "model": scenario.model,
            "tire": scenario.tire or "", "integrator": scenario.integrator,
            "integration_step_s": scenario.integration_step_s,
            "control_period_s": scenario.control_period_s,
            "state_period_s": scenario.state_period_s,
            "clock_mode": scenario.clock_mode,
            "initial_speed_mps": float(scenario.maneuver.initial_speed_mps),
            "autostart": False,
            "expected_state_subscribers": n_answering if lockstep else 0,
            "recorder_window_ticks": RECORDER_WINDOW_TICKS if lockstep and records_state else 0,
        },
        NODE_NAMES["maneuver"]: {
            "maneuver_json": dumps_config(scenario.maneuver.to_dict()),
            "vehicle": scenario.vehicle,
        },
        controller_name: {
            "law": law,
            "law_options_json": dumps_config(dict(scenario.law_options.get(law, {}))),
            "vehicle": scenario.vehicle,
            "belief_vehicle": belief.vehicle or "",
            "belief_scale_front": float(belief.cornering_stiffness_scale_front),
            "belief_scale_rear": float(belief.cornering_stiffness_scale_rear),
            "control_period_s": float(answer_period),
            # lockstep: the driver input of every tick comes (the run ends when it does not)
            "driver_wait_s": 0.0 if lockstep else 0.5,
        },
    }
    if bag_path is not None:
        params[NODE_NAMES["recorder"]] = {"bag_path": str(bag_path), "topics": recorded}
    return params


def _expected_endpoints(recorded: list[str] | None, controller_name: str
                        ) -> list[tuple[str, str, str]]:
    sim, man = NODE_NAMES["simulator"], NODE_NAMES["maneuver"]
    expected = [
        (topics.STATE, "pub", sim), (topics.STATE, "sub", man),
        (topics.STATE, "sub", controller_name),
        (topics.DRIVER_INPUT, "pub", man), (topics.DRIVER_INPUT, "sub", sim),
        (topics.DRIVER_INPUT, "sub", controller_name),
        (topics.REAR_STEER_CMD, "pub", controller_name), (topics.REAR_STEER_CMD, "sub", sim),
    ]
    for topic in recorded or []:
        expected.append((topic, "sub", NODE_NAMES["recorder"]))
    return expected


def _bag_counts(bag_path: Path) -> dict[str, int]:
    """Message count per topic from a bag's metadata.yaml (empty if it has none)."""
    import yaml

    meta = bag_path / "metadata.yaml"
    if not meta.is_file():
        return {}
    info = yaml.safe_load(meta.read_text())["rosbag2_bagfile_information"]
    return {t["topic_metadata"]["name"]: int(t["message_count"])
            for t in info.get("topics_with_message_count", [])}


class _Interrupted(Exception):
    """SIGINT/SIGTERM reached the launcher."""


def run_graph(scenario: Any, law: str, out_dir: Path, *, run_name: str | None = None,
              echo: Callable[[str], None] | None = None,
              controller: tuple[str, str] = ("controller", NODE_NAMES["controller"]),
              replay_driver_from: Path | None = None,
              node_overrides: dict[str, dict[str, Any]] | None = None,
              on_running: Callable[[Launcher], None] | None = None) -> GraphRun:
    """Run one scenario with one law through the real node graph, recording a bag.

    Parameters
    ----------
    scenario : fourws_sim.scenario.Scenario
    law : str
        Rear-steer law of this run.
    out_dir : Path
        Parent folder; the run gets ``out_dir/<run_name>/`` with ``bag/``, ``logs/`` and
        ``params.yaml``.
    run_name : str, optional
        Default ``<scenario>-<law>-<UTC time>``.
    echo : callable, optional
        Progress output (default stderr).
    controller : (str, str)
        ``fourws node`` name and ROS node name of the controller (a user controller may
        replace the built-in one).
    replay_driver_from : Path, optional
        A bag whose ``/fourws/driver_input`` drives this run instead of the maneuver node
        (replay node in answer mode, e.g. the same driver with another controller; the
        scenario should be the recorded one, for the initial speed).
    node_overrides : dict, optional
        Extra parameters per ROS node name (tests, benchmarks).
    on_running : callable, optional
        Called once with the launcher when the simulation has started (tests inject faults).

    Returns
    -------
    GraphRun
        ``ok`` false with the reason when a node failed, the run stalled or the simulator
        stopped it; the recorder is always stopped last so the bag keeps what it has.
    """
    echo = echo or (lambda text: print(text, file=sys.stderr, flush=True))
    # a step steer at a target lateral acceleration runs the amplitude found for this law
    from fourws_sim.closed_loop import scenario_for_law
    scenario = scenario_for_law(scenario, law)
    stamp = time.strftime("%Y%m%d-%H%M%S", time.gmtime())
    run_dir = Path(out_dir) / (run_name or f"{scenario.name}-{law}-{stamp}")
    if run_dir.exists():
        raise LaunchError(f"run folder {run_dir} exists already")
    run_dir.mkdir(parents=True)
    record = scenario.recording.enabled
    bag_path = run_dir / "bag" if record else None
    controller_node, controller_name = controller
    params = node_parameters(scenario, law, bag_path, controller_name)
    driver_node = "maneuver"
    if replay_driver_from is not None:
        driver_node = "replay"
        params[NODE_NAMES["maneuver"]] = {
            "bag_path": str(replay_driver_from), "topics": [topics.DRIVER_INPUT],
            "mode": "answer", "publish_clock": False}
    for name, extra in (node_overrides or {}).items():
        params.setdefault(name, {}).update(extra)
    params_file = write_params_file(run_dir / "params.yaml", params)
    recorded = params.get(NODE_NAMES["recorder"], {}).get("topics") if record else None
    config_json = dumps_config(run_config(scenario, law))

    lease = reserve_domain_id()
    launcher = Launcher(run_dir / "logs", lease.domain_id, echo=echo)
    state = {"done": False, "progress": 0.0, "phase": "", "sim_time_s": 0.0, "stop": "",
             "max_lateness_s": 0.0, "p99_lateness_s": 0.0, "overruns": 0, "stale": 0,
             "last_advance": time.monotonic(), "events": []}
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}

    def interrupt(_signum: int, _frame: Any) -> None:
        raise _Interrupted()

    ok, reason, interrupted = True, "", False
    wall_start = time.monotonic()
    exit_codes: dict[str, int | None] = {}
    try:
        signal.signal(signal.SIGINT, interrupt)
        signal.signal(signal.SIGTERM, interrupt)
        names = ([("recorder", NODE_NAMES["recorder"])] if record else []) + [
            (controller_node, controller_name), (driver_node, NODE_NAMES["maneuver"]),
            ("simulator", NODE_NAMES["simulator"])]
        for node, ros_name in names:
            cmd = node_command(node, params_file)
            if ros_name != NODE_NAMES.get(node, f"fourws_{node}"):
                cmd += ["-r", f"__node:={ros_name}"]
            # the recorder lags behind (flow control bounds it) rather than take the CPU from
            # the lockstep answer chain simulator -> maneuver -> controller
            launcher.start(ros_name, cmd,
                           niceness=RECORDER_NICENESS if node == "recorder" else 0)
        echo(f"fourws run {scenario.name} / {law}: {len(names)} nodes on ROS domain "
             f"{lease.domain_id} ({scenario.clock_mode}), logs in {run_dir / 'logs'}")
        node = launcher.open_ros()
        ok, reason = _drive_run(launcher, node, config_json, recorded, controller_name, state,
                                scenario, echo, on_running)
    except _Interrupted:
        state.setdefault("t_end", time.monotonic())
        ok, reason, interrupted = False, "interrupted (Ctrl-C / SIGTERM)", True
    except LaunchError as exc:
        ok, reason = False, str(exc)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        wall = time.monotonic() - wall_start
        try:
            order = [NODE_NAMES["simulator"], NODE_NAMES["maneuver"], controller_name]
            order = [n for n in order if any(c.name == n for c in launcher.children)]
            exit_codes.update(launcher.stop(order))
            if record and any(c.name == NODE_NAMES["recorder"] for c in launcher.children):
                launcher.grace_s = RECORDER_GRACE_S
                exit_codes.update(launcher.stop([NODE_NAMES["recorder"]]))
        except BaseException:
            launcher.kill_all()
            raise
        finally:
            launcher.close_ros()
            lease.release()
    if ok:
        bad = {n: c for n, c in exit_codes.items() if c not in (0, None)}
        if bad:
            ok, reason = False, "; ".join(launcher.describe_exit(launcher.child(n))
                                          for n in bad)
    if ok and state["stale"]:
        ok, reason = False, (
            f"the controller did not answer or sent unusable commands for {state['stale']} "
            f"control ticks (zero rear steer applied then; see "
            f"{launcher.log_dir / NODE_NAMES['simulator']}.log)")
    counts = _bag_counts(bag_path) if bag_path is not None else {}
    sim_time = float(state["sim_time_s"])
    running = float(state.get("t_end", time.monotonic()) - state.get("t_start", wall_start))
    return GraphRun(ok=ok, reason=reason, law=law, run_dir=run_dir, bag_path=bag_path,
                    sim_time_s=sim_time, wall_time_s=running,
                    realtime_factor=sim_time / running if running > 0 else 0.0,
                    max_lateness_s=float(state["max_lateness_s"]),
                    p99_lateness_s=float(state["p99_lateness_s"]),
                    overruns=int(state["overruns"]), stale_commands=int(state["stale"]),
                    message_counts=counts, exit_codes=exit_codes, interrupted=interrupted)


def _drive_run(launcher: Launcher, node: Any, config_json: str, recorded: list[str] | None,
               controller_name: str, state: dict[str, Any], scenario: Any,
               echo: Callable[[str], None],
               on_running: Callable[[Launcher], None] | None) -> tuple[bool, str]:
    """Publish the configuration, wait for the graph, start, follow the run to its end."""
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import String
    from std_srvs.srv import SetBool

    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)

    def spin(seconds: float) -> None:
        executor.spin_once(timeout_sec=seconds)

    config_pub = node.create_publisher(String, topics.RUN_CONFIG, topics.LATCHED_QOS)
    config_pub.publish(String(data=config_json))

    def on_maneuver(msg: Any) -> None:
        state["progress"], state["phase"] = msg.progress, msg.phase
        if msg.event:
            state["events"].append(msg.event)
        if msg.done:
            state["done"] = True
            state["sim_time_s"] = max(state["sim_time_s"], msg.header.stamp.sec
                                      + msg.header.stamp.nanosec * 1e-9)

    def on_sim(msg: Any) -> None:
        if msg.sim_time_s > state["sim_time_s"]:
            state["last_advance"] = time.monotonic()
        state["sim_time_s"] = msg.sim_time_s
        state["max_lateness_s"] = msg.max_lateness_s
        state["p99_lateness_s"] = msg.p99_lateness_s
        state["overruns"] = msg.overruns
        state["stale"] = msg.stale_commands
        if msg.stop_reason:
            state["stop"] = msg.stop_reason

    node.create_subscription(topics.message_class(topics.MANEUVER_STATUS),
                             topics.MANEUVER_STATUS, on_maneuver, topics.STATUS_QOS)
    node.create_subscription(topics.message_class(topics.SIM_STATUS), topics.SIM_STATUS,
                             on_sim, topics.STATUS_QOS)
    pause = node.create_client(SetBool, topics.SRV_PAUSE)

    launcher.wait_for_endpoints(_expected_endpoints(recorded, controller_name),
                                STARTUP_TIMEOUT_S, spin)
    if recorded is not None:
        # the recorder must hold the configuration before anything else is recorded
        launcher.wait_for_endpoints([(topics.RUN_CONFIG, "sub", NODE_NAMES["recorder"])],
                                    STARTUP_TIMEOUT_S, spin)
    deadline = time.monotonic() + STARTUP_TIMEOUT_S
    while not pause.service_is_ready():
        if time.monotonic() > deadline:
            raise LaunchError("the simulator's /fourws/pause service did not appear")
        spin(0.05)
    # Real-time priority while the run lasts (not during start-up, so imports and JIT
    # compilation do not hold a CPU at real-time priority). Lockstep: the answer chain
    # simulator -> maneuver -> controller, since every hop is a process wake-up that the normal
    # scheduler delays by 0.1-1 ms under load. Realtime: every thread of the simulator, so the
    # thread holding the GIL is never preempted while the integration thread waits for it.
    chain = ([NODE_NAMES["simulator"], NODE_NAMES["maneuver"], controller_name]
             if scenario.clock_mode == "lockstep" else [NODE_NAMES["simulator"]])
    granted = [set_fifo(c.proc.pid, LOCKSTEP_FIFO_PRIORITY) for c in launcher.children
               if c.name in chain and c.proc is not None]
    if not all(granted):
        echo("  (real-time priority not permitted: expect more latency under load)")
    future = pause.call_async(SetBool.Request(data=False))
    executor.spin_until_future_complete(future, timeout_sec=10.0)
    if not future.done():
        raise LaunchError("the simulator did not answer the start request")
    echo(f"  graph up after {time.monotonic() - launcher_start(launcher):.1f} s; running "
         f"{scenario.maneuver.name} ({scenario.maneuver.duration_s} s simulated)")
    state["last_advance"] = state["t_start"] = time.monotonic()
    reported = -1
    called = False
    tty = sys.stderr.isatty()
    while not state["done"]:
        spin(0.05)
        if state["stop"]:
            return False, f"simulator stopped the run: {state['stop']}"
        dead = launcher.crashed()
        if dead is not None:
            return False, launcher.describe_exit(dead)
        if time.monotonic() - state["last_advance"] > STALL_TIMEOUT_S:
            return False, (f"simulation stalled at t = {state['sim_time_s']:.2f} s (no progress "
                           f"for {STALL_TIMEOUT_S:.0f} s)")
        if on_running is not None and not called and state["sim_time_s"] > 0.0:
            called = True
            on_running(launcher)
        decile = int(state["progress"] * 10)
        if decile != reported:
            reported = decile
            line = (f"  [{state['progress'] * 100:5.1f} %] t = {state['sim_time_s']:6.2f} s  "
                    f"phase {state['phase'] or '-'}")
            if tty:
                print("\r" + line, end="", file=sys.stderr, flush=True)
            else:
                echo(line)
    state["t_end"] = time.monotonic()
    if tty:
        print(file=sys.stderr)
    # stop the simulation first so the recorder's queues run dry
    future = pause.call_async(SetBool.Request(data=True))
    executor.spin_until_future_complete(future, timeout_sec=5.0)
    for _ in range(4):  # collect the last status messages
        spin(0.05)
    reason = next((e for e in state["events"] if e.startswith("abort")), "")
    if reason:
        return False, f"maneuver {reason}"
    return True, "maneuver done"


def launcher_start(launcher: Launcher) -> float:
    """Monotonic time at which the first node process was started."""
    return getattr(launcher, "_t0", time.monotonic())
