# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Shared pytest fixtures, and the ROS environment every test starts from.

The suite passes whatever the user's shell holds: the ROS settings a shell commonly exports
(:data:`USER_ROS_ENVIRONMENT`: a ``ROS_DOMAIN_ID`` of the user's own graph, static peers, a
middleware, a DDS profile or discovery server, security, a log format) are removed for the
whole session when this file is imported (before any fixture, module-scoped ones included),
and discovery is limited to this machine. A test that needs a domain reserves one
(``ros_domain``); everything else -- ``fourws run``, ``run_graph``, the nodes a test starts --
leases a free domain of its own (``fourws_ros.domains``), so runs side by side never share one.

``ros_domain``: a ROS domain ID reserved for one test (no other fourws test or run on this
machine holds it) with discovery limited to this machine, so ROS tests never see each other
and never send traffic off the machine.
"""

from __future__ import annotations

import faulthandler
import importlib.util
import io
import os
import signal
import sys
from contextlib import redirect_stdout
from pathlib import Path

import pytest

#: What a user's shell may export that changes how the suite's nodes find each other, talk or
#: log (tests read the nodes' log lines): removed for every test.
USER_ROS_ENVIRONMENT = (
    "ROS_DOMAIN_ID", "ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY", "ROS_DISCOVERY_SERVER",
    "ROS_SUPER_CLIENT", "RMW_IMPLEMENTATION", "FASTDDS_DEFAULT_PROFILES_FILE",
    "FASTRTPS_DEFAULT_PROFILES_FILE", "CYCLONEDDS_URI", "ROS_SECURITY_ENABLE",
    "ROS_SECURITY_STRATEGY", "ROS_SECURITY_KEYSTORE", "ROS_SECURITY_ENCLAVE_OVERRIDE",
    "RCUTILS_CONSOLE_OUTPUT_FORMAT", "RCUTILS_COLORIZED_OUTPUT", "RCUTILS_LOGGING_USE_STDOUT",
    "RCUTILS_LOGGING_BUFFERED_STREAM",
)
for _name in USER_ROS_ENVIRONMENT:
    os.environ.pop(_name, None)
# Whatever a test does, DDS discovery stays on this machine.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"


def _install_node_starter() -> None:
    """The runs of the suite start their nodes as ``fourws run`` does: forked by the node
    starter unless ``FOURWS_NODE_STARTER=0`` (fourws_cli.node_starter), started
    with the first node's environment. Not for a core-only session on a machine without
    ROS."""
    try:
        from fourws_cli import node_starter
        node_starter.install(start=False)
    except ImportError:
        pass


_install_node_starter()


def _launcher_backstop_off() -> None:
    """The launcher's close has a process-wide faulthandler timer (launcher_node
    CLOSE_BACKSTOP); the suite's own per-test timer (HARD_TIMEOUT_S below) covers the same
    case, and faulthandler has one timer per process."""
    try:
        from fourws_ros import launcher_node
        launcher_node.CLOSE_BACKSTOP = False
    except ImportError:
        pass


_launcher_backstop_off()


@pytest.fixture(autouse=True)
def _numba_cpu_features_kept():
    """``fourws study`` run in-process sets numba's CPU features to 512-bit vectors for its
    process and the workers it starts (``fourws_sim.lanes.use_wide_vectors``): kept, it gave
    every later test's nodes other compile targets, so each compiled its kernels again instead
    of loading ``make setup``'s cache. Restored after each test."""
    import sys

    before = os.environ.get("NUMBA_CPU_FEATURES")
    yield
    if os.environ.get("NUMBA_CPU_FEATURES") != before:
        if before is None:
            os.environ.pop("NUMBA_CPU_FEATURES", None)
        else:
            os.environ["NUMBA_CPU_FEATURES"] = before
        config = sys.modules.get("numba.core.config")
        if config is not None:
            config.CPU_FEATURES = before


@pytest.fixture
def ros_domain(monkeypatch: pytest.MonkeyPatch):
    """Reserve a ROS domain ID for the test and export it (``ROS_DOMAIN_ID``)."""
    from fourws_ros.domains import reserve_domain_id

    lease = reserve_domain_id()
    monkeypatch.setenv("ROS_DOMAIN_ID", str(lease.domain_id))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    try:
        yield lease.domain_id
    finally:
        lease.release()


@pytest.fixture
def rclpy_context():
    """An rclpy context of the test's own (use with :func:`ros_domain`), shut down after."""
    import rclpy
    from rclpy.context import Context

    ctx = Context()
    rclpy.init(args=[], context=ctx)
    try:
        yield ctx
    finally:
        ctx.try_shutdown()


#: A test running this long is ended with the whole session, every thread's stack printed: the
#: C-level watchdog of :mod:`faulthandler` (pytest.ini's ``timeout`` fails a test earlier, but
#: through a Python handler, which never runs while the main thread is blocked in C).
HARD_TIMEOUT_S = 900.0
_TERMINAL_FD: list[int] = []

#: Fast DDS's own cleaner of shared-memory files left by processes that died without closing
#: them (``fastdds shm clean``), shipped with the ROS wheels under the venv.
_FASTDDS_SHM_CLEAN = Path(sys.prefix) / "tools" / "fastdds" / "shm" / "clean.py"


def _clean_zombie_shm() -> None:
    """Remove the Fast DDS shared-memory ports and segments whose owner process is gone.

    The suite kills and stops nodes on purpose; a node killed holding a shared-memory port
    leaves it behind, and Fast DDS reopens that port for a later participant of the same
    domain and participant index (known Fast DDS failures after ``kill -9``: participants that
    hang while created, readers that never receive). Each file is removed only when no living
    process holds its lock (the cleaner's own check), so running nodes are never touched."""
    if not _SHM_CLEANER:
        if not _FASTDDS_SHM_CLEAN.is_file():
            return  # not the venv of `make setup` (a system ROS install): its users' business
        spec = importlib.util.spec_from_file_location("fourws_test_fastdds_shm_clean",
                                                      _FASTDDS_SHM_CLEAN)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        _SHM_CLEANER.append(module.Clean)
    with redirect_stdout(io.StringIO()):
        _SHM_CLEANER[0]().run(force=False)


_SHM_CLEANER: list = []


@pytest.hookimpl(trylast=True)
def pytest_configure(config: pytest.Config) -> None:
    terminal = config.pluginmanager.get_plugin("terminalreporter")
    if terminal is not None:
        _TERMINAL_FD.append(os.dup(terminal._tw._file.fileno()))
    _clean_zombie_shm()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    """Arm the hard watchdog for one test (its stacks go to the terminal, not the capture)."""
    out = os.fdopen(os.dup(_TERMINAL_FD[0]), "w") if _TERMINAL_FD else sys.__stderr__
    faulthandler.dump_traceback_later(HARD_TIMEOUT_S, exit=True, file=out)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
        if out is not sys.__stderr__:
            out.close()
        _clean_zombie_shm()


_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@pytest.fixture(autouse=True)
def _signal_handling_kept():
    """A test leaves this process's handling of SIGINT/SIGTERM as it found it: the processes
    later tests start inherit an ignored or blocked signal (``subprocess`` passes both on), and
    a node that ignores SIGINT cannot be stopped by the launcher or Ctrl-C."""
    handlers = {sig: signal.getsignal(sig) for sig in _SIGNALS}
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    yield
    changed = [sig.name for sig in _SIGNALS if signal.getsignal(sig) is not handlers[sig]]
    now_blocked = signal.pthread_sigmask(signal.SIG_SETMASK, blocked)
    for sig, handler in handlers.items():
        signal.signal(sig, handler)
    changed += [f"{sig.name} blocked" for sig in _SIGNALS if sig in now_blocked - blocked]
    assert not changed, f"the test changed this process's signal handling: {changed}"


_EXIT_STATUS: list[int] = []


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    _EXIT_STATUS.append(int(exitstatus))


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config: pytest.Config) -> None:
    """A run in this process whose launcher participant stuck in Fast DDS
    (``fourws_ros.launcher_node.ABANDONED``): leave with the session's status once everything
    is reported, as ``fourws`` does (a normal exit destroys the stuck participant and hangs)."""
    import sys

    launcher = sys.modules.get("fourws_ros.launcher_node")
    if launcher is not None and launcher.ABANDONED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_EXIT_STATUS[-1] if _EXIT_STATUS else 1)
