# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The verdict of a graph run: its outcome and reason from what its nodes reported and from
its closed bag -- no ROS here, so the rules are read and tested in one place.

:func:`conclude` fills a :class:`~fourws_run.record.RunRecord` from

* the simulator's final (or last) status and the maneuver's end (or last) status, as plain
  :class:`SimReport` / :class:`ManeuverReport` (the launcher converts the messages),
* the launcher's own failure ('' if none: a node crashed, the graph did not come up, ...),
* the check of the closed bag (:func:`fourws_run.bagfile.verify_bag`).

The rules, in order (the first that applies decides):

1. a signal stopped the run: ``interrupted``;
2. the launcher's failure: ``failed`` with it (after the cause when one is known: a second
   publisher of states, rule 3, or of answers, rule 6);
3. a second publisher sent states on the run's clock (the maneuver refused states of the run's
   clock that did not continue it): ``failed`` -- the answers applied may be to its states;
4. the simulator stopped the run: ``diverged`` (the simulation diverged, bag complete) or
   ``failed`` (a node stopped answering, a peer left, ...);
5. the bag does not hold every message: ``failed``, naming what is missing and who flooded,
   after the cause when one is known: a second publisher that answered states (6), or a
   controller beyond its share (7; a stopped controller never delivers to a recorder that
   matched its writer late);
6. a second publisher answered states: ``failed``;
7. the controller: lockstep ticks without a command, or in realtime more than
   ``realtime.max_stale_share`` of the ticks without a fresh command or of the commands
   refused: ``failed``, naming the controller node;
8. a realtime run slower than ``realtime.min_realtime_factor``: ``failed``;
9. the maneuver's end: ``spun`` / ``diverged`` (the car left the maneuver's
   :class:`~fourws_sim.outcome.VehicleLimits`), ``aborted``, or ``failed`` when the
   simulation ended before the maneuver node was done (a foreign 'done' status);
10. otherwise ``completed``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from fourws_run import interface
from fourws_run.accounting import RunAccount
from fourws_run.config import RunConfig
from fourws_run.record import Outcome, RunRecord
from fourws_run.ticks import NOT_AFTER_PREVIOUS, SECOND_ANSWER, SKIPS_STATES
from fourws_sim.outcome import DIVERGED, SPUN

#: Refusal reasons of commands that count as refused for the realtime share (the command
#: could not be used: impossible values or not a command at all).
UNUSABLE_COMMAND = ("impossible values", "not a RearSteerCommand")


@dataclass
class SimReport:
    """What the simulator's final (or last) status says."""

    sim_time_s: float = 0.0
    max_lateness_s: float = 0.0
    p99_lateness_s: float = 0.0
    overruns: int = 0
    stale_commands: int = 0
    steps: int = 0
    wall_time_s: float = 0.0
    commands_accepted: int = 0
    end_reason: str = ""
    stop_reason: str = ""
    final: bool = False
    rejections: dict[str, int] = field(default_factory=dict)


@dataclass
class ManeuverReport:
    """What the maneuver's end (or last) status says."""

    end: str = ""
    event: str = ""
    done: bool = False
    rejections: dict[str, int] = field(default_factory=dict)


@dataclass
class BagCheck:
    """The closed bag, checked: counts per topic, its accounting, the problems found."""

    counts: dict[str, int] = field(default_factory=dict)
    accounting: Mapping[str, Any] | None = None
    problems: list[str] = field(default_factory=list)


def _shares(record: RunRecord, config: RunConfig, sim: SimReport) -> str:
    """Why the controller's commands fail the run ('' if they do not)."""
    node = config.controller.node_name
    if config.lockstep:
        if record.stale_commands:
            return (f"the controller did not answer {record.stale_commands} control ticks "
                    f"(node {node}; zero rear steer was applied then)")
        return ""
    limit = config.realtime.max_stale_share
    ticks = max(record.control_ticks, 1)
    stale = record.stale_commands / ticks
    prefix = f"{interface.NODE_NAMES[interface.Role.SIMULATOR]}: {interface.REAR_STEER_CMD}: "
    refused = sum(n for k, n in record.rejections.items()
                  if k.startswith(prefix) and k[len(prefix):] in UNUSABLE_COMMAND)
    sent = refused + sim.commands_accepted
    refused_share = refused / sent if sent else 0.0
    problems = []
    if stale > limit:
        problems.append(f"{record.stale_commands} of {record.control_ticks} control ticks "
                        f"({stale:.1%}) ran without a fresh command (zero rear steer)")
    if refused_share > limit:
        problems.append(f"{refused} of {sent} commands ({refused_share:.1%}) were refused as "
                        "unusable")
    if not problems:
        return ""
    return (f"the controller node ({node}): " + "; ".join(problems)
            + f", beyond the allowed {limit:.1%} (realtime.max_stale_share)")


def _flooders(account: RunAccount | None) -> str:
    """Foreign publishers, for a reason that blames the one who flooded."""
    if account is None or not account.foreign_publishers:
        return ""
    top = sorted(account.foreign_publishers.items(), key=lambda kv: -kv[1])[:3]
    return "; foreign messages: " + ", ".join(f"{n} on {what}" for what, n in top)


#: How the launcher's failure begins when the recorder never held every message.
RECORDER_LATE = "the recorder did not hold every message"


def _second_publisher(what: str, counts: dict[str, int], so: str) -> str:
    """'a second publisher <what> (12x <rejection>; ...): <so>'."""
    return (f"a second publisher {what} ("
            + "; ".join(f"{n}x {k}" for k, n in counts.items()) + f"): {so}")


def _doubled(doubled: dict[str, int]) -> str:
    return _second_publisher("sent states on this run's clock", doubled,
                             "the answers applied may be to its states")


def _second_answers(ambiguous: dict[str, int]) -> str:
    return _second_publisher("answered states of this run", ambiguous,
                             "the inputs applied are not certain")


def conclude(record: RunRecord, config: RunConfig, sim: SimReport | None,
             man: ManeuverReport | None, interrupted: bool, failure: str,
             bag: BagCheck | None) -> None:
    """Fill ``record``'s outcome, reason and numbers (module docstring for the rules)."""
    sim_name = interface.NODE_NAMES[interface.Role.SIMULATOR]
    man_name = interface.NODE_NAMES[interface.Role.MANEUVER]
    record.clock_mode = config.clock_mode
    if sim is not None:
        record.sim_time_s = sim.sim_time_s
        record.max_lateness_s = sim.max_lateness_s
        record.p99_lateness_s = sim.p99_lateness_s
        record.overruns = sim.overruns
        record.stale_commands = sim.stale_commands
        if sim.wall_time_s > 0.0:  # the simulator's own measure of the running phase
            record.wall_time_s = sim.wall_time_s
        n_control = max(int(round(config.control_period_s / config.integration_step_s)), 1)
        record.control_ticks = sim.steps // n_control
        for reason, n in sim.rejections.items():
            record.rejections[f"{sim_name}: {reason}"] = n
    if man is not None:
        for reason, n in man.rejections.items():
            record.rejections[f"{man_name}: {reason}"] = n
    problems: list[str] = []
    if bag is not None:
        record.message_counts = dict(bag.counts)
        if bag.accounting:
            record.account = RunAccount.from_dict(bag.accounting)
        problems.extend(bag.problems)
    record.reason = failure
    if interrupted or failure.startswith("interrupted"):
        record.outcome = Outcome.INTERRUPTED
        record.reason = "interrupted (Ctrl-C / SIGTERM)"
        return
    ambiguous = {k: n for k, n in record.rejections.items() if SECOND_ANSWER in k}
    # states refused for not continuing the run although they were on its clock: a second
    # publisher sends states of this run, and the nodes cannot tell which one they answered
    doubled = {k: n for k, n in record.rejections.items() if k.startswith(man_name) and (
        NOT_AFTER_PREVIOUS in k or (config.lockstep and SKIPS_STATES in k))}
    if failure:
        record.outcome = Outcome.FAILED
        if ambiguous and failure.startswith(RECORDER_LATE):
            # a foreign answer the simulator applied is counted as applied but, foreign, never
            # stored: the recorder cannot complete, because a second publisher answered
            record.reason = _second_answers(ambiguous) + f"; then: {failure}"
        elif doubled:
            # the maneuver answered a foreign copy of a state and refused the run's own, and
            # the simulator stopped the run for the answer that never came: the copies are
            # the cause (beside a CPU hog, 1 run in 18 of the foreign-clock test)
            record.reason = _doubled(doubled) + f"; then: {failure}"
        return
    assert sim is not None and sim.final
    end = sim.end_reason
    stop = sim.stop_reason
    controller = _shares(record, config, sim)
    pace = config.realtime.min_realtime_factor
    if doubled:  # whatever followed, the run's inputs are not certain
        record.outcome = Outcome.FAILED
        record.reason = _doubled(doubled) + (f"; then: {stop}" if stop else "")
    elif stop:
        diverged = "diverged" in stop and not problems
        record.outcome = Outcome.DIVERGED if diverged else Outcome.FAILED
        record.reason = stop + ("" if not problems else
                                "; recording incomplete: " + "; ".join(problems))
    elif problems:
        record.outcome = Outcome.FAILED
        record.reason = ("recording incomplete: " + "; ".join(problems)
                         + _flooders(record.account))
        if ambiguous:  # as above: the foreign answer applied is what the bag cannot hold
            record.reason = _second_answers(ambiguous) + f"; then: {record.reason}"
        elif controller:
            # a controller that stopped answering (stopped, hung) also never delivered what
            # it had sent to a recorder that matched it late: the cause is the controller
            record.reason = controller + f"; then: {record.reason}"
    elif ambiguous:
        record.outcome = Outcome.FAILED
        record.reason = _second_answers(ambiguous)
    elif controller:
        # a foreign flood on the run's domain is the likely cause of a controller that fell
        # behind: said with it (seen: a realtime run beside a rogue failed naming only the
        # controller)
        record.outcome = Outcome.FAILED
        record.reason = controller + _flooders(record.account)
    elif not config.lockstep and pace > 0.0 and record.wall_time_s > 0.0 \
            and record.realtime_factor < pace:
        record.outcome = Outcome.FAILED
        record.reason = (f"the run simulated {record.realtime_factor:.2f}x real time, below "
                         f"the scenario's realtime.min_realtime_factor {pace:g} "
                         f"({record.overruns} overruns, max lateness "
                         f"{record.max_lateness_s * 1e3:.1f} ms)")
    elif not config.driver_node and end.startswith("end time"):
        # a user's driver: the simulator ended the run at the maneuver's duration
        record.outcome = Outcome.COMPLETED
        record.reason = end
    elif man is None or not man.done:
        record.outcome = Outcome.FAILED
        record.reason = f"the simulation ended without the maneuver's end ({end})"
    elif man.end in (SPUN, DIVERGED):
        record.outcome = Outcome.SPUN if man.end == SPUN else Outcome.DIVERGED
        record.reason = man.event.split(": ", 1)[-1]
    elif man.end == "aborted":
        record.outcome = Outcome.ABORTED
        record.reason = (f"the maneuver was aborted at t = {record.sim_time_s:.2f} s of "
                         f"{config.maneuver.duration_s} s: {man.event}")
    elif man.end == "stopped":
        # the maneuver node was not done: the simulator ended on an end it did not send
        # (a foreign 'done' status on the run's domain) or for a reason of its own
        record.outcome = Outcome.FAILED
        record.reason = (f"the simulation ended ({end}) at t = {record.sim_time_s:.2f} s "
                         f"before the maneuver node was done ({man.event}); "
                         "a foreign maneuver status on the run's domain?")
    else:
        record.outcome = Outcome.COMPLETED
        record.reason = end


__all__ = ["BagCheck", "ManeuverReport", "RECORDER_LATE", "SimReport", "UNUSABLE_COMMAND",
           "conclude"]
