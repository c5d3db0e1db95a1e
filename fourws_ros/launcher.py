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
from dataclasses import dataclass, field
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


def _child_setup() -> None:
    """In the child before exec: die with the parent (SIGTERM), own process group."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)


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


@dataclass
class RunOutcome:
    """How a launched run ended."""

    ok: bool
    reason: str
    sim_time_s: float = 0.0
    wall_time_s: float = 0.0
    max_lateness_s: float = 0.0
    overruns: int = 0
    stale_commands: int = 0
    exit_codes: dict[str, int | None] = field(default_factory=dict)
    events: list[str] = field(default_factory=list)


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
    def start(self, name: str, cmd: list[str], required: bool = True) -> Child:
        """Start ``cmd`` as node process ``name`` (own process group, log file)."""
        log_path = self.log_dir / f"{name}.log"
        child = Child(name, cmd, log_path, required=required)
        with open(log_path, "wb") as log:
            child.proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                          stdin=subprocess.DEVNULL, env=self.env,
                                          start_new_session=True, preexec_fn=_child_setup)
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
