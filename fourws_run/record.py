# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The record of one graph run: its outcome, its accounting, what went wrong and where.

:class:`RunRecord` is what ``fourws run`` prints (:meth:`RunRecord.summary_lines`), returns as
an exit code (:data:`EXIT_CODES`) and writes next to the bag as ``run.json``
(:meth:`RunRecord.write`). A run is ``ok`` only if its maneuver reached its end and the bag
(when recorded) holds every message the run's nodes published -- the recorder's accounting,
checked again against the closed bag (:func:`fourws_run.bagfile.verify_bag`).
"""

from __future__ import annotations

import enum
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from fourws_run.accounting import RunAccount

RECORD_VERSION = 1


class Outcome(str, enum.Enum):
    """How a run ended."""

    #: The maneuver reached its end (duration or its designed end condition); the bag is
    #: complete.
    COMPLETED = "completed"
    #: The car or the driver could not do the maneuver (it spun, left the path); the bag is
    #: complete up to there. A vehicle-dynamics result, not a fault.
    ABORTED = "aborted"
    #: The car spun or drove backwards (:class:`fourws_sim.outcome.VehicleLimits`): the run
    #: ended there, the bag is complete up to there; its metrics describe a spin, not the car.
    SPUN = "spun"
    #: The simulation diverged, or the car left the states the model represents (the model
    #: was driven past what it can represent); the bag is complete up to there.
    DIVERGED = "diverged"
    #: A node failed, the run stalled, or the bag does not hold every message.
    FAILED = "failed"
    #: Ctrl-C or SIGTERM.
    INTERRUPTED = "interrupted"


#: Exit code of ``fourws run`` for a run's outcome.
EXIT_CODES: dict[Outcome, int] = {
    Outcome.COMPLETED: 0, Outcome.FAILED: 1, Outcome.ABORTED: 3, Outcome.SPUN: 3,
    Outcome.DIVERGED: 3, Outcome.INTERRUPTED: 130}
#: A realtime run that simulated less than this per wall time fell behind real time (it
#: says so; a scenario's ``realtime.min_realtime_factor`` may fail it).
BEHIND_REAL_TIME = 0.99


@dataclass
class RunRecord:
    """One run's record (see the module docstring).

    Attributes
    ----------
    outcome : Outcome
    reason : str
        Why the run ended as it did (names the node at fault for a failure).
    law : str
    run_dir : Path
    bag_path : Path or None
    sim_time_s, wall_time_s : float
        Simulated time reached and the wall time of the running phase, s.
    startup_s : float
        Wall time from the launch of the nodes to the start of the simulation (the graph up
        and matched), s; 0 if it never started.
    max_lateness_s, p99_lateness_s : float
        Realtime step lateness, s.
    overruns : int
        Realtime steps that started a whole step late.
    stale_commands : int
        Control ticks run with zero rear steer (no valid command in time).
    control_ticks : int
        Control ticks the simulator ran.
    clock_mode : str
        ``lockstep`` or ``realtime``.
    account : RunAccount or None
        The recording's accounting (None when not recorded, or the recorder never reported).
    rejections : dict of str to int
        Inputs refused as not belonging to the run, ``"<node>: <topic>: <reason>"`` -> count.
    message_counts : dict of str to int
        Messages per topic in the closed bag.
    exit_codes : dict of str to int or None
        Exit code of each node process.
    domain_id : int
        ROS domain of the run.
    config : dict
        The run configuration (:meth:`fourws_run.config.RunConfig.to_dict`).
    """

    outcome: Outcome
    reason: str
    law: str
    run_dir: Path
    bag_path: Path | None
    sim_time_s: float = 0.0
    wall_time_s: float = 0.0
    startup_s: float = 0.0
    max_lateness_s: float = 0.0
    p99_lateness_s: float = 0.0
    overruns: int = 0
    stale_commands: int = 0
    control_ticks: int = 0
    clock_mode: str = "lockstep"
    account: RunAccount | None = None
    rejections: dict[str, int] = field(default_factory=dict)
    message_counts: dict[str, int] = field(default_factory=dict)
    exit_codes: dict[str, int | None] = field(default_factory=dict)
    domain_id: int = -1
    config: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """The run completed and its bag (if recorded) is complete."""
        return self.outcome == Outcome.COMPLETED

    @property
    def interrupted(self) -> bool:
        """Ctrl-C or SIGTERM ended it."""
        return self.outcome == Outcome.INTERRUPTED

    @property
    def exit_code(self) -> int:
        """Exit code for this outcome."""
        return EXIT_CODES[self.outcome]

    @property
    def realtime_factor(self) -> float:
        """Simulated time per wall time of the running phase."""
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0.0 else 0.0

    @property
    def behind_real_time(self) -> bool:
        """A realtime run that simulated less than :data:`BEHIND_REAL_TIME` per wall time, or
        had steps a whole step late."""
        return self.clock_mode == "realtime" and self.wall_time_s > 0.0 and (
            self.realtime_factor < BEHIND_REAL_TIME or self.overruns > 0)

    @property
    def complete(self) -> bool:
        """The bag holds every message the run published (False when not recorded)."""
        return self.account is not None and self.account.complete

    def summary_lines(self) -> list[str]:
        """What ``fourws run`` prints for this run."""
        head = {Outcome.COMPLETED: "ok", Outcome.ABORTED: "ABORTED", Outcome.SPUN: "SPUN",
                Outcome.DIVERGED: "DIVERGED", Outcome.FAILED: "FAILED",
                Outcome.INTERRUPTED: "INTERRUPTED"}[self.outcome]
        behind = ""
        if self.behind_real_time:
            behind = (f" (behind real time: {self.realtime_factor:.2f}x, "
                      f"{self.overruns} overruns)")
        lines = [f"run {self.law}: {head}" + (f": {self.reason}" if not self.ok else "")
                 + behind]
        if self.wall_time_s > 0.0:
            lines.append(f"  simulated {self.sim_time_s:.2f} s in {self.wall_time_s:.2f} s of "
                         f"running (real-time factor {self.realtime_factor:.2f}x)")
        if self.max_lateness_s > 0.0:
            lines.append(f"  step lateness p99 {self.p99_lateness_s * 1e3:.3f} ms, max "
                         f"{self.max_lateness_s * 1e3:.3f} ms, overruns {self.overruns}")
        if self.stale_commands:
            lines.append(f"  control ticks with zero rear steer (no valid command in time): "
                         f"{self.stale_commands}")
        for what, n in sorted(self.rejections.items()):
            lines.append(f"  refused {n}x {what}")
        if self.bag_path is not None:
            lines.append(f"  bag: {self.bag_path}")
            if self.account is None:
                lines.append("  recording: no accounting (the recorder never reported)")
            elif self.account.complete and self.outcome in (Outcome.FAILED,
                                                            Outcome.INTERRUPTED):
                lines.append("  recording: the bag holds every message the nodes published "
                             "before the run stopped (the run itself did not end well)")
            else:
                lines.append(f"  recording: {self.account.summary()}")
                for what, n in sorted(self.account.foreign_publishers.items()):
                    lines.append(f"  not recorded: {n} foreign messages on {what}")
            counts = ", ".join(f"{t} {n}" for t, n in sorted(self.message_counts.items()))
            lines.append(f"  messages: {counts}")
        lines.append(f"  record: {self.run_dir / 'run.json'}; logs: {self.run_dir / 'logs'}")
        return lines

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (``run.json``)."""
        return {
            "version": RECORD_VERSION, "outcome": self.outcome.value, "ok": self.ok,
            "reason": self.reason, "law": self.law, "run_dir": str(self.run_dir),
            "bag_path": None if self.bag_path is None else str(self.bag_path),
            "sim_time_s": self.sim_time_s, "wall_time_s": self.wall_time_s,
            "startup_s": self.startup_s, "realtime_factor": self.realtime_factor,
            "max_lateness_s": self.max_lateness_s,
            "p99_lateness_s": self.p99_lateness_s, "overruns": self.overruns,
            "stale_commands": self.stale_commands, "control_ticks": self.control_ticks,
            "clock_mode": self.clock_mode, "behind_real_time": self.behind_real_time,
            "recording": None if self.account is None else self.account.to_dict(),
            "rejections": dict(sorted(self.rejections.items())),
            "message_counts": dict(sorted(self.message_counts.items())),
            "exit_codes": dict(self.exit_codes), "domain_id": self.domain_id,
            "config": self.config,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "RunRecord":
        """Inverse of :meth:`to_dict`."""
        rec = data.get("recording")
        return cls(
            outcome=Outcome(data["outcome"]), reason=str(data.get("reason", "")),
            law=str(data.get("law", "")), run_dir=Path(data["run_dir"]),
            bag_path=None if data.get("bag_path") is None else Path(data["bag_path"]),
            sim_time_s=float(data.get("sim_time_s", 0.0)),
            wall_time_s=float(data.get("wall_time_s", 0.0)),
            startup_s=float(data.get("startup_s", 0.0)),
            max_lateness_s=float(data.get("max_lateness_s", 0.0)),
            p99_lateness_s=float(data.get("p99_lateness_s", 0.0)),
            overruns=int(data.get("overruns", 0)),
            stale_commands=int(data.get("stale_commands", 0)),
            control_ticks=int(data.get("control_ticks", 0)),
            clock_mode=str(data.get("clock_mode", "lockstep")),
            account=None if rec is None else RunAccount.from_dict(rec),
            rejections={str(k): int(v) for k, v in dict(data.get("rejections", {})).items()},
            message_counts={str(k): int(v)
                            for k, v in dict(data.get("message_counts", {})).items()},
            exit_codes=dict(data.get("exit_codes", {})),
            domain_id=int(data.get("domain_id", -1)), config=dict(data.get("config", {})))

    def write(self) -> Path:
        """Write ``run.json`` into the run folder (atomically); returns its path.

        Raises
        ------
        OSError
            The folder is not writable.
        """
        path = self.run_dir / "run.json"
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(self.to_dict(), indent=1, sort_keys=True, default=str))
        os.replace(tmp, path)
        return path


__all__ = ["BEHIND_REAL_TIME", "EXIT_CODES", "Outcome", "RECORD_VERSION", "RunRecord"]
