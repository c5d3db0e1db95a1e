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

import os

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
