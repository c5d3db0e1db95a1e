# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The suite does not depend on the user's ROS environment (conftest.py): what a shell exports
is gone in every test, and a test's domain is its own.

Sources: the list of conftest.py, ``fourws_ros.domains.DOMAIN_ID_RANGE`` (the domains fourws
leases), and a pytest session started with such a shell's variables exported.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from conftest import USER_ROS_ENVIRONMENT

from fourws_ros.domains import DOMAIN_ID_RANGE, reserve_domain_id

ROOT = Path(__file__).resolve().parent.parent
#: What a ROS user's shell often holds (the issue's case: ROS_DOMAIN_ID=91 exported).
USER_SHELL = {"ROS_DOMAIN_ID": "91", "ROS_LOCALHOST_ONLY": "1", "ROS_STATIC_PEERS": "10.0.0.9",
              "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET",
              "RCUTILS_CONSOLE_OUTPUT_FORMAT": "{time}: {message}",
              "RCUTILS_COLORIZED_OUTPUT": "1", "RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"}


def test_no_user_ros_setting_reaches_a_test():
    """None of conftest's list is set, and discovery stays on this machine."""
    assert [name for name in USER_ROS_ENVIRONMENT if name in os.environ] == []
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert set(USER_SHELL) - {"ROS_AUTOMATIC_DISCOVERY_RANGE"} <= set(USER_ROS_ENVIRONMENT)


def test_a_reserved_domain_is_the_tests_own(ros_domain):
    """``ros_domain`` exports a leased domain (fourws's range), never a user's."""
    assert os.environ["ROS_DOMAIN_ID"] == str(ros_domain)
    assert ros_domain in DOMAIN_ID_RANGE


def test_runs_one_after_the_other_never_share_a_domain():
    """A domain released is the last one leased again: each of 90 leases taken and released in
    turn gets a domain none of the others got (what a run left behind on its domain never
    meets the next run of this process); 10 of the 100 may be held meanwhile by runs beside."""
    seen = []
    for _ in range(len(DOMAIN_ID_RANGE) - 10):
        lease = reserve_domain_id()
        seen.append(lease.domain_id)
        lease.release()
    assert len(set(seen)) == len(seen) and set(seen) <= set(DOMAIN_ID_RANGE)


def test_a_shells_ros_settings_are_removed_for_the_session(tmp_path):
    """A pytest session started from a shell that exports USER_SHELL runs the first test of
    this file and passes: the settings are removed before any test (conftest is imported
    first)."""
    env = {**os.environ, **USER_SHELL, "PYTEST_ADDOPTS": ""}
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           f"{Path(__file__)}::test_no_user_ros_setting_reaches_a_test"],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "1 passed" in done.stdout
