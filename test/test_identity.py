# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Taking messages by publisher identity (``fourws_ros.identity.RunNodeFilter``), without a
ROS graph: a stand-in names publishers the way the graph does once discovery told it."""

from __future__ import annotations

from fourws_ros import identity


class _Names:
    """Names of publisher GIDs the test has 'discovered' so far."""

    def __init__(self) -> None:
        self.known: dict[bytes, str] = {}

    def name(self, _topic: str, gid: bytes) -> str | None:
        return self.known.get(gid)


def _info(gid: bytes) -> dict:
    return {"publisher_gid": {"data": gid}}


RUN, ROGUE = b"r" * 16, b"x" * 16


def _filter(names: _Names):
    taken, refused = [], []
    filt = identity.RunNodeFilter(names, lambda role: {"maneuver_node": "fourws_maneuver"}[role],
                                  lambda topic, detail: refused.append(detail))
    return filt, taken, refused


def test_the_runs_messages_never_wait_behind_an_unnamed_foreign_publisher():
    """A foreign publisher the graph cannot name holds only its own messages: the run's node's
    input, named, is taken at once (before, one held message blocked its topic for 5 s)."""
    names = _Names()
    filt, taken, refused = _filter(names)
    names.known[RUN] = "fourws_maneuver"
    filt.offer("/fourws/driver_input", _info(ROGUE), "maneuver_node", b"rogue-0", taken.append)
    filt.offer("/fourws/driver_input", _info(RUN), "maneuver_node", b"run-0", taken.append)
    assert taken == [b"run-0"] and refused == []
    names.known[ROGUE] = "rogue"
    filt.poll()
    assert taken == [b"run-0"] and refused == ["publisher rogue"]


def test_a_publisher_named_late_has_its_held_messages_taken_in_order():
    """The run's own first messages, arriving before discovery named their publisher, are
    taken once it is named, in the order they came, none lost."""
    names = _Names()
    filt, taken, refused = _filter(names)
    for k in range(3):
        filt.offer("/fourws/driver_input", _info(RUN), "maneuver_node", b"%d" % k, taken.append)
    filt.poll()
    assert taken == []  # not named yet, well within the bound
    names.known[RUN] = "fourws_maneuver"
    filt.poll()
    assert taken == [b"0", b"1", b"2"] and refused == []


def test_an_unnamed_publisher_is_foreign_after_the_bound(monkeypatch):
    names = _Names()
    filt, taken, refused = _filter(names)
    clock = [100.0]
    monkeypatch.setattr(identity.time, "monotonic", lambda: clock[0])
    filt.offer("/fourws/driver_input", _info(ROGUE), "maneuver_node", b"r", taken.append)
    clock[0] += identity.UNIDENTIFIED_AFTER_S - 0.1
    filt.poll()
    assert refused == []
    clock[0] += 0.2
    filt.poll()
    assert taken == [] and refused == ["publisher (unknown)"]


class _Graph:
    """A node's view of the graph: the publishers it names per topic, and how many the
    subscriptions have matched (the graph can lag the matching); counts its look-ups."""

    def __init__(self) -> None:
        self.named: dict[str, list[tuple[str, bytes]]] = {}
        self.lookups: list[str] = []

    def get_publishers_info_by_topic(self, topic: str) -> list:
        self.lookups.append(topic)
        return [type("Info", (), {"node_name": n, "endpoint_gid": list(g)})()
                for n, g in self.named.get(topic, [])]


class _Sub:
    def __init__(self) -> None:
        self.count = 0

    def get_publisher_count(self) -> int:
        return self.count


def test_publisher_names_are_looked_up_only_when_a_topics_publishers_change():
    """One look-up per topic whose matched publishers changed (or were not all named):
    ten quiet periods cost none; a new publisher is named at the next period, and one the
    graph does not name yet is asked for again until it is."""
    graph, subs = _Graph(), {"/a": _Sub(), "/b": _Sub()}
    names = identity.PublisherNames(graph)
    assert names.refresh_changed(subs) == ["/a", "/b"] and len(graph.lookups) == 2
    for _ in range(10):
        assert names.refresh_changed(subs) == []
    assert len(graph.lookups) == 2
    subs["/a"].count = 1
    graph.named["/a"] = [("fourws_simulator", RUN)]
    assert names.refresh_changed(subs) == ["/a"]
    assert names.name("/a", RUN) == "fourws_simulator" and len(graph.lookups) == 3
    subs["/b"].count = 1  # matched before the graph can name it
    assert names.refresh_changed(subs) == ["/b"]
    assert names.refresh_changed(subs) == ["/b"]  # asked again: not named yet
    graph.named["/b"] = [("fourws_maneuver", ROGUE)]
    assert names.refresh_changed(subs) == ["/b"]
    assert names.refresh_changed(subs) == []
    assert graph.lookups == ["/a", "/b", "/a", "/b", "/b", "/b"]
    assert names.name("/b", ROGUE) == "fourws_maneuver"
