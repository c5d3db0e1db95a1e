# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The node processes of a run: start, watch, stop -- without orphans.

Each node runs as its own OS process in its own process group, with a log file. Shutdown is by
process group: SIGINT, then SIGTERM after ``grace_s``, then SIGKILL. Children also get SIGTERM
from the kernel if the launcher itself dies (``PR_SET_PDEATHSIG``), so neither Ctrl-C, a
crashing node nor a killed launcher leaves orphans; a stopped (SIGSTOP) node is continued so
it can handle the signal.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable

from fourws_ros.oslevel import PR_SET_PDEATHSIG, is_stopped, node_prefix, prctl
from fourws_ros.runtime import (EXIT_INCOMPLETE, EXIT_PEERS, EXIT_RUN_STOPPED, EXIT_USER_ERROR,
                                PHASE_FD_ENV, STACK_SIGNAL)

#: How many lines of a failed node's log the launcher repeats.
LOG_TAIL_LINES = 15
#: How long a stuck node gets at most to write its stacks before it is killed, s; frames
#: repeated.
STACK_WAIT_S = 2.0
STACK_LINES = 8


def _child_setup() -> None:
    """In the child before exec: die with the parent (SIGTERM)."""
    prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def set_fifo(pid: int, priority: int) -> bool:
    """SCHED_FIFO ``priority`` for every thread of process ``pid``; False if not permitted
    (no CAP_SYS_NICE) -- the process then keeps normal scheduling. Speed only: nothing in a
    run's correctness depends on it."""
    try:
        tids = [int(t) for t in os.listdir(f"/proc/{pid}/task")]
        for tid in tids:
            os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
    except (OSError, ValueError):
        return False
    return True


#: ``(cmd, env, log_fd, phase_fd) -> process or None``: starts a fourws node command
#: instead of ``exec`` (None: it cannot, ``exec`` then), set by :func:`use_node_spawner`.
_NODE_SPAWNER: list[Callable[[list[str], dict[str, str], int, int], Any]] = []


def use_node_spawner(spawner: Callable[[list[str], dict[str, str], int, int], Any] | None,
                     ) -> None:
    """Start the fourws nodes of later runs with ``spawner`` (a process with the methods of
    :class:`subprocess.Popen` the group uses, or None to ``exec`` that one); None: ``exec``
    every node. The command line installs its node starter (:mod:`fourws_cli.node_starter`)."""
    _NODE_SPAWNER[:] = [spawner] if spawner is not None else []


def _spawned(cmd: list[str], env: dict[str, str], log_fd: int, phase_fd: int) -> Any:
    return _NODE_SPAWNER[0](cmd, env, log_fd, phase_fd) if _NODE_SPAWNER else None


def node_command(node: str, params_file: Path | None = None,
                 params: dict[str, Any] | None = None,
                 node_name: str | None = None) -> list[str]:
    """Command line that runs fourws node ``node`` with a parameter file and overrides."""
    cmd = node_prefix() + [node]
    return cmd + ros_args(params_file, params, node_name)


def ros_args(params_file: Path | None = None, params: dict[str, Any] | None = None,
             node_name: str | None = None) -> list[str]:
    """``--ros-args`` of a node: node name remap, parameter file, parameter overrides."""
    args = ["--ros-args"]
    if node_name:
        args += ["-r", f"__node:={node_name}"]
    if params_file is not None:
        args += ["--params-file", str(params_file)]
    for key, value in (params or {}).items():
        args += ["-p", f"{key}:={_param_text(value)}"]
    return args


def user_command(command: tuple[str, ...] | list[str]) -> list[str]:
    """A user's controller command made runnable: a ``.py`` file that is not executable runs
    with this Python (the one with rclpy and the fourws messages)."""
    cmd = list(command)
    if cmd and cmd[0].endswith(".py") and not os.access(cmd[0], os.X_OK):
        cmd.insert(0, sys.executable)
    return cmd


def _param_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(_param_text(v) for v in value) + "]"
    return str(value)


@dataclass
class Child:
    """One node process.

    ``phase`` is the start-up phase the node reported last (``configuring``, ``compiling``,
    ``ready``, ``failed: <why>``; '' before the first, while Python imports; always '' for a
    program that does not report, such as a user's controller), ``phase_at`` when (monotonic
    s).
    """

    name: str
    cmd: list[str]
    log_path: Path
    #: A :class:`subprocess.Popen`, or what the node spawner returned (the same methods).
    proc: Any = None
    phase: str = ""
    phase_at: float = 0.0
    #: Every phase reported, with its time (monotonic s).
    phase_log: list[tuple[str, float]] = field(default_factory=list)
    _phase_fd: int = -1
    _phase_buf: bytes = b""

    def read_phases(self) -> None:
        """Take the phase lines the node wrote since the last call."""
        if self._phase_fd < 0:
            return
        while True:
            try:
                chunk = os.read(self._phase_fd, 4096)
            except BlockingIOError:
                break
            except OSError:
                chunk = b""
            if not chunk:  # the node closed its end (it exited)
                os.close(self._phase_fd)
                self._phase_fd = -1
                break
            self._phase_buf += chunk
        *lines, self._phase_buf = self._phase_buf.split(b"\n")
        for line in lines:
            if line.strip():
                self.phase = line.decode("utf-8", "replace").strip()
                self.phase_at = time.monotonic()
                self.phase_log.append((self.phase, self.phase_at))

    def alive(self) -> bool:
        """True while the process runs."""
        return self.proc is not None and self.proc.poll() is None

    def stopped(self) -> bool:
        """The process is stopped (SIGSTOP/SIGTSTP): alive but not running."""
        return self.alive() and self.proc is not None and is_stopped(self.proc.pid)

    def exit_code(self) -> int | None:
        """The exit code (None while it runs)."""
        return None if self.proc is None else self.proc.poll()

    def log_tail(self, lines: int = LOG_TAIL_LINES) -> str:
        """Last ``lines`` lines of the node's log."""
        try:
            text = self.log_path.read_text(errors="replace").splitlines()
        except OSError:
            return ""
        return "\n".join(text[-lines:])


def describe_exit(child: Child, with_log: bool = True) -> str:
    """Why ``child`` ended, and the tail of its log."""
    code = child.exit_code()
    if code == EXIT_USER_ERROR:
        what = "refused its configuration"
    elif code == EXIT_RUN_STOPPED:
        what = "stopped the run"
    elif code == EXIT_INCOMPLETE:
        what = "closed an incomplete bag"
    elif code == EXIT_PEERS:
        what = "gave up on its peers"
    elif code is not None and code < 0:
        what = f"was killed by {signal.Signals(-code).name}"
    else:
        what = f"exited with code {code}"
    text = f"node {child.name} {what} (log {child.log_path})"
    cause = last_line(child.log_tail()) if with_log else ""
    return f"{text}: {cause}" if cause else text


def last_line(text: str) -> str:
    """The last meaningful line of a node's log (a Python traceback's last line is its
    error), without terminal colour codes, at most 300 characters."""
    lines = [re.sub(r"\x1b\[[0-9;]*m", "", ln).strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln and not ln.startswith("^")]
    return lines[-1][:300] if lines else ''


class ProcessGroup:
    """Starts, watches and stops the node processes of one run.

    Parameters
    ----------
    log_dir : Path
        Folder for one log file per node.
    env : dict
        Environment of the node processes (:func:`fourws_ros.domains.graph_env`).
    echo : callable
        Where progress lines go.
    grace_s : float
        Time a node gets after SIGINT (and again after SIGTERM) before escalation, s.
    """

    def __init__(self, log_dir: Path, env: dict[str, str], echo: Callable[[str], None],
                 grace_s: float = 5.0) -> None:
        self.log_dir = Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.env = dict(env)
        # a user's `python my_controller.py` finds this environment's Python first
        bin_dir = str(Path(sys.executable).parent)
        self.env["PATH"] = bin_dir + os.pathsep + self.env.get("PATH", "")
        self.children: list[Child] = []
        #: Children whose exit does not fail the run (the live view: a viewer, not a node of
        #: the run).
        self.optional: set[str] = set()
        self.grace_s = grace_s
        self.echo = echo
        self.started_at = time.monotonic()

    def start(self, name: str, cmd: list[str]) -> Child:
        """Start ``cmd`` as node process ``name`` (own process group, log file, a pipe for
        its start-up phases: :data:`fourws_ros.runtime.PHASE_FD_ENV`).

        Raises
        ------
        OSError
            The program cannot be run (not found, not executable).
        """
        log_path = self.log_dir / f"{name}.log"
        if shutil.which(cmd[0], path=self.env.get("PATH")) is None and not Path(cmd[0]).is_file():
            raise FileNotFoundError(f"{cmd[0]!r}: command not found")
        child = Child(name, cmd, log_path, phase_at=time.monotonic())
        read_fd, write_fd = os.pipe()
        os.set_blocking(read_fd, False)
        env = dict(self.env, **{PHASE_FD_ENV: str(write_fd)})
        try:
            with open(log_path, "wb") as log:
                # a fourws node forked by the node spawner (its imports done once per
                # launcher, fourws_cli.node_starter), else started as its own program
                child.proc = _spawned(cmd, self.env, log.fileno(), write_fd) or \
                    subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL, env=env,
                                     start_new_session=True, preexec_fn=_child_setup,
                                     pass_fds=(write_fd,))
        except OSError:
            os.close(read_fd)
            raise
        finally:
            os.close(write_fd)
        child._phase_fd = read_fd
        self.children.append(child)
        return child

    def read_phases(self) -> None:
        """Take every child's new start-up phase lines."""
        for child in self.children:
            child.read_phases()

    def startup_breakdown(self) -> str:
        """Where the start-up time went, per node that reports phases: seconds from its
        launch to its first phase (Python imports), and in each phase."""
        parts = []
        for child in self.children:
            if not child.phase_log:
                continue
            t, doing, spans = self.started_at, "imports", []
            for phase, at in child.phase_log:
                spans.append(f"{doing} {at - t:.1f}")
                doing, t = phase, at
            parts.append(f"{child.name}: " + ", ".join(spans))
        return "; ".join(parts)

    def child(self, name: str) -> Child:
        """The child process called ``name``."""
        for c in self.children:
            if c.name == name:
                return c
        raise KeyError(name)

    def has(self, name: str) -> bool:
        """Whether a child called ``name`` was started."""
        return any(c.name == name for c in self.children)

    def stopped(self) -> list[str]:
        """The names of the children stopped now (SIGSTOP/SIGTSTP)."""
        return [c.name for c in self.children if c.stopped()]

    def failed(self) -> Child | None:
        """A child that exited with a non-zero code, if any (exiting with 0 is how nodes end
        at the end of a run)."""
        for child in self.children:
            code = child.exit_code()
            if code not in (None, 0) and child.name not in self.optional:
                return child
        return None

    def wait_exit(self, names: Iterable[str], timeout_s: float,
                  poll: Callable[[float], None]) -> list[str]:
        """Wait until the named children exit on their own; the names still running after
        ``timeout_s`` (``poll(seconds)`` is called meanwhile, e.g. to spin ROS)."""
        names = [n for n in names if self.has(n)]
        deadline = time.monotonic() + timeout_s
        while True:
            running = [n for n in names if self.child(n).alive()]
            if not running or time.monotonic() > deadline \
                    or all(self.child(n).stopped() for n in running):
                return running  # (a stopped process cannot exit by itself)
            poll(0.05)

    def stop(self, names: Iterable[str] | None = None,
             grace_s: float | None = None) -> dict[str, int | None]:
        """Stop children (in the given order, default reverse start order) by process group;
        returns the exit codes."""
        order = ([self.child(n) for n in names if self.has(n)] if names is not None
                 else list(reversed(self.children)))
        return {child.name: self._stop_one(child, self.grace_s if grace_s is None else grace_s)
                for child in order}

    def _stop_one(self, child: Child, grace_s: float) -> int | None:
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
                proc.wait(timeout=grace_s)
            except subprocess.TimeoutExpired:
                self.echo(f"  {child.name} ignored {signal.Signals(sig).name}, escalating")
                if sig == signal.SIGTERM:
                    self._echo_stack(child)
        # members of the group that outlived the leader
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        return proc.wait()

    def _echo_stack(self, child: Child) -> None:
        """Before a fourws node is killed (it ignored SIGINT and SIGTERM: stuck in C), have it
        write its threads' stacks to its log (``runtime.STACK_SIGNAL``) and repeat where its
        main thread is."""
        if not child.phase_log:  # not a fourws node: the signal would only kill it
            return
        try:
            start = child.log_path.stat().st_size
            os.kill(child.proc.pid, STACK_SIGNAL)
        except OSError:
            return
        # faulthandler: "Current thread 0x... (most recent call first):" then its frames;
        # read until the dump has its main thread and stopped growing (or STACK_WAIT_S)
        deadline = time.monotonic() + STACK_WAIT_S
        dump: list[str] = []
        current: list[int] = []
        while time.monotonic() < deadline:
            time.sleep(0.05)
            try:
                with child.log_path.open("rb") as f:
                    f.seek(start)
                    lines = f.read(64 * 1024).decode("utf-8", "replace").splitlines()
            except OSError:
                return
            settled = current and lines == dump
            dump = lines
            current = [i for i, line in enumerate(dump) if line.startswith("Current thread")]
            if settled:
                break
        frames = dump[current[0]:current[0] + 1 + STACK_LINES] if current else []
        for line in frames:
            self.echo(f"    {line.strip()}")
        if frames:
            self.echo(f"    (every thread's stack: {child.log_path})")

    def exit_codes(self) -> dict[str, int | None]:
        """Exit code of every child (None while running)."""
        return {c.name: c.exit_code() for c in self.children}

    def kill_all(self) -> None:
        """SIGKILL every child process group at once (last resort)."""
        for child in self.children:
            if child.proc is not None:
                try:
                    os.killpg(child.proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                child.proc.wait()


__all__ = ["Child", "LOG_TAIL_LINES", "ProcessGroup", "describe_exit", "last_line", "node_command",
           "ros_args", "set_fifo", "use_node_spawner", "user_command"]
