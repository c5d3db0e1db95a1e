# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Bounds of the numbers given on the command line (one place for every subcommand).

A value outside its bounds is a :class:`~fourws_sim.errors.ParameterError` naming the option,
so ``fourws linear --speed-kmh 1e6`` ends in one line instead of a "stable" verdict at a speed
no vehicle reaches. Speeds share :data:`fourws_sim.params.MAX_SPEED_MPS` with the maneuver
files.
"""

from __future__ import annotations

import math

from fourws_sim.errors import ParameterError
from fourws_sim.params import MAX_SPEED_MPS

KMH_PER_MPS = 3.6
#: Slowest speed of the analyses linearized about straight running, m/s (their equations
#: divide by U; below a walking pace their numbers mean nothing).
MIN_ANALYSIS_SPEED_MPS = 0.1
#: Controller belief scale of the cornering stiffnesses (the scenario's and the controller
#: node's range).
BELIEF_SCALE = (0.05, 20.0)


def bounded(option: str, value: float, low: float, high: float, unit: str = "",
            low_open: bool = False) -> float:
    """``value`` as float if it is finite and within ``[low, high]`` (``(low, high]`` with
    ``low_open``), else :class:`ParameterError` naming ``option`` and the range."""
    v = float(value)
    inside = (low < v if low_open else low <= v) and v <= high
    if not (math.isfinite(v) and inside):
        lo = "(" if low_open else "["
        raise ParameterError(option, f"must be within {lo}{low:g}, {high:g}]{unit}, got {v!r}")
    return v


def speed_mps(option: str, value: float) -> float:
    """A forward speed in m/s: ``[MIN_ANALYSIS_SPEED_MPS, MAX_SPEED_MPS]``."""
    return bounded(option, value, MIN_ANALYSIS_SPEED_MPS, MAX_SPEED_MPS, " m/s")


def speed_kmh(option: str, value: float) -> float:
    """A forward speed in km/h: ``[3.6 MIN_ANALYSIS_SPEED_MPS, 3.6 MAX_SPEED_MPS]``."""
    return bounded(option, value, MIN_ANALYSIS_SPEED_MPS * KMH_PER_MPS,
                   MAX_SPEED_MPS * KMH_PER_MPS, " km/h")


__all__ = ["BELIEF_SCALE", "KMH_PER_MPS", "MIN_ANALYSIS_SPEED_MPS", "bounded", "speed_kmh",
           "speed_mps"]
