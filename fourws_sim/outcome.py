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
* on every state of a study's compiled closed loop (:mod:`fourws_study.loop_kernels`), which
  ends its run at the same tick as the twin;
* to a recorded time history by :meth:`VehicleLimits.first_violation` (a study point's status,
  a bag in ``fourws analyze``): the first sample that breaks the rule.

The predicate is written once, :func:`breach_code`: a plain function of numbers that the
per-state check, the time-history check (on numpy arrays) and the compiled loop (numba
compiles it, with the limits passed in as numbers) all call.

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

#: Codes of :func:`breach_code`: no limit broken; |sideslip|, forward speed or |roll| beyond
#: its limit (the first of roll, sideslip, speed that is broken).
NO_BREACH, SIDESLIP_BREACH, REVERSING_BREACH, ROLL_BREACH = range(4)
#: The maneuver end of each breach code.
BREACH_KINDS = {SIDESLIP_BREACH: SPUN, REVERSING_BREACH: SPUN, ROLL_BREACH: DIVERGED}


def breach_code(sideslip_rad, speed_mps, roll_rad,  # type: ignore[no-untyped-def]
                max_sideslip_rad, min_forward_speed_mps, max_roll_rad):
    """The rule of :class:`VehicleLimits` on one state: :data:`ROLL_BREACH` if
    ``|roll| > max_roll_rad``, else :data:`SIDESLIP_BREACH` if ``|sideslip| >
    max_sideslip_rad``, else :data:`REVERSING_BREACH` if ``speed < min_forward_speed_mps``,
    else :data:`NO_BREACH`.

    Parameters
    ----------
    sideslip_rad, speed_mps, roll_rad : float or numpy.ndarray
        Body sideslip (rad), forward speed (m/s) and roll (rad); NaN breaks no limit (an
        absent channel is passed as NaN).
    max_sideslip_rad, min_forward_speed_mps, max_roll_rad : float
        The limits (the :class:`VehicleLimits` fields).

    Returns
    -------
    int or numpy.ndarray of int
        The code, element by element for arrays.

    Written as arithmetic on the comparisons, without branches, so that the same function
    serves numbers (the per-state check), numpy arrays (a time history) and the compiled
    closed loop (numba compiles it as a plain function).
    """
    rolled = 1 * (abs(roll_rad) > max_roll_rad)
    slid = 1 * (abs(sideslip_rad) > max_sideslip_rad)
    reversing = 1 * (speed_mps < min_forward_speed_mps)
    return rolled * ROLL_BREACH + (1 - rolled) * (
        slid * SIDESLIP_BREACH + (1 - slid) * reversing * REVERSING_BREACH)


def _number(value: Any) -> float:
    """A channel's value for :func:`breach_code` (None: not checked, NaN)."""
    return math.nan if value is None else float(value)


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
        beta, speed, roll = _number(beta), _number(speed), _number(roll)
        return self._described(self.code(beta, speed, roll), t_s, beta, speed, roll)

    def code(self, sideslip_rad: Any, speed_mps: Any, roll_rad: Any) -> Any:
        """:func:`breach_code` with these limits (numbers or arrays; NaN is not checked)."""
        return breach_code(sideslip_rad, speed_mps, roll_rad, self.max_sideslip_rad,
                           self.min_forward_speed_mps, self.max_roll_rad)

    def _described(self, code: int, t_s: float, beta: float, speed: float,
                   roll: float) -> Violation | None:
        """The :class:`Violation` of breach ``code`` by the state (beta, speed, roll) at
        ``t_s``, or None for :data:`NO_BREACH`."""
        if code == ROLL_BREACH:
            reason = (f"roll {math.degrees(roll):.1f} deg at t = {t_s:.2f} s is beyond "
                      f"{math.degrees(self.max_roll_rad):.3g} deg, outside what the model "
                      "represents")
        elif code == SIDESLIP_BREACH:
            reason = (f"the car spun: |sideslip| {math.degrees(abs(beta)):.1f} deg at "
                      f"t = {t_s:.2f} s is beyond {math.degrees(self.max_sideslip_rad):.3g} "
                      "deg")
        elif code == REVERSING_BREACH:
            reason = (f"the car drives backwards: forward speed {speed:.2f} m/s at "
                      f"t = {t_s:.2f} s is below {self.min_forward_speed_mps:g} m/s")
        else:
            return None
        return Violation(BREACH_KINDS[code], float(t_s), reason)

    def first_violation(self, time_s: Any, sideslip_rad: Any = None, speed_mps: Any = None,
                        roll_rad: Any = None) -> Violation | None:
        """The first sample of a time history that breaks the rule (:func:`breach_code`
        sample by sample, as :meth:`violation` per state), or None. Arrays of equal length;
        a channel given as None is not checked."""
        t = np.asarray(time_s, dtype=float)
        beta, speed, roll = (np.full(t.shape, math.nan) if c is None
                             else np.asarray(c, dtype=float)
                             for c in (sideslip_rad, speed_mps, roll_rad))
        codes = self.code(beta, speed, roll)
        hits = np.flatnonzero(codes)
        if hits.size == 0:
            return None
        k = int(hits[0])
        return self._described(int(codes[k]), float(t[k]), float(beta[k]), float(speed[k]),
                               float(roll[k]))

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


__all__ = ["BREACH_KINDS", "DEFAULT_LIMITS", "DIVERGED", "NO_BREACH", "REVERSING_BREACH",
           "ROLL_BREACH", "SIDESLIP_BREACH", "SPUN", "VehicleLimits", "Violation",
           "breach_code", "vehicle_limits_from"]
