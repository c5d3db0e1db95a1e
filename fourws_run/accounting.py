# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Recording accounting: what the run's nodes published against what the bag holds.

A run is complete when, for every recorded topic, the bag holds exactly the messages the
run's own publishers sent: no fewer (lost), and nothing from anyone else (foreign messages are
not stored, only counted). Two independent sources say what was sent:

* the publishers' own counts: the simulator and the maneuver node report, in their status
  messages, how many messages they published per topic (the final status, ``final`` /
  ``done``, carries the final counts, itself included);
* DDS publication sequence numbers: every publisher numbers its messages 1, 2, 3, ...; the
  recorder sees the number of each message it takes, so a number it never saw is a message lost
  in transport (a *gap*), and the highest number is the publisher's count when it does not
  report one (a user's controller).

:class:`Ledger` is the recorder's live bookkeeping; :class:`RunAccount` its verdict, stored
in the bag's metadata (:mod:`fourws_run.bagfile`) and the run record;
:func:`account_from_messages` recomputes a verdict from a bag's own messages (repair, bags
without accounting).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

from fourws_run import interface

#: Version of the accounting layout in bags and run records.
ACCOUNT_VERSION = 1


@dataclass
class TopicAccount:
    """One topic's verdict.

    Attributes
    ----------
    topic : str
    stored : int
        Messages of the run's publishers in the bag.
    expected : int or None
        Messages the run's publishers sent (None: not known, e.g. a publisher's final count
        never arrived).
    foreign : int
        Messages from publishers outside the run (not stored).
    gaps : int
        Messages lost in transport (sequence numbers never seen).
    """

    topic: str
    stored: int
    expected: int | None
    foreign: int = 0
    gaps: int = 0

    @property
    def missing(self) -> int | None:
        """Messages sent but not stored (None if ``expected`` is unknown)."""
        return None if self.expected is None else max(self.expected - self.stored, 0)

    def problem(self) -> str:
        """What is wrong with this topic ('' if nothing)."""
        if self.expected is None:
            return f"{self.topic}: {self.stored} stored, the publisher's final count is unknown"
        if self.stored < self.expected:
            return f"{self.topic}: {self.expected - self.stored} of {self.expected} missing"
        if self.stored > self.expected:
            return (f"{self.topic}: {self.stored} stored but only {self.expected} "
                    "published")
        if self.gaps:
            return f"{self.topic}: {self.gaps} lost in transport"
        return ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"stored": self.stored, "expected": self.expected, "foreign": self.foreign,
                "gaps": self.gaps}


@dataclass
class RunAccount:
    """The accounting verdict of a recorded run.

    Attributes
    ----------
    topics : dict of str to TopicAccount
        One entry per recorded topic.
    notes : list of str
        Problems that are not a count of one topic (e.g. fewer commands stored than the
        simulator applied).
    foreign_publishers : dict of str to int
        Foreign messages per publisher (``"<topic> from <node>"``), for the run record.
    """

    topics: dict[str, TopicAccount]
    notes: list[str] = field(default_factory=list)
    foreign_publishers: dict[str, int] = field(default_factory=dict)

    @property
    def complete(self) -> bool:
        """Every topic's expected count is known and stored, nothing lost, no note."""
        return not self.problems()

    def problems(self) -> list[str]:
        """One line per problem (empty when complete)."""
        lines = [p for p in (t.problem() for t in self.topics.values()) if p]
        return lines + list(self.notes)

    def summary(self) -> str:
        """``complete`` or the problems, one line."""
        problems = self.problems()
        return "complete" if not problems else "INCOMPLETE: " + "; ".join(problems)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (stored in bag metadata and run records)."""
        return {"version": ACCOUNT_VERSION,
                "topics": {t: a.to_dict() for t, a in sorted(self.topics.items())},
                "notes": list(self.notes),
                "foreign_publishers": dict(sorted(self.foreign_publishers.items())),
                "complete": self.complete}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "RunAccount":
        """Inverse of :meth:`to_dict`.

        Raises
        ------
        ValueError
            Not an accounting mapping (or a newer layout).
        """
        if not isinstance(data, Mapping) or int(data.get("version", 0)) != ACCOUNT_VERSION:
            raise ValueError(f"not a version-{ACCOUNT_VERSION} recording accounting")
        topics = {}
        for topic, entry in dict(data["topics"]).items():
            expected = entry.get("expected")
            topics[topic] = TopicAccount(topic, int(entry["stored"]),
                                         None if expected is None else int(expected),
                                         int(entry.get("foreign", 0)), int(entry.get("gaps", 0)))
        return cls(topics, [str(n) for n in data.get("notes", [])],
                   {str(k): int(v) for k, v in dict(data.get("foreign_publishers", {})).items()})


@dataclass
class _WriterTally:
    """One publisher's messages on one topic as the recorder saw them.

    A publisher numbers its messages 1, 2, 3, ...; every number up to the highest one seen
    that is not stored is a message lost on the way (counted the same whatever order the
    messages were taken in).
    """

    stored: int = 0
    last_sequence: int = 0

    @property
    def gaps(self) -> int:
        """Messages lost in transport."""
        return max(self.last_sequence - self.stored, 0) if self.last_sequence else 0


#: The roles whose final status carries their published counts, with the topics they count.
REPORTING_ROLES: dict[interface.Role, tuple[str, ...]] = {
    interface.Role.SIMULATOR: interface.SIMULATOR_COUNTED,
    interface.Role.MANEUVER: interface.MANEUVER_COUNTED,
}


class Ledger:
    """The recorder's live accounting of one run.

    Parameters
    ----------
    topics : iterable of str
        The recorded topics.
    writers : mapping of Role to str
        The ROS node name of each role in this run (who may publish what:
        :data:`fourws_run.interface.WRITER_ROLES`).
    reporting : mapping of Role to tuple of str
        The roles whose final status carries their counts (default :data:`REPORTING_ROLES`;
        a user's driver in the maneuver's role reports none: its messages are counted by
        their sequence numbers).
    """

    def __init__(self, topics: Iterable[str], writers: Mapping[interface.Role, str],
                 reporting: Mapping[interface.Role, tuple[str, ...]] = REPORTING_ROLES
                 ) -> None:
        self.topics = list(topics)
        self.writers = dict(writers)
        self.reporting = dict(reporting)
        self._legit: dict[str, set[str]] = {
            t: {self.writers[r] for r in interface.WRITER_ROLES[t] if r in self.writers}
            for t in self.topics}
        self._tally: dict[str, dict[str, _WriterTally]] = {t: {} for t in self.topics}
        self.foreign: dict[str, dict[str, int]] = {t: {} for t in self.topics}
        self._reports: dict[str, dict[str, int]] = {}
        self._final: set[str] = set()
        #: Commands the simulator applied (its final report); the bag must hold at least these.
        self.commands_applied: int | None = None

    def is_legit(self, topic: str, node: str) -> bool:
        """Whether ``node`` is a publisher of ``topic`` in this run."""
        return node in self._legit.get(topic, ())

    def stored(self, topic: str) -> int:
        """Messages of ``topic`` stored so far."""
        return sum(t.stored for t in self._tally.get(topic, {}).values())

    def on_message(self, topic: str, node: str, sequence: int | None) -> bool:
        """Count one message of ``topic`` from ``node`` (publication ``sequence`` number, or
        None if the middleware gives none); returns whether to store it."""
        if not self.is_legit(topic, node):
            per = self.foreign[topic]
            per[node] = per.get(node, 0) + 1
            return False
        tally = self._tally[topic].setdefault(node, _WriterTally())
        tally.stored += 1
        if sequence and sequence > tally.last_sequence:
            tally.last_sequence = sequence
        return True

    def on_report(self, node: str, published: Mapping[str, int], final: bool,
                  commands_applied: int | None = None) -> None:
        """A status of ``node`` with its published counts (``final``: they will not grow)."""
        self._reports[node] = dict(published)
        if final:
            self._final.add(node)
            if commands_applied is not None:
                self.commands_applied = int(commands_applied)

    @property
    def ended(self) -> bool:
        """The simulator has sent its final status."""
        sim = self.writers.get(interface.Role.SIMULATOR)
        return sim is not None and sim in self._final

    def _reporters(self, topic: str) -> list[str]:
        return [self.writers[role] for role, counted in self.reporting.items()
                if topic in counted and role in self.writers
                and role in interface.WRITER_ROLES[topic]]

    def expected(self, topic: str) -> int | None:
        """Messages the run's publishers sent on ``topic`` (None until known)."""
        if not self.ended:
            return None
        reporters = self._reporters(topic)
        if any(node not in self._final for node in reporters):
            return None
        nodes = set(reporters) | set(self._tally[topic])
        total = 0
        for node in nodes:
            tally = self._tally[topic].get(node, _WriterTally())
            # without sequence numbers (a middleware that gives none) the stored count stands
            # for the publisher's own
            sent = tally.last_sequence if tally.last_sequence else tally.stored
            total += max(self._reports.get(node, {}).get(topic, 0), sent)
        return total

    def account(self) -> RunAccount:
        """The verdict so far."""
        topics = {}
        foreign_pubs: dict[str, int] = {}
        for topic in self.topics:
            tallies = self._tally[topic].values()
            topics[topic] = TopicAccount(
                topic, sum(t.stored for t in tallies), self.expected(topic),
                sum(self.foreign[topic].values()), sum(t.gaps for t in tallies))
            for node, n in self.foreign[topic].items():
                foreign_pubs[f"{topic} from {node or '(unidentified publisher)'}"] = n
        notes = []
        if not self.ended:
            notes.append("the simulator's final status was not received (the run did not end)")
        cmd = interface.REAR_STEER_CMD
        if (cmd in topics and self.commands_applied is not None
                and topics[cmd].stored < self.commands_applied):
            notes.append(f"{cmd}: {topics[cmd].stored} stored but the simulator applied "
                         f"{self.commands_applied}")
        return RunAccount(topics, notes, foreign_pubs)


def account_from_messages(messages: Iterable[Any], store: Any) -> RunAccount:
    """A verdict from a bag's own messages (for repaired bags and bags without accounting).

    The publishers' final counts come from the last ``SimulatorStatus`` with ``final`` and the
    last ``ManeuverStatus`` with ``done``; the controller's from the highest MCAP sequence
    number of ``/fourws/rear_steer_cmd``. Topics whose publisher reports no count
    (``/fourws/run_config``) are expected to hold what they hold.

    Parameters
    ----------
    messages : iterable of fourws_run.bagfile.RawMessage
    store : rosbags Typestore
        Decodes the status messages (:func:`fourws_run.bagfile.bag_typestore` of the bag).
    """
    stored: dict[str, int] = {}
    seqs: dict[str, list[int]] = {}
    sim_final: Any = None
    man_final: Any = None
    for m in messages:
        stored[m.topic] = stored.get(m.topic, 0) + 1
        seqs.setdefault(m.topic, []).append(int(m.sequence))
        if m.topic == interface.SIM_STATUS:
            msg = store.deserialize_cdr(m.data, m.msgtype)
            if getattr(msg, "final", False):
                sim_final = msg
        elif m.topic == interface.MANEUVER_STATUS:
            msg = store.deserialize_cdr(m.data, m.msgtype)
            if getattr(msg, "done", False):
                man_final = msg
    reports: dict[str, dict[str, int]] = {}
    for name, msg in (("simulator", sim_final), ("maneuver", man_final)):
        if msg is not None:
            reports[name] = dict(zip(msg.published_topics, (int(c) for c in
                                                            msg.published_counts)))
    topics: dict[str, TopicAccount] = {}
    notes: list[str] = []
    if sim_final is None:
        notes.append("no final simulator status in the bag (the run or the recording ended "
                     "early)")
    for topic, n in stored.items():
        expected: int | None = None
        if topic == interface.NODE_CONFIG:
            expected = sum(r.get(topic, 0) for r in reports.values()) or None
            expected = None if expected is None else max(expected, n)
        elif topic in interface.SIMULATOR_COUNTED and "simulator" in reports:
            expected = reports["simulator"].get(topic)
        elif topic in interface.MANEUVER_COUNTED and "maneuver" in reports:
            expected = reports["maneuver"].get(topic)
        elif topic in (interface.REAR_STEER_CMD, interface.RUN_CONFIG) and sim_final is not None:
            expected = max(max(seqs[topic]), n)
        gaps = 0
        if topic != interface.NODE_CONFIG:
            numbered = sorted(s for s in seqs[topic] if s > 0)
            if numbered:
                gaps = numbered[-1] - numbered[0] + 1 - len(set(numbered))
        topics[topic] = TopicAccount(topic, n, expected, 0, gaps)
    if sim_final is not None and interface.REAR_STEER_CMD in topics \
            and topics[interface.REAR_STEER_CMD].stored < int(sim_final.commands_accepted):
        notes.append(f"{interface.REAR_STEER_CMD}: fewer stored than the simulator applied "
                     f"({sim_final.commands_accepted})")
    return RunAccount(topics, notes)


__all__ = ["ACCOUNT_VERSION", "Ledger", "REPORTING_ROLES", "RunAccount", "TopicAccount",
           "account_from_messages"]
