# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""What every fourws node reports about itself: counted publishers, the node's configuration,
the accounting fields of the status messages, and delivery before exit.

The recorder can only call a bag complete if it knows what was sent: every publishing node
counts its messages per topic (:class:`PublishCounts`) and puts the counts, its own status
included, into its status messages (:func:`fill_accounting`); the final status carries the
final counts. Before a node exits it waits until every subscriber has acknowledged what it
published (:func:`wait_delivered`), so no message dies with the process.
"""

from __future__ import annotations

import json
import time
from typing import Any, Mapping

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.duration import Duration

from fourws_ros import topics
from fourws_run.interface import WRITER_ROLES
from fourws_run.ticks import Rejections
from fourws_sim.errors import ParameterError

#: How long a node that ended its run waits for its subscribers to acknowledge everything, s.
DELIVERY_TIMEOUT_S = 30.0
#: The same for a node stopped by a signal (the run is being aborted; a subscriber that was
#: killed never acknowledges, and the launcher must not wait for its lease to expire), s.
SIGNAL_DELIVERY_TIMEOUT_S = 3.0


def delivery_timeout(node: Any) -> float:
    """How long ``node`` waits to deliver before exiting: long when it ended by itself
    (``finished``), short when a signal stopped it."""
    return DELIVERY_TIMEOUT_S if getattr(node, "finished", False) else SIGNAL_DELIVERY_TIMEOUT_S


class CountingPublisher:
    """An rclpy publisher that counts what it publishes (into a shared :class:`PublishCounts`)."""

    __slots__ = ("pub", "_counts", "topic")

    def __init__(self, pub: Any, counts: dict[str, int], topic: str) -> None:
        self.pub = pub
        self._counts = counts
        self.topic = topic

    def publish(self, msg: Any) -> None:
        """Publish ``msg`` (a message or serialized CDR bytes) and count it."""
        self.pub.publish(msg)
        self._counts[self.topic] += 1

    def get_subscription_count(self) -> int:
        """Matched subscriptions (rclpy's)."""
        return int(self.pub.get_subscription_count())


class PublishCounts:
    """Per-topic counts of everything one node publishes."""

    def __init__(self) -> None:
        self.counts: dict[str, int] = {}
        self.publishers: list[CountingPublisher] = []

    def publisher(self, node: Any, topic: str) -> CountingPublisher:
        """A counted publisher of graph topic ``topic`` with the topic's QoS."""
        pub = node.create_publisher(topics.message_class(topic), topic, topics.TOPIC_QOS[topic])
        self.counts.setdefault(topic, 0)
        counted = CountingPublisher(pub, self.counts, topic)
        self.publishers.append(counted)
        return counted


def publish_node_config(node: Any, counts: PublishCounts, role: topics.Role,
                        config: Mapping[str, Any]) -> CountingPublisher:
    """Publish what this node runs with on ``/fourws/node_config`` (latched, one message):
    ``{"node": name, "role": role, "config": {...}}``; returns the publisher (keep it alive)."""
    pub = counts.publisher(node, topics.NODE_CONFIG)
    msg = topics.message_class(topics.NODE_CONFIG)()
    msg.data = json.dumps({"node": node.get_name(), "role": role.value, "config": dict(config)},
                          sort_keys=True, default=_plain)
    pub.publish(msg)
    return pub


def _plain(obj: Any) -> Any:
    if hasattr(obj, "tolist"):
        return obj.tolist()
    return str(obj)


def fill_accounting(msg: Any, counts: Mapping[str, int], rejections: Rejections) -> None:
    """Set the accounting fields of a ``SimulatorStatus`` or ``ManeuverStatus`` (the status
    itself must already be counted: call this with its count incremented)."""
    names = sorted(counts)
    msg.published_topics = names
    msg.published_counts = [int(counts[t]) for t in names]
    reasons = sorted(rejections.counts)
    msg.rejected_reasons = reasons
    msg.rejected_counts = [int(rejections.counts[r]) for r in reasons]
    msg.last_rejection = rejections.last


def publish_counted_status(pub: CountingPublisher, msg: Any, counts: PublishCounts,
                           rejections: Rejections) -> None:
    """Publish a status message whose accounting includes the message itself."""
    counts.counts[pub.topic] += 1
    fill_accounting(msg, counts.counts, rejections)
    pub.pub.publish(msg)


#: Name of the node parameter holding the subscribers each published topic must have matched
#: before a node publishes on it (JSON mapping topic -> count; empty: no wait).
EXPECTED_SUBSCRIBERS_PARAM = "expected_subscribers_json"


def parse_expected_subscribers(text: str) -> dict[str, int]:
    """The mapping of :data:`EXPECTED_SUBSCRIBERS_PARAM` (``""`` is no expectation).

    Raises
    ------
    ParameterError
        The text is not a JSON mapping of topic names to counts from 0 to 64.
    """
    if not text:
        return {}
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ParameterError(EXPECTED_SUBSCRIBERS_PARAM, f"not JSON ({exc})") from None
    if not isinstance(value, dict) or not all(
            isinstance(k, str) and type(n) is int and 0 <= n <= 64 for k, n in value.items()):
        raise ParameterError(EXPECTED_SUBSCRIBERS_PARAM,
                             "must map topic names to subscriber counts from 0 to 64")
    return value


class MatchWait:
    """Holds a node's first publications until each of its counted publishers has matched
    the subscribers the run expects on its topic.

    Graph discovery tells the launcher that a node subscribes to a topic before that
    subscription has matched each publisher, and a volatile publisher never resends what it
    published before a subscriber matched it: a recorder matched late would miss the run's
    first messages and a lockstep run would stall on them. Matching is checked by the
    publishers themselves (rclpy's matched-subscription count), once; after that it stays
    ready (a node that leaves later ends the run by other means).
    """

    def __init__(self, counts: PublishCounts, expected: Mapping[str, int]) -> None:
        self._counts = counts
        self._expected = dict(expected)
        self._ready = not self._expected

    @property
    def expected(self) -> dict[str, int]:
        """The expected subscriber count of each topic."""
        return dict(self._expected)

    def ready(self) -> bool:
        """True once every counted publisher has its expected subscribers."""
        if not self._ready:
            self._ready = not self.unmatched()
        return self._ready

    def _short(self) -> list[tuple[str, int, int]]:
        """``(topic, matched, expected)`` of each publisher short of its subscribers."""
        counted = ((p.topic, p.get_subscription_count(), self._expected.get(p.topic, 0))
                   for p in self._counts.publishers)
        return [(topic, have, want) for topic, have, want in counted if have < want]

    def unmatched(self) -> list[str]:
        """Topics whose publisher has fewer matched subscribers than expected."""
        return [topic for topic, _, _ in self._short()]

    def unmatched_text(self) -> list[str]:
        """The unmatched publishers, each as "1 of 2 subscribers of /fourws/odom"."""
        return [f"{have} of {want} subscribers of {topic}" for topic, have, want in self._short()]


def match_wait(node: Any, counts: PublishCounts) -> MatchWait:
    """Declare :data:`EXPECTED_SUBSCRIBERS_PARAM` on ``node`` and give the :class:`MatchWait`
    of its counted publishers (raises ``ParameterError`` for a malformed mapping)."""
    node.declare_parameter(EXPECTED_SUBSCRIBERS_PARAM, "", ParameterDescriptor(
        description="JSON mapping topic -> the number of the run's subscribers this node's "
                    "publisher of the topic must have matched before it publishes (empty: "
                    "no wait; fourws run sets it)", read_only=True))
    text = str(node.get_parameter(EXPECTED_SUBSCRIBERS_PARAM).value)
    return MatchWait(counts, parse_expected_subscribers(text))


class RecorderWatch:
    """What the recorder reports stored (``/fourws/recorder_status``), for a node that must
    know its messages are in the bag before it exits."""

    #: A recorder that has sent no status for this long (wall time; it reports at least
    #: every recorder_node.STATUS_HEARTBEAT_S, 0.5 s)
    #: is gone -- killed, or stopped -- and there is no point waiting for it, s.
    SILENT_S = 2.0

    def __init__(self, node: Any, subscribe: bool = True) -> None:
        self.stored: dict[str, int] | None = None
        self._heard = 0.0
        if subscribe:
            node.create_subscription(topics.message_class(topics.RECORDER_STATUS),
                                     topics.RECORDER_STATUS, self.update, topics.STATUS_READ_QOS)

    def update(self, msg: Any) -> None:
        """Take a ``RecorderStatus`` (the subscription calls it; a node that subscribes itself
        passes the messages on)."""
        self.stored = dict(zip(msg.topics, (int(n) for n in msg.stored)))
        self._heard = time.monotonic()

    def silent(self) -> bool:
        """A recorder was heard, and has been silent for :attr:`SILENT_S` since."""
        return self.stored is not None and time.monotonic() - self._heard > self.SILENT_S

    def holds(self, counts: Mapping[str, int]) -> bool:
        """The recorder has stored at least ``counts`` of every topic it records that only
        this node publishes."""
        if self.stored is None:
            return False
        for topic, n in counts.items():
            if topic in self.stored and len(WRITER_ROLES[topic]) == 1 \
                    and self.stored[topic] < n:
                return False
        return True


def wait_delivered(counts: PublishCounts, logger: Any, executor: Any = None,
                   watch: RecorderWatch | None = None,
                   timeout_s: float = DELIVERY_TIMEOUT_S) -> bool:
    """Wait until every matched subscriber has acknowledged what this node published (the
    simulator needs the maneuver's last status, the recorder everything) and, once a recorder
    was heard (``watch``), until it reports them stored. Gives up, False with an error logged,
    after ``timeout_s`` or once the recorder has gone silent (a killed recorder's readers stay
    in the graph for seconds and never acknowledge).

    Acknowledged is not stored: the recorder takes a message only from a publisher the ROS
    graph names as the run's node, and holds the others until the graph does. A node that
    left at once, its messages acknowledged, could leave the graph before the recorder's
    graph had named it (a run that ended within a second of starting, on a loaded machine):
    its messages were then foreign for good and the bag incomplete."""
    deadline = time.monotonic() + timeout_s
    now = Duration(seconds=0)
    while True:
        if all(c.pub.wait_for_all_acked(now) for c in counts.publishers) and (
                watch is None or watch.stored is None or watch.holds(counts.counts)):
            return True
        if watch is not None and watch.silent():
            logger.error("the recorder went silent before it held everything this node "
                         "published")
            return False
        if time.monotonic() > deadline:
            late = [c.topic for c in counts.publishers if not c.pub.wait_for_all_acked(now)]
            if late:
                logger.error(f"not every subscriber acknowledged {', '.join(late)} within "
                             f"{timeout_s:.0f} s")
            else:
                logger.error(f"the recorder did not report storing everything this node "
                             f"published within {timeout_s:.0f} s (published "
                             f"{counts.counts}, stored {watch.stored if watch else {}})")
            return False
        if executor is not None:
            executor.spin_once(timeout_sec=0.05)
        else:
            time.sleep(0.05)


__all__ = ["CountingPublisher", "DELIVERY_TIMEOUT_S", "EXPECTED_SUBSCRIBERS_PARAM", "MatchWait",
           "PublishCounts", "RecorderWatch", "SIGNAL_DELIVERY_TIMEOUT_S", "delivery_timeout",
           "fill_accounting", "parse_expected_subscribers", "publish_counted_status",
           "publish_node_config", "wait_delivered"]
