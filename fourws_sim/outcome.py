# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""When the car's motion is no longer the maneuver's: the one vehicle-outcome rule.

A handling maneuver is a test of a car that keeps driving forward along its path. Once the car
has spun, drives backwards, or has left the states the model can represent, what follows is
no longer a handling result, and a verdict of ``ok`` or a step-response metric of it would be
a plausible wrong number. :class:`VehicleLimits` states the rule once; it is applied

* on every answered state by the maneuver (:meth:`fourws_sim.maneuvers.Maneuver.done`), so a
  graph run (the maneuver node) and the offline twin end at the same tick, with the maneuver
  end ``spun`` or ``diverged`` (run outcome ``spun``/``diverged``, exit code 3, a complete
  bag);
* to a recorded time history by :func:`first_violation` (a study's compiled loop, a bag in
  ``fourws analyze``): the first sample that breaks the rule, the same predicate on the same
  per-tick values.

The limits (maneuver or scenario key ``vehicle_limits``; each may be lifted by a larger value):

``max_sideslip_rad`` (default 20 deg)
    The car has spun: ``|beta|`` beyond it. Production cars stay below 5-6 deg of body
    sideslip up to their limit on dry roads and an ESC intervenes well before 10 deg (van
    Zanten, "Bosch ESP systems: 5 years of experience", SAE 2000-01-1633); 20 deg is far past
    recovery for a driver holding the wheel, and it is the threshold the studies have always
    used for ``spun``.
``min_forward_speed_mps`` (default -0.5 m/s)
    The car drives backwards (a spin that turned it around): forward speed ``u`` below it.
    Maneuvers that brake to a stop settle at 0; the margin keeps the wheels' rolling back and
    forth at standstill from counting.
``max_roll_rad`` (default 30 deg)
    The state the model can represent: the 8-DOF's roll is one rotational degree of freedom
    about a fixed roll axis with linear suspension forces; a passenger car's suspension
    reaches its bump stops near 8-10 deg, so a roll of 30 deg is a car on its side in reality
    and a model driven beyond its range here. Outcome ``diverged``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from fourws_sim.params import _from_mapping, _spec

#: Maneuver end (``ManeuverStatus.end``) of a run whose car spun or drove backwards.
SPUN = "spun"
#: Maneuver end of a run whose car left the states the model represents.
DIVERGED = "diverged"


@dataclass(frozen=True)
class Violation:
    """The first breach of the rule.

    Attributes
    ----------
    kind : str
        :data:`SPUN` or :data:`DIVERGED`.
    time_s : float
        Time of the state that broke it, s.
    reason : str
        One sentence: the quantity, its value and the limit.
    """

    kind: str
    time_s: float
    reason: str


@dataclass(frozen=True)
class VehicleLimits:
    """The limits of a handling maneuver's motion (module docstring)."""

    max_sideslip_rad: float = _spec(default=math.radians(20.0),
                                    doc="|body sideslip| beyond which the car has spun, rad",
                                    bounds=(0.01, math.pi))
    min_forward_speed_mps: float = _spec("any", default=-0.5,
                                         doc="forward speed below which the car drives "
                                             "backwards, m/s", bounds=(-150.0, 0.0))
    max_roll_rad: float = _spec(default=math.radians(30.0),
                                doc="|roll| beyond the model's range, rad",
                                bounds=(0.01, math.pi))

    def violation(self, t_s: float, outputs: Mapping[str, Any]) -> Violation | None:
        """The breach by one state (``Simulator.outputs()`` / ``VehicleState`` fields
        ``sideslip_rad``, ``speed_mps``, ``roll_rad``; absent fields are not checked), or
        None."""
        beta = outputs.get("sideslip_rad")
        speed = outputs.get("speed_mps")
        roll = outputs.get("roll_rad")
        return self._breach(t_s, beta, speed, roll)

    def _breach(self, t_s: float, beta: Any, speed: Any, roll: Any) -> Violation | None:
        if roll is not None and abs(roll) > self.max_roll_rad:
            return Violation(DIVERGED, float(t_s),
                             f"roll {math.degrees(roll):.1f} deg at t = {t_s:.2f} s is beyond "
                             f"{math.degrees(self.max_roll_rad):.0f} deg, outside what the "
                             "model represents")
        if beta is not None and abs(beta) > self.max_sideslip_rad:
            return Violation(SPUN, float(t_s),
                             f"the car spun: |sideslip| {math.degrees(abs(beta)):.1f} deg at "
                             f"t = {t_s:.2f} s is beyond "
                             f"{math.degrees(self.max_sideslip_rad):.0f} deg")
        if speed is not None and speed < self.min_forward_speed_mps:
            return Violation(SPUN, float(t_s),
                             f"the car drives backwards: forward speed {speed:.2f} m/s at "
                             f"t = {t_s:.2f} s is below {self.min_forward_speed_mps:g} m/s")
        return None

    def first_violation(self, time_s: Any, sideslip_rad: Any = None, speed_mps: Any = None,
                        roll_rad: Any = None) -> Violation | None:
        """The first sample of a time history that breaks the rule (the same predicate as
        :meth:`violation`, sample by sample), or None. Arrays of equal length; a channel
        given as None is not checked."""
        t = np.asarray(time_s, dtype=float)
        channels = [None if c is None else np.asarray(c, dtype=float)
                    for c in (sideslip_rad, speed_mps, roll_rad)]
        bad = np.zeros(t.shape, dtype=bool)
        beta, speed, roll = channels
        if beta is not None:
            bad |= np.abs(beta) > self.max_sideslip_rad
        if speed is not None:
            bad |= speed < self.min_forward_speed_mps
        if roll is not None:
            bad |= np.abs(roll) > self.max_roll_rad
        hits = np.flatnonzero(bad)
        if hits.size == 0:
            return None
        k = int(hits[0])
        values = [None if c is None else float(c[k]) for c in channels]
        return self._breach(float(t[k]), *values)

    def to_dict(self) -> dict[str, float]:
        """The file layout."""
        return {"max_sideslip_rad": self.max_sideslip_rad,
                "min_forward_speed_mps": self.min_forward_speed_mps,
                "max_roll_rad": self.max_roll_rad}


#: The limits every maneuver has unless its file or the scenario says otherwise.
DEFAULT_LIMITS = VehicleLimits()


def vehicle_limits_from(data: Any, source: str | None, prefix: str = "vehicle_limits.",
                        unchecked: frozenset[str] = frozenset()) -> VehicleLimits:
    """Validate a ``vehicle_limits`` mapping (None gives the defaults; a missing key keeps
    its default).

    Raises
    ------
    ParameterError
        Unknown key, a value that is not a number or outside its plausible range.
    """
    if data is None:
        return DEFAULT_LIMITS
    return _from_mapping(VehicleLimits, data, source, prefix, unchecked)


__all__ = ["DEFAULT_LIMITS", "DIVERGED", "SPUN", "VehicleLimits", "Violation",
           "vehicle_limits_from"]
