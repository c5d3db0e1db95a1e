# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""What every fourws node's ``main()`` shares: init, signals, spinning, clean shutdown.

A node process ends in one of four ways, with a distinct exit code the launcher reports:

* :data:`EXIT_OK` (0) — SIGINT/SIGTERM or the node asked to stop (``node.finished``);
* :data:`EXIT_USER_ERROR` (2) — a bad start-up input: a :class:`fourws_sim.errors.FourwsError`
  (bad parameter, unknown name, malformed YAML), a parameter rclpy refuses (type, range,
  name), a ``--params-file`` that is empty, has no section for the node or sets a parameter
  the node does not declare, or arguments rcl cannot take (a missing, binary or malformed
  ``--params-file``); its message, on one line that names the field or file, goes to stderr;
* :data:`EXIT_RUN_STOPPED` (3) — the node stopped the run for a reason of the simulation
  (non-finite state, ...), given in ``node.stop_reason``;
* :data:`EXIT_INCOMPLETE` (4) — the recorder closed a bag that does not hold every message
  the run published (its accounting says what is missing);
* :data:`EXIT_PEERS` (5) — the node gave up on its peers: a node it needs never came, refused
  its configuration, or left the graph (:mod:`fourws_ros.peers`);
* anything else — a crash (Python traceback in the log).

Signals are handled here rather than by rclpy (``SignalHandlerOptions.NO``) so a node can
finish its work on SIGINT/SIGTERM — the recorder drains its queues and closes the bag — before
the context shuts down.
"""

from __future__ import annotations

import faulthandler
import json
import os
import re
import signal
import sys
import threading
import time
from typing import Any, Callable, Sequence

import rclpy
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from fourws_ros import topics
from fourws_ros.lean_executor import LeanExecutor
from fourws_sim.config_yaml import read_yaml
from fourws_sim.errors import FourwsError, ParameterError, one_line

EXIT_OK = 0
EXIT_CRASH = 1
EXIT_USER_ERROR = 2
EXIT_RUN_STOPPED = 3
EXIT_INCOMPLETE = 4
EXIT_PEERS = 5

#: How long the executor runs callbacks before the spin loop checks for a signal or a finished
#: node again, s (how quickly a signal is noticed).
SPIN_TIMEOUT_S = 0.05
#: Environment variable naming a file descriptor the launcher reads the node's start-up
#: phases from (one line each: ``configuring``, ``compiling``, ``ready``, ``failed: ...``).
PHASE_FD_ENV = "FOURWS_PHASE_FD"
#: A node that refused its configuration in a graph started by hand keeps announcing why on
#: ``/fourws/node_config`` for this long before it exits, so peers starting meanwhile stop
#: with its reason instead of waiting for their start-up timeout, s.
ANNOUNCE_FAILURE_S = 10.0
#: Once a node's work is done, the ROS teardown (destroying publishers, shutting rcl down)
#: gets this long; the middleware can deadlock there (a DataWriter's destructor waiting for
#: its event thread), and a node that did its job must not hang: the process then exits
#: with the code it had, s.
TEARDOWN_TIMEOUT_S = 10.0
#: How much longer the interpreter-free backstop of that limit waits, s.
TEARDOWN_BACKSTOP_S = 2.0


def report_phase(phase: str) -> None:
    """Tell the launcher (if one started this process, :data:`PHASE_FD_ENV`) the node's
    start-up phase; without a launcher, nothing happens."""
    fd = os.environ.get(PHASE_FD_ENV, "")
    if not fd.isdigit():
        return
    try:
        os.write(int(fd), (phase.replace("\n", " ") + "\n").encode("utf-8", "replace"))
    except OSError:
        pass  # the launcher has gone: nothing to tell


def _announce_failure(name: str, error: str) -> None:
    """Publish ``{"node", "error"}`` on ``/fourws/node_config`` (latched) and keep it there
    for :data:`ANNOUNCE_FAILURE_S` (peers of a hand-started graph stop with the reason); not
    when a launcher watches the process (it has the reason at once)."""
    if os.environ.get(PHASE_FD_ENV):
        return
    try:
        node = rclpy.create_node(name)
        pub = node.create_publisher(topics.message_class(topics.NODE_CONFIG),
                                    topics.NODE_CONFIG, topics.LATCHED_QOS)
        msg = topics.message_class(topics.NODE_CONFIG)()
        msg.data = json.dumps({"node": node.get_name(), "error": error})
        pub.publish(msg)
        flag = _StopFlag()
        signal.signal(signal.SIGINT, flag)
        signal.signal(signal.SIGTERM, flag)
        deadline = time.monotonic() + ANNOUNCE_FAILURE_S
        while flag.signal is None and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.1)
        node.destroy_node()
    except rclpy_implementation.RCLError:
        pass


class _StopFlag:
    """Set by SIGINT/SIGTERM."""

    def __init__(self) -> None:
        self.signal: int | None = None

    def __call__(self, signum: int, _frame: Any) -> None:
        self.signal = signum


def _rcl_message(exc: BaseException) -> str:
    """An rcl error on one line, without the C source locations rcl appends
    (``..., at ./src/parser.c:263``)."""
    return re.sub(r",? at \S+:\d+", "", one_line(exc)).strip() or type(exc).__name__


#: The signal on which a node writes every thread's stack to its log (see :func:`run_node`).
STACK_SIGNAL = signal.SIGUSR1


def _exit_after(seconds: float, code: int, name: str) -> None:
    """Exit the process with ``code`` if it is still there ``seconds`` from now (a daemon
    timer: a normal exit before then ends it)."""
    def stop() -> None:
        print(f"[{name}] the ROS teardown did not finish within {seconds:g} s; exiting",
              file=sys.stderr, flush=True)
        os._exit(code)

    timer = threading.Timer(seconds, stop)
    timer.daemon = True
    timer.start()


def _params_files(argv: Sequence[str]) -> list[str]:
    return [value for flag, value in zip(argv, argv[1:]) if flag == "--params-file"]


def check_params_files(argv: Sequence[str]) -> None:
    """Read every ``--params-file`` of ``argv`` with fourws's strict YAML reader before rcl
    does: rcl keeps the last of two equal keys without a word and reads a NUL-cut file up to
    the NUL, and starts a node on an empty file; here each is an error naming the key or the
    file.

    Raises
    ------
    fourws_sim.errors.ParameterError
        A parameter file that is missing, not UTF-8, not valid YAML, has a duplicate key, or
        is empty (no node section).
    """
    for path in _params_files(argv):
        data = read_yaml(path)
        if not isinstance(data, dict) or not data:
            raise ParameterError("<file>", "is empty or not a ROS 2 parameter file (a "
                                 "section per node: NODE: {ros__parameters: {...}}, or /** for "
                                 "every node)", path)


def _section_matches(pattern: str, fqn: str) -> bool:
    """Whether a parameter-file section applies to the node ``fqn`` as rcl matches it: a
    leading ``/`` implied, ``*`` one name token, ``**`` any number of them (ROS 2 design
    article "ROS command line arguments")."""
    want = [t for t in pattern.split("/") if t]
    have = [t for t in fqn.split("/") if t]

    def match(i: int, j: int) -> bool:
        if i == len(want):
            return j == len(have)
        if want[i] == "**":
            return any(match(i + 1, k) for k in range(j, len(have) + 1))
        return j < len(have) and want[i] in ("*", have[j]) and match(i + 1, j + 1)

    return match(0, 0)


def _flat_names(params: Any, prefix: str = "") -> list[str]:
    if not isinstance(params, dict):
        return [prefix[:-1]] if prefix else []
    return [name for key, value in params.items()
            for name in _flat_names(value, f"{prefix}{key}.")]


def check_node_params(node: Any, argv: Sequence[str]) -> None:
    """Refuse what rclpy ignores without a word: a ``--params-file`` with no section for
    this node (its name, a wildcard such as ``/**``), or one that sets a parameter the node
    does not declare under such a section (a typo runs on the default). Sections of other
    nodes are theirs: several nodes share one file.

    Raises
    ------
    fourws_sim.errors.ParameterError
        Naming the parameter (or ``<file>``), the node and the file.
    """
    fqn = node.get_fully_qualified_name()
    for path in _params_files(argv):
        data = read_yaml(path)
        sections = [key for key in data if _section_matches(str(key), fqn)]
        if not sections:
            raise ParameterError("<file>", f"has no section for node {fqn} (its sections: "
                                 f"{', '.join(map(str, data))}; /** is read by every node)",
                                 path)
        for key in sections:
            params = data[key].get("ros__parameters") if isinstance(data[key], dict) else None
            for name in _flat_names(params):
                if not node.has_parameter(name):
                    valid = ", ".join(sorted(node.list_parameters([], 0).names))
                    raise ParameterError(name, f"not a parameter of node {fqn} (under "
                                         f"{key!r}; valid: {valid})", path)


def make_executor(context: Any = None, message_info: bool = False) -> Any:
    """The executor the nodes use: rclpy's C++ events executor when present (lower overhead per
    callback, which bounds the lockstep rate), else :class:`~fourws_ros.lean_executor.
    LeanExecutor`.

    ``message_info``: the node's callbacks take rclpy message info (publisher identity and
    sequence number), which the events executor cannot deliver: the lean executor (rclpy's
    single-threaded executor with a shorter wake-up). ``FOURWS_EXECUTOR``: ``events`` (the
    default, as above), ``lean`` (the lean executor for every node) or ``rclpy`` (rclpy's
    single-threaded executor instead of the lean one: what it is compared with)."""
    choice = os.environ.get("FOURWS_EXECUTOR", "events")
    if not message_info and choice in ("events", "rclpy"):
        try:
            # optional: rclpy builds without the C++ events executor
            from rclpy.experimental import EventsExecutor
            return EventsExecutor(context=context)
        except ImportError:
            pass
    if choice == "rclpy":
        return SingleThreadedExecutor(context=context)
    return LeanExecutor(context=context)


def run_node(factory: Callable[[], Any], args: Sequence[str] | None = None,
             name: str = "fourws node") -> int:
    """Create the node with ``factory`` and spin it until a signal or until it finishes.

    The node may define ``finished`` (bool attribute: stop spinning), ``stop_reason`` (str:
    non-empty means the run was stopped, exit code :data:`EXIT_RUN_STOPPED`, or ``exit_code``
    if the node sets one), ``needs_message_info`` (class attribute: spin with an executor
    that delivers message info) and ``on_shutdown(executor)`` (called after the spin loop,
    before the context shuts down).

    Parameters
    ----------
    factory : callable
        Builds the node (after ``rclpy.init``).
    args : sequence of str, optional
        Command-line arguments (``--ros-args ...``), default ``sys.argv``.
    name : str
        Used in messages before the node exists.

    Returns
    -------
    int
        Exit code (see module docstring).
    """
    rcl_error = rclpy_implementation.RCLError
    argv = list(args) if args is not None else list(sys.argv)
    try:
        check_params_files(argv)
    except FourwsError as exc:
        print(f"[{name}] error: {one_line(exc)}", file=sys.stderr, flush=True)
        return EXIT_USER_ERROR
    flag = _StopFlag()
    signal.signal(signal.SIGINT, flag)
    signal.signal(signal.SIGTERM, flag)
    # a node that ignores SIGINT and SIGTERM is stuck in C (a Python handler runs only between
    # bytecodes); the launcher sends STACK_SIGNAL before it kills it, and every thread's Python
    # stack goes to the log (faulthandler's handler needs neither the GIL nor the stuck thread)
    faulthandler.register(STACK_SIGNAL, all_threads=True, chain=False)
    report_phase("configuring")
    try:
        rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    except rcl_error as exc:
        # rcl refuses the arguments: a --params-file that is missing, not YAML or not a
        # parameter file, a malformed -p or remapping
        print(f"[{name}] error: cannot start: {_rcl_message(exc)}", file=sys.stderr, flush=True)
        return EXIT_USER_ERROR
    node = None
    code = EXIT_OK
    try:
        try:
            node = factory()
            check_node_params(node, argv)
        except (FourwsError, ParameterException, NameValidationException) as exc:
            # ParameterException: a --ros-args/-p or --params-file value of the wrong type or
            # outside its descriptor's range
            print(f"[{name}] error: {one_line(exc)}", file=sys.stderr, flush=True)
            report_phase(f"failed: {one_line(exc)}")
            _announce_failure(name, one_line(exc))
            return EXIT_USER_ERROR
        except rcl_error as exc:
            print(f"[{name}] error: cannot start: {_rcl_message(exc)}", file=sys.stderr,
                  flush=True)
            report_phase(f"failed: cannot start: {_rcl_message(exc)}")
            return EXIT_USER_ERROR
        report_phase("ready")
        executor = make_executor(message_info=getattr(node, "needs_message_info", False))
        executor.add_node(node)
        # Callbacks run inside the executor for SPIN_TIMEOUT_S at a time (spinning until a
        # future that never completes, with that timeout), not one per spin_once: with the
        # events executor the loop between two callbacks then stays in C++, which saves
        # Python work on every message (about 10 % of the lockstep rate, where every process
        # takes several messages per tick). A signal's Python handler runs at the next callback
        # or timeout.
        never = Future()
        context_ok = node.context.ok
        while flag.signal is None and not getattr(node, "finished", False) and context_ok():
            executor.spin_until_future_complete(never, timeout_sec=SPIN_TIMEOUT_S)
        hook = getattr(node, "on_shutdown", None)
        if hook is not None:
            hook(executor)
        reason = getattr(node, "stop_reason", "")
        if reason:
            print(f"[{node.get_name()}] run stopped: {reason}", file=sys.stderr, flush=True)
            code = int(getattr(node, "exit_code", EXIT_RUN_STOPPED) or EXIT_RUN_STOPPED)
        _exit_after(TEARDOWN_TIMEOUT_S, code, node.get_name())
        # and should that timer never get the interpreter (a teardown stuck in C that holds
        # it), faulthandler's own thread writes every stack to the log and exits (code 1)
        faulthandler.dump_traceback_later(TEARDOWN_TIMEOUT_S + TEARDOWN_BACKSTOP_S, exit=True)
        executor.remove_node(node)
        executor.shutdown(timeout_sec=1.0)
    finally:
        # the node's work is done: a signal arriving while the process exits (the launcher
        # stopping a node that is already ending) must not turn a clean exit into a kill
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        if node is not None:
            node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return code
