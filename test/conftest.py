# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Shared pytest fixtures.

``ros_domain``: a ROS domain ID reserved for one test (no other fourws test or run on this
machine holds it) with discovery limited to this machine, so ROS tests never see each other
and never send traffic off the machine.
"""

from __future__ import annotations

import os

import pytest

# Whatever a test does, DDS discovery stays on this machine.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"


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
