# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Who published a message: the publishing node's name, from rclpy message info and the graph.

rclpy hands a subscription callback that takes two arguments the message info, which holds the
publisher's GID (``publisher_gid``) and its publication sequence number. The ROS graph maps
every publisher GID to its node (``get_publishers_info_by_topic``). The recorder and the
launcher use this to take messages only from the run's own nodes.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Mapping

from fourws_ros import topics


def publisher_gid(info: Any) -> bytes:
    """The publisher GID (16 bytes) of rclpy message info (``b""`` if it has none)."""
    gid = info.get("publisher_gid") if isinstance(info, dict) else None
    if not gid:
        return b""
    return bytes(gid.get("data", b""))[:16]


class PublisherNames:
    """Node names of publishers by GID, looked up in the ROS graph of ``node`` and cached.

    A publisher whose node the graph does not know yet (discovery still running) gives None;
    ask again later. A GID is a 12-byte participant prefix and a 4-byte entity id; every
    fourws process has one participant, so a publisher the graph cannot name any more (its
    node is gone, its last messages still queued) is named after the single node its
    participant was seen with.
    """

    def __init__(self, node: Any) -> None:
        self._node = node
        self._names: dict[bytes, str] = {}
        self._participants: dict[bytes, set[str]] = {}
        self._seen: dict[str, int] = {}  # topic -> matched publishers at its last look-up

    def refresh(self, *topics: str) -> int:
        """Learn the publishers of ``topics`` now; how many the graph named. Call it
        regularly while the publishers live (or :meth:`refresh_changed`): once a node is gone
        the graph no longer names its publishers, yet its last messages may still be waiting
        to be taken."""
        named = 0
        for topic in topics:
            for info in self._node.get_publishers_info_by_topic(topic):
                node_name = info.node_name
                if node_name and not node_name.startswith("_"):  # _NODE_NAME_UNKNOWN_
                    gid = bytes(info.endpoint_gid)[:16]
                    self._names[gid] = node_name
                    self._participants.setdefault(gid[:12], set()).add(node_name)
                    named += 1
        return named

    def refresh_changed(self, subscriptions: Mapping[str, Any]) -> list[str]:
        """:meth:`refresh` the topics (topic -> subscription) whose matched publishers changed
        in number since they were last looked up, or of which the graph did not name every
        matched publisher then; the topics refreshed. A look-up costs about 0.3 ms a topic
        (rmw's graph under its lock), so a recorder that refreshed its 15 topics ten times a
        second spent about a tenth of its CPU here; counting the matched publishers costs a
        few microseconds. A publisher replaced by another between two calls keeps the count:
        its first message is looked up by :meth:`name` while it lives."""
        changed = []
        for topic, sub in subscriptions.items():
            count = sub.get_publisher_count()
            if self._seen.get(topic) != count:
                changed.append(topic)
                self._seen[topic] = count
                named = self.refresh(topic)
                if named < count:
                    del self._seen[topic]  # the graph lags the matching: ask again next time
        return changed

    def name(self, topic: str, gid: bytes) -> str | None:
        """Node name of publisher ``gid`` on ``topic`` (None if not known yet)."""
        name = self._names.get(gid)
        if name is None:
            self.refresh(topic)
            name = self._names.get(gid)
        if name is None and len(self._participants.get(gid[:12], ())) == 1:
            (name,) = self._participants[gid[:12]]
        return name

    def of(self, topic: str, info: Any) -> str | None:
        """Node name of the publisher of a message received with ``info``."""
        return self.name(topic, publisher_gid(info))


#: A publisher the graph cannot name within this wall time is foreign, s: the bound of the
#: nodes' discovery phase (``fourws_ros.startup``), not a guess at how fast discovery is. Only
#: the unnamed publisher's own messages wait meanwhile (held per publisher), so a foreign
#: publisher that is never named delays nothing of the run.
UNIDENTIFIED_AFTER_S = 30.0
#: Messages held per unnamed publisher and topic; more are refused at once (a flood).
MAX_HELD = 20_000


class RunNodeFilter:
    """Takes messages only from the run's node of their role (the simulator's realtime
    answers, the controller's driver inputs); a foreign one is refused through
    ``refuse(topic, detail)``.

    A publisher the graph cannot name yet has its messages held, in order, and decided once it
    is named (:meth:`poll`): its first messages (a transient-local history handed over on
    matching) can arrive before discovery has told this node whose they are, and a refused
    first answer is never sent again (a realtime run then waited 60 s for its first driver
    input, seen 2 runs in 3 on a loaded machine). Held per publisher: the run's own messages
    never wait behind a foreign publisher's. Unnamed after :data:`UNIDENTIFIED_AFTER_S`:
    foreign.

    Parameters
    ----------
    names : PublisherNames
    expected : callable
        The run's node name for a role parameter name (``"maneuver_node"``).
    refuse : callable
        Counts a refusal: ``refuse(topic, detail)``.
    """

    def __init__(self, names: PublisherNames, expected: Callable[[str], str],
                 refuse: Callable[[str, str], Any]) -> None:
        self._names = names
        self._expected = expected
        self._refuse = refuse
        # (topic, publisher GID) -> (wall time of the first held, [(role, raw, handler)])
        self._held: dict[tuple[str, bytes],
                         tuple[float, list[tuple[str, bytes, Callable[[bytes], Any]]]]] = {}

    def offer(self, topic: str, info: Any, role: str, raw: bytes,
              handler: Callable[[bytes], Any]) -> None:
        """A message of ``topic`` received with ``info``: ``handler(raw)`` now if it comes
        from the run's node of ``role``, later if its publisher is not named yet."""
        gid = publisher_gid(info)
        key = (topic, gid)
        if key in self._held or self._names.name(topic, gid) is None:
            held = self._held.setdefault(key, (time.monotonic(), []))[1]
            if len(held) < MAX_HELD:
                held.append((role, raw, handler))
            else:
                self._refuse(topic, "publisher (unknown): more held than the bound")
        elif self._decide(topic, gid, role):
            handler(raw)

    def _decide(self, topic: str, gid: bytes, role: str) -> bool:
        node = self._names.name(topic, gid)
        if node == self._expected(role):
            return True
        self._refuse(topic, f"publisher {node or '(unknown)'}")
        return False

    def poll(self) -> None:
        """Pass on (or refuse) the held messages whose publisher is named now."""
        for key, (since, held) in list(self._held.items()):
            topic, gid = key
            if (self._names.name(topic, gid) is None
                    and time.monotonic() - since < UNIDENTIFIED_AFTER_S):
                continue
            del self._held[key]
            for role, raw, handler in held:
                if self._decide(topic, gid, role):
                    handler(raw)


def run_node_filter(node: Any, rejections: Any) -> RunNodeFilter:
    """A :class:`RunNodeFilter` of ``node`` whose run's node for a role is the node's parameter
    of that name (``"simulator_node"``); a foreign message is counted in ``rejections``
    (:class:`fourws_run.ticks.Rejections`) and said in the log, at most once a second."""
    def refuse(topic: str, detail: str) -> None:
        rejections.add(topic, "not from the run's node", detail)
        node.get_logger().warning(f"refused a {topic} message: not from the run's node "
                                  f"({detail})", throttle_duration_sec=1.0)
    return RunNodeFilter(PublisherNames(node),
                         lambda role_param: str(node.get_parameter(role_param).value), refuse)


def subscribe_from(node: Any, run_nodes: RunNodeFilter, topic: str, role: str,
                   handler: Callable[[bytes], Any], qos: Any) -> Any:
    """A raw subscription of ``topic`` that hands ``handler(raw)`` the messages of the run's
    node of ``role`` only (``run_nodes``). Each wake-up takes the whole queue: a foreign flood
    would otherwise hold the run's own message behind thousands of messages, one executor
    wake-up each. The node must spin an executor that delivers message info."""
    msg_type = topics.message_class(topic)
    holder: list[Any] = []

    def offer(raw: bytes, info: Any) -> None:
        run_nodes.offer(topic, info, role, raw, handler)

    def callback(raw: bytes, info: Any) -> None:
        offer(raw, info)
        drain(holder[0], msg_type, True, offer, topics.STREAM_DEPTH)

    holder.append(node.create_subscription(msg_type, topic, callback, qos, raw=True))
    return holder[0]


def drain(subscription: Any, msg_type: type, raw: bool,
          receive: Any, limit: int = 100_000) -> int:
    """Hand ``receive(msg, info)`` every message waiting in ``subscription``'s queue; the
    count. The executor wakes a callback for one message at a time, which costs far more
    than handling it: a node flooded by a foreign publisher would fall behind and lose the
    run's own messages from its queue. Called from the subscription's callback."""
    handle = subscription.handle
    n = 0
    while n < limit:
        with handle:
            taken = handle.take_message(msg_type, raw)
        if taken is None:
            break
        receive(*taken)
        n += 1
    return n


__all__ = ["MAX_HELD", "PublisherNames", "RunNodeFilter", "UNIDENTIFIED_AFTER_S", "drain",
           "publisher_gid", "run_node_filter", "subscribe_from"]
