# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""ISO 3888-2 lane change: clearance to the cones and pass/fail, from the driven path.

A run passes when the car drove through every gated section of the course and its body (the
CG +- W/2 sideways, W the ``vehicle_width_m`` of the maneuver) stayed inside the cone lines
at every sample in a section: the smallest clearance (:func:`fourws_sim.corridor.clearance`,
the measure the reference line was planned with) is >= 0. ISO 3888-2 judges a run by the cones
standing; a body that stays inside the lines knocks none (the test's own tolerance, cones
touched but standing, is not modelled).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from fourws_analysis.bag import MetricUnavailableError
from fourws_sim.corridor import clearance
from fourws_sim.maneuvers import maneuver_spec_from_mapping

#: A section counts as driven through when the record has at least this many samples inside
#: it (a car at 60 km/h spends 0.66 s in a 11-m section: 66 samples at 100 Hz).
MIN_SAMPLES_PER_SECTION = 3


@dataclass
class LaneChangeResult:
    """Clearance and outcome of one lane-change run.

    Attributes
    ----------
    clearance_m : float
        Smallest distance between the body and the cone lines over the samples inside the
        gated sections, m (negative: the body crossed a line by that much).
    passed : bool
        Every section driven through and ``clearance_m >= 0``.
    sections_driven : int
        Gated sections with at least :data:`MIN_SAMPLES_PER_SECTION` samples.
    notes : list of str
    """

    clearance_m: float
    passed: bool
    sections_driven: int
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"clearance_m": self.clearance_m, "passed": self.passed,
                "sections_driven": self.sections_driven, "notes": list(self.notes)}


def lane_change_metrics(x_m: np.ndarray, y_m: np.ndarray,
                        sections: Sequence[tuple[float, float, float, float]],
                        vehicle_width_m: float) -> LaneChangeResult:
    """Clearance and pass/fail of a lane change from the CG path.

    Parameters
    ----------
    x_m, y_m : ndarray
        Earth-frame CG position, m (the course starts at the origin heading +x).
    sections : sequence of (x_start, x_end, y_right, y_left)
        The gated sections, m (:attr:`fourws_sim.maneuvers.DoubleLaneChangeParams.sections`).
    vehicle_width_m : float
        W, m.
    """
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    driven = sum(1 for x0, x1, _, _ in sections
                 if np.count_nonzero((x >= x0) & (x <= x1)) >= MIN_SAMPLES_PER_SECTION)
    margin = clearance(x, y, sections, vehicle_width_m)
    notes = []
    if driven < len(sections):
        notes.append(f"the car drove through {driven} of the {len(sections)} gated sections")
    return LaneChangeResult(float(margin), bool(driven == len(sections) and margin >= 0.0),
                            driven, notes)


def lane_change_of_run(x_m: np.ndarray, y_m: np.ndarray,
                       maneuver: Mapping[str, Any]) -> LaneChangeResult:
    """:func:`lane_change_metrics` of a ``double_lane_change`` run from its maneuver mapping
    (the run configuration's ``maneuver``).

    Raises
    ------
    MetricUnavailableError
        The maneuver is not a lane change.
    """
    if maneuver.get("type") != "double_lane_change":
        raise MetricUnavailableError(f"lane change: needs a double_lane_change run; this run "
                                     f"is {maneuver.get('type') or 'unrecognized'}")
    params = maneuver_spec_from_mapping(maneuver, "run_config:maneuver").params
    return lane_change_metrics(x_m, y_m, params.sections, params.vehicle_width_m)


__all__ = ["LaneChangeResult", "MIN_SAMPLES_PER_SECTION", "lane_change_metrics",
           "lane_change_of_run"]
