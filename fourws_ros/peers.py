# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Liveness of a node's peers: wait for them with a bound, say what is missing, notice when
one is gone.

A node of a run needs other nodes: the simulator needs subscribers of its states and
publishers of the answers, the maneuver and the controller need the simulator's states. Under
``fourws run`` the launcher watches the processes; a graph started by hand (``ros2 run``, the
README's recipe) has nobody else to notice a peer that never came or went away, and would wait
forever. :class:`PeerWatch` makes every node end by itself instead:

* **start-up**: until each :class:`Need` is met, the node logs every :data:`REPORT_EVERY_S`
  what it waits for (the topic, how many of how many, the nodes that are there), and gives up
  after ``startup_timeout_s`` with one line naming the missing peers;
* **a peer that failed**: a fourws node that refuses its configuration announces the reason on
  ``/fourws/node_config`` before it exits (:func:`fourws_ros.runtime.run_node`); a peer
  that sees the announcement stops at once with that reason;
* **a peer that left**: once met, a need whose matched count falls below it again (the peer's
  process exited, or was killed and its lease expired) ends the node with a line naming the
  topic.

Counts are the rclpy objects' own matched counts (a publisher's matched subscriptions, a
subscription's matched publishers), the names come from the ROS graph.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from typing import Any, Callable

from fourws_ros import topics

#: Period of the "waiting for ..." log lines, s.
REPORT_EVERY_S = 5.0
#: Default start-up timeout of a node waiting for its peers, s: a peer that compiles its
#: numba kernels cold on a busy two-core machine takes up to about a minute, so twice that.
STARTUP_TIMEOUT_S = 120.0
#: A start-up wait longer than this is logged as a warning, s.
WARN_AFTER_S = 10.0
#: Key of a configuration-failure announcement on ``/fourws/node_config``.
ERROR_KEY = "error"


@dataclass
class Need:
    """One thing a node needs of the graph.

    Attributes
    ----------
    endpoint : object
        The node's own rclpy publisher (its matched subscriptions count) or subscription (its
        matched publishers count).
    topic : str
    count : int
        How many must be matched.
    what : str
        ``"subscribers"`` or ``"publishers"`` (of the topic, for the messages).
    """

    endpoint: Any
    topic: str
    count: int
    what: str

    def matched(self) -> int:
        """The endpoint's matched count now."""
        if self.what == "subscribers":
            return int(self.endpoint.get_subscription_count())
        return int(self.endpoint.get_publisher_count())


class PeerWatch:
    """The peers one node waits for and watches (module docstring).

    Parameters
    ----------
    node : rclpy Node
    timeout_s : float
        Start-up timeout, s (0: wait forever, as a node that is part of a bigger system may).
    monotonic : callable
        Wall clock, s.
    """

    def __init__(self, node: Any, timeout_s: float,
                 monotonic: Callable[[], float] = time.monotonic) -> None:
        self._node = node
        self._timeout = float(timeout_s)
        self._now = monotonic
        self.needs: list[Need] = []
        self._since = monotonic()
        self._reported = 0.0
        self._met = False
        self._present: list[set[str]] = []
        #: Configuration failures of peers announced on ``/fourws/node_config``.
        self.failed_peers: dict[str, str] = {}
        node.create_subscription(topics.message_class(topics.NODE_CONFIG), topics.NODE_CONFIG,
                                 self._on_config, topics.LATCHED_RECORD_QOS)

    def need_subscribers(self, publisher: Any, topic: str, count: int) -> None:
        """``publisher`` (of ``topic``) needs ``count`` matched subscribers."""
        if count > 0:
            self.needs.append(Need(publisher, topic, int(count), "subscribers"))

    def need_publishers(self, subscription: Any, topic: str, count: int = 1) -> None:
        """``subscription`` (of ``topic``) needs ``count`` matched publishers."""
        if count > 0:
            self.needs.append(Need(subscription, topic, int(count), "publishers"))

    def _on_config(self, msg: Any) -> None:
        try:
            data = json.loads(msg.data)
        except (TypeError, ValueError):
            return
        if isinstance(data, dict) and data.get(ERROR_KEY):
            name = str(data.get("node", "?"))
            if name != self._node.get_name():
                self.failed_peers[name] = str(data[ERROR_KEY])

    def missing(self) -> list[str]:
        """The unmet needs, each as "2 of 3 subscribers of /fourws/state (there:
        fourws_maneuver, fourws_controller)"."""
        out = []
        for need in self.needs:
            have = need.matched()
            if have < need.count:
                infos = (self._node.get_subscriptions_info_by_topic(need.topic)
                         if need.what == "subscribers"
                         else self._node.get_publishers_info_by_topic(need.topic))
                names = sorted({i.node_name for i in infos} - {self._node.get_name()})
                out.append(f"{have} of {need.count} {need.what} of {need.topic} (there: "
                           + (", ".join(names) if names else "none") + ")")
        return out

    def _names(self, need: Need) -> set[str]:
        infos = (self._node.get_subscriptions_info_by_topic(need.topic)
                 if need.what == "subscribers"
                 else self._node.get_publishers_info_by_topic(need.topic))
        return {i.node_name for i in infos} - {self._node.get_name()}

    def ready(self) -> bool:
        """Every need is met (once met, it stays so: :meth:`gone` watches after that)."""
        if not self._met:
            self._met = all(n.matched() >= n.count for n in self.needs)
            if self._met:  # who was there, to name the one that leaves
                self._present = [self._names(n) for n in self.needs]
        return self._met

    def check_startup(self, also: Callable[[], list[str]] | None = None) -> str:
        """While not :meth:`ready` (or ``also`` names more the node waits for): log what is
        missing every :data:`REPORT_EVERY_S` (a warning once the wait is longer than
        :data:`WARN_AFTER_S`: the launcher keeps a node's warnings as its last words); the
        reason to give up ('' to go on waiting): a peer's announced failure, or the
        start-up timeout."""
        failed = self.failure()
        if failed:
            return failed
        more = also() if also is not None else []
        if self.ready() and not more:
            return ""
        now = self._now()
        missing = (self.missing() if not self._met else []) + more
        if now - self._reported >= REPORT_EVERY_S and now - self._since >= 1.0:
            self._reported = now
            text = f"waiting {now - self._since:.0f} s for " + "; ".join(missing)
            # one call site per severity: rclpy refuses a call site that changes severity
            if now - self._since >= WARN_AFTER_S:
                self._node.get_logger().warning(text)
            else:
                self._node.get_logger().info(text)
        if self._timeout > 0.0 and now - self._since > self._timeout:
            return (f"gave up after {self._timeout:g} s (startup_timeout_s) waiting for "
                    + "; ".join(missing))
        return ""

    def failure(self) -> str:
        """A peer's announced configuration failure ('' if none)."""
        if not self.failed_peers:
            return ""
        name, error = next(iter(self.failed_peers.items()))
        return f"node {name} refused its configuration: {error}"

    def gone(self) -> str:
        """After start-up: the need whose peers all left ('' while every need has a match),
        or a peer's announced failure."""
        failed = self.failure()
        if failed:
            return failed
        if not self._met:
            return ""
        for need, present in zip(self.needs, self._present):
            have = need.matched()
            if have < need.count:
                left = sorted(present - self._names(need))
                who = f"node {', '.join(left)}" if left else "a node"
                return (f"{who} ({need.count - have} of the {need.count} {need.what} of "
                        f"{need.topic}) left the graph: it exited or was killed")
        return ""


__all__ = ["ERROR_KEY", "Need", "PeerWatch", "REPORT_EVERY_S", "STARTUP_TIMEOUT_S", "WARN_AFTER_S"]
