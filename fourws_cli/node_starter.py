# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The node starter: one process that imports what every fourws node needs once, then forks
the nodes of a run, so a run does not pay Python's imports once per node.

Started as its own program (``python -m fourws_cli.node_starter FD``, a fresh interpreter:
never a fork of a launcher that may hold a ROS context), it imports rclpy, numpy, numba, the
messages and every node module of :data:`fourws_cli.nodes.NODES`, and then forks one node
per request, having set numba's compiler context up (its registries, about 0.6 s per
process otherwise). Nothing ROS-related is initialised in it: each node calls
``rclpy.init`` itself, with the run's environment, in its own process, as a node started
with ``exec`` does.

A forked node is the launcher's own child, as a started one is: the launcher is a child
subreaper (``PR_SET_CHILD_SUBREAPER``), the starter forks an intermediate process that forks
the node and exits at once, and the node is re-parented to the launcher, which waits for it
(exit code, signal) as for any child. A forked node runs only once the launcher has its
pid: it waits for a byte on a pipe the launcher writes after the starter's answer, so a node
forked by a starter that then failed to answer leaves at once instead of running beside the
copy started in its place. The node then takes the rest of what ``exec`` would have
given it: its own session and process group, the death signal when the launcher dies, the
log file as stdout/stderr, the phase pipe, the run's environment, working folder, signal mask
and ignored signals, fresh random seeds, and its command line as its process title (what
``ps`` and ``/proc/PID/cmdline`` show).

The starter is used only when it reproduces ``exec`` exactly: a node's environment must equal
the starter's except for the variables only read when a node runs (:data:`RUN_VARIABLES`);
with another environment the starter is restarted with it. A starter that cannot be started
or does not answer (:data:`READY_TIMEOUT_S`) leaves the nodes to be started as before, as
their own programs. On by default; ``FOURWS_NODE_STARTER=0`` (:data:`ENABLE_ENV`) starts every
node as its own program. Speed only: a node started either way behaves the same.
"""

from __future__ import annotations

import importlib
import inspect
import io
import json
import os
import random
import select
import signal
import socket
import subprocess
import sys
import threading
import time
from typing import Any

from fourws_cli.nodes import NODES, _stopped_while_starting, run_node
from fourws_ros.oslevel import (PR_SET_CHILD_SUBREAPER, PR_SET_PDEATHSIG, is_stopped, node_prefix,
                                prctl)

#: Variables a node reads only once it runs (rcl, Fast DDS, the launcher's phase pipe), which
#: therefore may differ between the starter and the node it forks; any other difference
#: (numba's, Python's, the loader's settings: read at import) restarts the starter.
RUN_VARIABLES = frozenset({
    "ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_STATIC_PEERS", "PYTHONUNBUFFERED",
    "FASTDDS_DEFAULT_PROFILES_FILE", "FASTRTPS_DEFAULT_PROFILES_FILE", "FOURWS_PHASE_FD",
    "PATH", "PWD", "OLDPWD", "_",
})
#: Environment switch: ``0`` starts every node as its own program; unset or anything else
#: (the default) forks the nodes through a starter.
ENABLE_ENV = "FOURWS_NODE_STARTER"
#: Time the starter gets to import everything and answer its first request, s.
READY_TIMEOUT_S = 60.0
#: Time the starter gets to answer a later request (a fork: milliseconds), s.
REPLY_TIMEOUT_S = 30.0
#: A forked node waits this long to be re-parented to the launcher, s.
REPARENT_TIMEOUT_S = 10.0

_MAX_MESSAGE = 1 << 20


def _env_key(env: dict[str, str]) -> dict[str, str]:
    return {k: v for k, v in env.items() if k not in RUN_VARIABLES}


def is_node_command(cmd: list[str]) -> bool:
    """Whether ``cmd`` is a fourws node of :func:`fourws_ros.processes.node_command`."""
    prefix = node_prefix()
    return cmd[:len(prefix)] == prefix and len(cmd) > len(prefix)


# ----------------------------------------------------------------------------- launcher side

class ForkedProcess:
    """A node forked by the starter, re-parented to this process: the parts of
    :class:`subprocess.Popen` the launcher uses (``pid``, ``poll``, ``wait``,
    ``send_signal``, ``returncode``)."""

    def __init__(self, pid: int, args: list[str]) -> None:
        self.pid = pid
        self.args = args
        self.returncode: int | None = None

    def poll(self) -> int | None:
        """The exit code (negative: killed by that signal), None while it runs."""
        if self.returncode is None:
            try:
                pid, status = os.waitpid(self.pid, os.WNOHANG)
            except ChildProcessError:  # reaped by someone else: it is gone, cause unknown
                self.returncode = -signal.SIGKILL
                return self.returncode
            if pid == self.pid:
                self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """Wait for the exit (``subprocess.TimeoutExpired`` after ``timeout`` s)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        delay = 0.0005
        while self.poll() is None:
            if deadline is not None and time.monotonic() >= deadline:
                raise subprocess.TimeoutExpired(self.args, timeout or 0.0)
            time.sleep(delay)
            delay = min(delay * 2, 0.02)
        return self.returncode  # type: ignore[return-value]

    def send_signal(self, sig: int) -> None:
        """Send ``sig`` to the node (nothing once it has exited)."""
        if self.poll() is None:
            os.kill(self.pid, sig)


class NodeStarter:
    """The launcher's end of one starter process (module docstring)."""

    def __init__(self, env: dict[str, str]) -> None:
        self.env = dict(env)
        self.broken = False
        self._ready = False
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self._sock = ours
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "fourws_cli.node_starter", str(theirs.fileno())],
                env=self.env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL, start_new_session=True, pass_fds=(theirs.fileno(),),
                preexec_fn=_starter_setup)
        finally:
            theirs.close()

    def _receive(self, timeout_s: float) -> dict[str, Any] | None:
        """The starter's next message; None if it ended, is stopped (SIGSTOP) or said
        nothing within ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while True:
            ready, _, _ = select.select([self._sock], [], [], 0.1)
            if ready:
                data = self._sock.recv(_MAX_MESSAGE)
                return json.loads(data) if data else None
            if time.monotonic() > deadline or self.proc.poll() is not None \
                    or is_stopped(self.proc.pid):
                return None

    def spawn(self, cmd: list[str], env: dict[str, str], log_fd: int, phase_fd: int,
              cwd: str) -> ForkedProcess | None:
        """Fork node ``cmd`` (``fourws_cli.main node NAME ...``); None if the starter cannot
        (then it is broken and the caller starts the node as its own program)."""
        if self.broken:
            return None
        sigmask = sorted(int(s) for s in signal.pthread_sigmask(signal.SIG_BLOCK, []))
        ignored = [int(s) for s in (signal.SIGINT, signal.SIGTERM)
                   if signal.getsignal(s) is signal.SIG_IGN]
        request = {"cmd": cmd, "argv": cmd[4:], "env": env, "cwd": cwd,
                   "launcher": os.getpid(), "sigmask": sigmask, "ignored": ignored}
        # the node runs only once this process has its pid: a node forked by a starter that
        # then failed to answer reads end-of-file here and leaves (never a second copy)
        go_r, go_w = os.pipe()
        try:
            if not self._ready:
                hello = self._receive(READY_TIMEOUT_S)
                if not hello or not hello.get("ready"):
                    raise OSError("the node starter did not get ready")
                self._ready = True
            socket.send_fds(self._sock, [json.dumps(request).encode()],
                            [log_fd, phase_fd, go_r])
            reply = self._receive(REPLY_TIMEOUT_S)
            if not reply or "pid" not in reply:
                raise OSError((reply or {}).get("error", "the node starter did not answer"))
            proc = ForkedProcess(int(reply["pid"]), cmd)
            os.write(go_w, b"1")
        except (OSError, ValueError):
            self.close()
            return None
        finally:
            os.close(go_r)
            os.close(go_w)
        return proc

    def close(self) -> None:
        """Stop the starter (its nodes run on)."""
        self.broken = True
        try:
            self._sock.close()
        except OSError:
            pass
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()


def _starter_setup() -> None:
    """In the starter before exec: SIGKILL when the launcher dies."""
    prctl(PR_SET_PDEATHSIG, signal.SIGKILL)


_LOCK = threading.Lock()
_STARTER: list[NodeStarter] = []
_SUBREAPER: list[bool] = []


def enabled() -> bool:
    """Whether nodes may be forked by a starter here (Linux, a child subreaper possible,
    :data:`ENABLE_ENV` not ``0``)."""
    if os.environ.get(ENABLE_ENV, "1") == "0" or not sys.platform.startswith("linux"):
        return False
    if not _SUBREAPER:
        _SUBREAPER.append(prctl(PR_SET_CHILD_SUBREAPER, 1))
    return _SUBREAPER[0]


def install(start: bool = True) -> None:
    """Have :class:`fourws_ros.processes.ProcessGroup` fork the fourws nodes of this
    process's runs through a starter; ``start``: start it now (it imports for about a second
    meanwhile), with this process's environment, else with the first node's."""
    if not enabled():
        return
    if start:
        prestart()
    # rclpy with it: after the starter is on its way
    from fourws_ros import processes
    processes.use_node_spawner(spawn)


def prestart() -> None:
    """Start the starter with this process's environment unless one with it runs."""
    with _LOCK:
        _starter_for(dict(os.environ))


def _starter_for(env: dict[str, str]) -> NodeStarter | None:
    if _STARTER and (_STARTER[0].broken or _env_key(_STARTER[0].env) != _env_key(env)):
        _STARTER.pop().close()
    if not _STARTER:
        try:
            _STARTER.append(NodeStarter(env))
        except OSError:
            return None
    return _STARTER[0]


def spawn(cmd: list[str], env: dict[str, str], log_fd: int, phase_fd: int,
          cwd: str | None = None) -> ForkedProcess | None:
    """Fork fourws node ``cmd`` with ``env`` through the starter; None when it cannot
    (``cmd`` is not a fourws node, the starter is off or failed): start it with ``exec``."""
    if not is_node_command(cmd) or not enabled():
        return None
    with _LOCK:
        starter = _starter_for(env)
        if starter is None:
            return None
        # a starter that failed is broken: the next node's _starter_for replaces it
        return starter.spawn(cmd, env, log_fd, phase_fd, cwd or os.getcwd())


def shutdown() -> None:
    """Stop the starter of this process, if any (the nodes it forked run on)."""
    with _LOCK:
        while _STARTER:
            _STARTER.pop().close()


# ------------------------------------------------------------------------------ starter side

class _NodeJob:
    """What a forked node process runs once it has left the starter's loop."""

    def __init__(self, request: dict[str, Any], fds: list[int], ready_fd: int) -> None:
        self.request = request
        self.fds = fds
        self.ready_fd = ready_fd

    def run(self) -> int:
        req = self.request
        log_fd, phase_fd, go_fd = self.fds
        # own session and process group first: the launcher signals the group by this pid
        os.setsid()
        ignored = set(req.get("ignored", []))
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, signal.SIG_IGN if int(sig) in ignored else _stopped_while_starting)
        try:  # its title before the launcher knows it (ps, /proc/PID/cmdline)
            import setproctitle  # optional (fourws_cli.node_starter: imported by _preload)
            setproctitle.setproctitle(" ".join(req["cmd"]))
        except ImportError:
            pass
        os.write(self.ready_fd, b"1")
        os.close(self.ready_fd)
        launcher = int(req["launcher"])
        deadline = time.monotonic() + REPARENT_TIMEOUT_S
        while os.getppid() != launcher:  # until the intermediate process has exited
            if time.monotonic() > deadline:
                return 1
            time.sleep(0.0002)
        prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
        if os.getppid() != launcher:  # the launcher died meanwhile
            return 1
        go = os.read(go_fd, 1)  # the launcher has this pid (NodeStarter.spawn)
        os.close(go_fd)
        if go != b"1":
            return 0
        devnull = os.open(os.devnull, os.O_RDONLY)
        os.dup2(devnull, 0)
        os.dup2(log_fd, 1)
        os.dup2(log_fd, 2)
        for fd in (devnull, log_fd):
            os.close(fd)
        os.chdir(req["cwd"])
        os.environ.clear()
        os.environ.update(req["env"])
        # loaded: the node modules import it; not at the top, where the launcher starts the
        # starter before it imports rclpy
        from fourws_ros.runtime import PHASE_FD_ENV
        os.environ[PHASE_FD_ENV] = str(phase_fd)
        signal.pthread_sigmask(signal.SIG_SETMASK, [signal.Signals(s) for s in req["sigmask"]])
        # as Python opens them for a started node (PYTHONUNBUFFERED: the run's environment)
        sys.stdin = io.TextIOWrapper(io.FileIO(0, "r", closefd=False))
        sys.stdout = io.TextIOWrapper(io.FileIO(1, "w", closefd=False), line_buffering=True,
                                      write_through=True)
        sys.stderr = io.TextIOWrapper(io.FileIO(2, "w", closefd=False), line_buffering=True,
                                      write_through=True, errors="backslashreplace")
        sys.argv = list(req["cmd"][1:])
        random.seed()
        numpy = sys.modules.get("numpy")  # the starter's, imported by the node modules
        if numpy is not None:
            numpy.random.seed()
        return run_node(list(req["argv"]))


def _fork_node(request: dict[str, Any], fds: list[int]) -> int | _NodeJob:
    """Fork the node of ``request``: its pid here; in the node process, its job."""
    pid_r, pid_w = os.pipe()
    mid = os.fork()
    if mid == 0:  # the intermediate process: fork the node, tell its pid, leave
        os.close(pid_r)
        ready_r, ready_w = os.pipe()
        node = os.fork()
        if node == 0:
            os.close(ready_r)
            os.close(pid_w)
            return _NodeJob(request, fds, ready_w)
        os.close(ready_w)
        os.read(ready_r, 1)  # the node has its own process group
        os.write(pid_w, str(node).encode())
        os._exit(0)
    os.close(pid_w)
    os.waitpid(mid, 0)
    with os.fdopen(pid_r, "rb") as f:
        text = f.read().decode()
    if not text.isdigit():
        raise OSError("the node process could not be forked")
    return int(text)


def _preload() -> None:
    """Import every node's modules (a module that does not import here is imported, and
    fails, in its node as it would have otherwise)."""
    # the starter's purpose: rclpy loaded once for every node
    importlib.import_module("rclpy")
    try:
        import setproctitle  # optional: a node's title (test_dependencies, PIP_ONLY)
        # its first call finds the room for titles (the command line and the environment
        # after it): here, before a node's environment replaces this one
        setproctitle.setproctitle(" ".join([sys.executable, "-m", "fourws_cli.node_starter"]))
    except ImportError:
        pass
    for target in NODES.values():
        try:
            importlib.import_module(target.partition(":")[0])
        except Exception:  # noqa: BLE001 -- the node reports it when it runs
            pass


#: Interface packages every rclpy node uses besides its own topics' (parameter events and
#: services, /rosout, type descriptions, the clock), whose type support :func:`_warm` loads.
NODE_INTERFACES = ("rcl_interfaces.msg", "rcl_interfaces.srv", "type_description_interfaces.srv",
                   "rosgraph_msgs.msg")


def _warm() -> None:
    """Do once here what every node would do on its own while it is created (about 0.6 s of
    CPU per run of four nodes, measured): import the graph topics' messages, the tire
    models, the vehicle models and the laws (each imported on first use); load the type
    support of every message and service loaded (rclpy loads it when a publisher,
    subscription or service is created, importing rosidl_generator_py the first time); and
    fill :mod:`inspect`'s module cache (rclpy's logger looks the caller's module up on every
    call, and the first look-up maps every loaded module's file)."""
    # numpy, rclpy: in the starter only, after it is running (the command line imports this
    # module before it starts the starter)
    from fourws_control.registry import LAWS  # numpy: in the starter only
    from fourws_ros import topics  # rclpy: in the starter only
    from fourws_sim.models import MODELS  # numpy: in the starter only
    from fourws_sim.tires import TIRES  # numpy: in the starter only
    modules = [*NODE_INTERFACES, *TIRES.values(), *MODELS.values(),
               *{target.partition(":")[0] for target in LAWS.values()},
               *{f"{t.partition('/')[0]}.msg"
                 for t in {**topics.TOPIC_TYPES, **topics.EXTERNAL_TOPIC_TYPES}.values()}]
    for name in modules:
        try:
            importlib.import_module(name)
        except Exception:  # noqa: BLE001 -- a missing package fails in the node that needs it
            pass
    for name, module in list(sys.modules.items()):
        if name.rpartition(".")[2] not in ("msg", "srv") or module is None:
            continue
        for value in list(vars(module).values()):
            if (isinstance(value, type) and getattr(value, "_TYPE_SUPPORT", 0) is None
                    and hasattr(value, "__import_type_support__")):
                try:
                    value.__import_type_support__()
                except Exception:  # noqa: BLE001 -- the node that uses the type reports it
                    pass
    inspect.getframeinfo(sys._getframe())


def _compiler_context() -> None:
    """Set numba's compiler context up (its registries), which loading a cached kernel
    needs first."""
    try:
        from numba.core.registry import cpu_target  # numba: the starter's purpose
        cpu_target.typing_context.refresh()
        cpu_target.target_context.refresh()
    except Exception:  # noqa: BLE001 -- each node then does it itself
        pass


def prepare() -> None:
    """Everything the starter does once before it forks nodes: imports, warm-up, numba's
    compiler context."""
    _preload()
    _warm()
    _compiler_context()


def _serve(sock: socket.socket) -> _NodeJob | None:
    """Answer fork requests until the launcher closes its end; in a forked node, its job."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    prepare()
    sock.send(json.dumps({"ready": True}).encode())
    while True:
        try:
            data, fds, _flags, _addr = socket.recv_fds(sock, _MAX_MESSAGE, 3)
        except OSError:
            return None
        if not data:
            return None
        try:
            request = json.loads(data)
            if len(fds) != 3:
                raise OSError("a request needs the log, phase and go descriptors")
            result = _fork_node(request, fds)
        except (OSError, ValueError, KeyError) as exc:
            for fd in fds:
                os.close(fd)
            sock.send(json.dumps({"error": str(exc)}).encode())
            continue
        if isinstance(result, _NodeJob):
            sock.close()
            return result
        for fd in fds:
            os.close(fd)
        sock.send(json.dumps({"pid": result}).encode())


def main(argv: list[str]) -> int:
    """The starter process (``python -m fourws_cli.node_starter FD``)."""
    sock = socket.socket(fileno=int(argv[0]))
    job = _serve(sock)
    # in a forked node: its run, whose exceptions end it as they end a started node
    return 0 if job is None else job.run()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
