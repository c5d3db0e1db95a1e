# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""How far a run went: peak sideslip, yaw rate and lateral acceleration, time the rear
actuator spent at its limits, and whether the car spun.

These are the quantities a stability study ranks runs by (:mod:`fourws_study`); each is
computed from the tick arrays of one run (offline twin or recorded bag alike).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fourws_sim.outcome import DEFAULT_LIMITS, VehicleLimits
#: An actuator sample counts as at a limit within this fraction of it (the actuator clips to
#: the limit exactly; the margin absorbs the rounding of a limit times a period).
LIMIT_RTOL = 1e-9


@dataclass(frozen=True)
class RunExtremes:
    """Peaks and limits of one run (SI units).

    Attributes
    ----------
    max_abs_sideslip_rad, max_abs_yaw_rate_radps, max_abs_lateral_accel_mps2,
    max_abs_roll_rad : float
        Largest magnitudes over the run.
    time_at_rear_angle_limit_s : float
        Time the rear actuator's angle sat at its angle limit, s.
    time_at_rear_rate_limit_s : float
        Time its angle moved at its rate limit, s.
    spin_time_s : float or None
        First time the car spun by the run's :class:`~fourws_sim.outcome.VehicleLimits`
        (|sideslip| or reversing past its limit), s (None: never).
    """

    max_abs_sideslip_rad: float
    max_abs_yaw_rate_radps: float
    max_abs_lateral_accel_mps2: float
    max_abs_roll_rad: float
    time_at_rear_angle_limit_s: float
    time_at_rear_rate_limit_s: float
    spin_time_s: float | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return dict(self.__dict__)


def _peak(values: np.ndarray) -> float:
    return float(np.max(np.abs(values))) if values.size else math.nan


def run_extremes(time_s: np.ndarray, sideslip_rad: np.ndarray, yaw_rate_radps: np.ndarray,
                 lateral_accel_mps2: np.ndarray, roll_rad: np.ndarray,
                 rear_angle_rad: np.ndarray, period_s: float, angle_limit_rad: float,
                 rate_limit_radps: float, limits: VehicleLimits = DEFAULT_LIMITS,
                 speed_mps: np.ndarray | None = None) -> RunExtremes:
    """Peaks and actuator limits of a run sampled once per control tick.

    Parameters
    ----------
    time_s : ndarray
        Times of the states, s.
    sideslip_rad, yaw_rate_radps, lateral_accel_mps2, roll_rad : ndarray
        The state at those times.
    rear_angle_rad : ndarray
        The rear actuator's angle commanded at each tick (held over the next period), rad
        (one per answered state: the final state of a run has none).
    period_s : float
        Control period, s: each tick holds its angle this long.
    angle_limit_rad, rate_limit_radps : float
        The actuator's limits (rad, rad/s).
    limits : VehicleLimits
        The run's limits (its maneuver's): the car spun at the first sample whose sideslip
        or forward speed breaks them.
    speed_mps : ndarray, optional
        Forward speed at the state times, m/s (None: reversing is not checked).
    """
    t = np.asarray(time_s, dtype=float)
    beta = np.asarray(sideslip_rad, dtype=float)
    rear = np.asarray(rear_angle_rad, dtype=float)
    at_angle = np.abs(rear) >= angle_limit_rad * (1.0 - LIMIT_RTOL)
    moves = np.abs(np.diff(np.concatenate([[0.0], rear])))  # the actuator starts at 0
    at_rate = moves >= rate_limit_radps * period_s * (1.0 - LIMIT_RTOL)
    spun = limits.first_violation(t, beta, speed_mps)  # roll is the model's range, no spin
    return RunExtremes(
        _peak(beta), _peak(np.asarray(yaw_rate_radps, dtype=float)),
        _peak(np.asarray(lateral_accel_mps2, dtype=float)),
        _peak(np.asarray(roll_rad, dtype=float)),
        float(np.count_nonzero(at_angle)) * period_s,
        float(np.count_nonzero(at_rate)) * period_s,
        spun.time_s if spun is not None else None)


__all__ = ["LIMIT_RTOL", "RunExtremes", "run_extremes"]
