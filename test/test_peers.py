# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The start-up wait of a node's peers (fourws_ros.peers.PeerWatch) names everything the node
waits for, the waits beside the matched counts included, and gives up on them at the timeout.

Source: the liveness contract of fourws_ros.peers (a hand-started graph never waits forever;
the one line names the missing part), on a fake node and clock: counts and messages only.
"""

from __future__ import annotations

from fourws_ros import peers, topics


class _Log:
    def __init__(self) -> None:
        self.lines: list[tuple[str, str]] = []

    def info(self, text: str) -> None:
        self.lines.append(("info", text))

    def warning(self, text: str) -> None:
        self.lines.append(("warning", text))


class _Node:
    def __init__(self) -> None:
        self.log = _Log()

    def create_subscription(self, *args, **kwargs) -> None:
        return None

    def get_logger(self) -> _Log:
        return self.log

    def get_name(self) -> str:
        return "fourws_simulator"

    def get_subscriptions_info_by_topic(self, topic: str) -> list:
        return []


class _Pub:
    def __init__(self, n: int) -> None:
        self.n = n

    def get_subscription_count(self) -> int:
        return self.n


def test_waits_beside_the_matches_are_reported_and_time_out() -> None:
    """Every peer matched, the recorder's first status missing: the node waits (no start),
    logs the missing status every REPORT_EVERY_S (a warning after WARN_AFTER_S: the launcher
    keeps those as the node's last words), and gives up at the timeout naming it."""
    now = [0.0]
    node = _Node()
    watch = peers.PeerWatch(node, 30.0, monotonic=lambda: now[0])
    watch.need_subscribers(_Pub(3), topics.STATE, 3)
    missing = ["a first /fourws/recorder_status"]
    assert watch.ready()  # the matches alone are there
    now[0] = 2.0  # before the first report
    assert watch.check_startup(lambda: missing) == ""
    assert node.log.lines == []
    now[0] = peers.REPORT_EVERY_S
    assert watch.check_startup(lambda: missing) == ""
    assert node.log.lines == [("info", "waiting 5 s for a first /fourws/recorder_status")]
    now[0] = peers.WARN_AFTER_S + 1.0
    assert watch.check_startup(lambda: missing) == ""
    assert node.log.lines[-1] == ("warning",
                                  "waiting 11 s for a first /fourws/recorder_status")
    now[0] = 31.0
    why = watch.check_startup(lambda: missing)
    assert why == ("gave up after 30 s (startup_timeout_s) waiting for a first "
                   "/fourws/recorder_status")
    # the waits met: nothing to wait for, no reason to give up
    assert watch.check_startup(lambda: []) == ""


def test_missing_matches_and_other_waits_are_named_together() -> None:
    """An unmatched need and another wait: the line names both, the count first."""
    now = [0.0]
    node = _Node()
    watch = peers.PeerWatch(node, 0.0, monotonic=lambda: now[0])
    watch.need_subscribers(_Pub(1), topics.STATE, 3)
    now[0] = 5.0
    assert watch.check_startup(lambda: ["2 of 4 subscribers of /fourws/sim_status"]) == ""
    assert node.log.lines == [("info", "waiting 5 s for 1 of 3 subscribers of /fourws/state "
                               "(there: none); 2 of 4 subscribers of /fourws/sim_status")]
    now[0] = 1e6  # no timeout (0): a node that is part of a bigger system waits
    assert watch.check_startup(lambda: []) == ""


def test_the_wait_switches_to_warnings_through_rclpys_own_logger() -> None:
    """The same wait logged by a real rclpy logger across the switch from info to warning:
    rclpy refuses a call site whose severity changes (ValueError 'Logger severity cannot be
    changed between calls', which ended every node of a hand-started graph waiting past
    WARN_AFTER_S)."""
    import rclpy.logging

    now = [0.0]
    node = _Node()
    logger = rclpy.logging.get_logger("fourws_test_peers")  # one object, as a node's
    node.get_logger = lambda: logger
    watch = peers.PeerWatch(node, 0.0, monotonic=lambda: now[0])
    for t in (peers.REPORT_EVERY_S, peers.WARN_AFTER_S + 1.0, peers.WARN_AFTER_S + 7.0):
        now[0] = t
        assert watch.check_startup(lambda: ["a first /fourws/recorder_status"]) == ""
