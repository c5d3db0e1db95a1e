# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Steady-state handling of the 2-DOF vehicle with and without a rear-steer law (ch. 4.5).

Front-wheel steering (Wong; Bernard et al.): the constant-speed test slope is

.. math::

    \frac{d\delta_f}{d a_y} = \frac{L}{U^2} + K_{us}, \qquad
    K_{us} = \frac{m}{L}\left(\frac{b}{C_f} - \frac{a}{C_r}\right)\ \mathrm{rad/(m/s^2)}

(eq. 4.104 per m/s^2 instead of per g): understeer :math:`K_{us} > 0` with characteristic
speed :math:`\sqrt{L/K_{us}}`, oversteer :math:`K_{us} < 0` with critical speed
:math:`\sqrt{-L/K_{us}}` (eq. 4.93). With a rear-steer law the slope is taken from the
closed-loop steady-state gain :math:`a_y/\delta_f` of the 2-DOF model (eq. 4.103 in closed
form for the laws of chapter 4), and the law's *effective* understeer gradient is
:math:`d\delta_f/da_y - L/U^2`. The speed where FWS and the law have equal slopes is
eq. 4.107's :math:`U_{ss}` (12.99 m/s for Table 4.4 with Solution 1, analytically
:math:`\sqrt{b L C_r/(m a)}`).

These are the 2-DOF model's numbers (``axle_tires``, no roll). The report also gives the
critical and characteristic speeds of every model level that applies side by side
(:func:`fourws_analysis.critical_speeds.compare_levels`: 2-DOF, 3-DOF with roll steer, 8-DOF
linearized) with the reasons they differ; its 2-DOF entry is the one the 2-DOF keys hold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import scipy.optimize

from fourws_analysis import critical_speeds
from fourws_analysis.critical_speeds import LevelComparison
from fourws_analysis.linear import closed_loop, steady_state_gains
from fourws_control.base import Law, check_speed
from fourws_control.bicycle import bicycle
from fourws_control.registry import make_law
from fourws_sim.errors import IncompatibleError, ParameterError
from fourws_sim.params import GRAVITY_MPS2, Vehicle

#: Speed range searched for the equal-slope speed, m/s.
EQUAL_SLOPE_RANGE_MPS = (1.0, 100.0)
_EQUAL_SLOPE_SAMPLES = 400
#: Relative slope difference below which two slopes are "identical" (law equals FWS).
_SAME_SLOPE_RTOL = 1e-9
#: Speeds of the slope table (Figure 4.14 uses 7 m/s, U_ss and 25 m/s), m/s.
DEFAULT_SLOPE_SPEEDS_MPS = (7.0, 15.0, 25.0)


def understeer_gradient(vehicle: Vehicle) -> float:
    """FWS understeer gradient K_us in rad/(m/s^2) (> 0 understeer)."""
    return vehicle.understeer_gradient_rad_per_mps2


def characteristic_speeds(vehicle: Vehicle) -> tuple[float | None, float | None]:
    """(characteristic speed, critical speed) of the FWS 2-DOF vehicle in m/s.

    Characteristic speed ``sqrt(L/K)`` for understeer, critical speed ``sqrt(-L/K)`` for
    oversteer (eq. 4.93); the other is None (both None for neutral steer).
    """
    K = understeer_gradient(vehicle)
    L = vehicle.chassis.wheelbase_m
    if K > 0.0:
        return math.sqrt(L / K), None
    if K < 0.0:
        return None, math.sqrt(-L / K)
    return None, None


def steer_slope(vehicle: Vehicle, law: Law | str | None, speed_mps: float) -> float:
    """d(delta_f)/d(a_y) of the 2-DOF closed loop at ``speed_mps``, rad/(m/s^2).

    Raises
    ------
    IncompatibleError
        No steady state (zero eigenvalue) or zero lateral-acceleration gain.
    """
    cl = closed_loop("2dof", vehicle, law, speed_mps)
    gain = steady_state_gains(cl)["lateral_acceleration/DELTA_F"]
    if gain == 0.0:
        raise IncompatibleError(f"zero steady lateral-acceleration gain at {speed_mps} m/s")
    return 1.0 / gain


def fws_steer_slope(vehicle: Vehicle, speed_mps: float) -> float:
    """Analytic FWS slope L/U^2 + K_us (eq. 4.104), rad/(m/s^2)."""
    u = check_speed(speed_mps)
    return vehicle.chassis.wheelbase_m / (u * u) + understeer_gradient(vehicle)


def equal_slope_speed(vehicle: Vehicle, law: Law | str,
                      speed_range_mps: tuple[float, float] = EQUAL_SLOPE_RANGE_MPS
                      ) -> float | None:
    """Lowest speed (m/s) where FWS and ``law`` have the same steer/a_y slope (eq. 4.107).

    None when the slopes never cross in the range or are identical (e.g. ``fws``).
    """
    lo, hi = (check_speed(s, "speed_range_mps") for s in speed_range_mps)
    if hi <= lo:
        raise ParameterError("speed_range_mps", f"must be increasing, got {speed_range_mps}")
    law_obj = make_law(law, vehicle) if isinstance(law, str) else law

    def diff(u: float) -> float:
        return steer_slope(vehicle, law_obj, u) - fws_steer_slope(vehicle, u)

    speeds = np.geomspace(lo, hi, _EQUAL_SLOPE_SAMPLES)
    values = []
    for u in speeds:
        try:
            values.append(diff(float(u)))
        except IncompatibleError:
            values.append(float("nan"))
    vals = np.array(values)
    scale = np.array([abs(fws_steer_slope(vehicle, float(u))) for u in speeds])
    if np.all(np.abs(vals[np.isfinite(vals)]) <= _SAME_SLOPE_RTOL * scale[np.isfinite(vals)]):
        return None
    for i in range(len(speeds) - 1):
        a, b = vals[i], vals[i + 1]
        if not (np.isfinite(a) and np.isfinite(b)):
            continue
        if a == 0.0:
            return float(speeds[i])
        if a * b < 0.0:
            return float(scipy.optimize.brentq(diff, float(speeds[i]), float(speeds[i + 1]),
                                               xtol=1e-9))
    return None


def sol1_equal_slope_speed(vehicle: Vehicle) -> float:
    """Closed form of eq. 4.107 for Solution 1: ``sqrt(b L Cr / (m a))`` in m/s."""
    p = bicycle(vehicle)
    return math.sqrt(p.b * p.L * p.cr / (p.m * p.a))


def zero_sideslip_ksf_limits(vehicle: Vehicle, speed_mps: float) -> tuple[float, float]:
    """Upper stability limits on Ksf of the zero-sideslip family (eqs. 4.16, 4.17).

    With ``Kr`` from eq. 4.14 (``ff_zero_sideslip`` with option ``ksf``), the Routh-Hurwitz
    conditions of the quadratic characteristic equation are ``a1 > 0``:

    .. math::

        K_{sf} < \\frac{C_f\\,[I_z L (C_f + C_r) + m L a^2 C_f + m^2 a b U^2]}
                       {m b C_r (a L C_f + m b U^2)}

    (eq. 4.16, re-derived) and ``a0 > 0``: :math:`K_{sf} < 1` (eq. 4.17).

    Returns
    -------
    (float, float)
        The eq. 4.16 limit and the eq. 4.17 limit (1.0).
    """
    u = check_speed(speed_mps)
    p = bicycle(vehicle)
    num = p.cf * (p.iz * p.L * (p.cf + p.cr) + p.m * p.L * p.a ** 2 * p.cf
                  + p.m ** 2 * p.a * p.b * u * u)
    den = p.m * p.b * p.cr * (p.a * p.L * p.cf + p.m * p.b * u * u)
    return num / den, 1.0


@dataclass(frozen=True)
class SlopeRow:
    """Steer/lateral-acceleration slopes at one speed (deg of front steer per g)."""

    speed_mps: float
    fws_deg_per_g: float
    law_deg_per_g: float | None
    law_understeer_gradient_deg_per_g: float | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"speed_mps": self.speed_mps, "fws_deg_per_g": self.fws_deg_per_g,
                "law_deg_per_g": self.law_deg_per_g,
                "law_understeer_gradient_deg_per_g": self.law_understeer_gradient_deg_per_g}


@dataclass(frozen=True)
class HandlingReport:
    """What ``fourws handling`` prints: the 2-DOF model's FWS properties and the law's
    comparison (``speeds_model_level``), and every level's speeds side by side (``levels``)."""

    vehicle: str
    law: str
    understeer_gradient_rad_per_mps2: float
    characteristic_speed_mps: float | None
    critical_speed_mps: float | None
    law_critical_speed_mps: float | None
    equal_slope_speed_mps: float | None
    slopes: list[SlopeRow] = field(default_factory=list)
    levels: LevelComparison = field(default_factory=LevelComparison)
    #: The model level of the speeds and gradient above (the levels' entry with this name).
    speeds_model_level: str = "2dof"

    @property
    def understeer_gradient_deg_per_g(self) -> float:
        """K_us in degrees of front steer per g."""
        return math.degrees(self.understeer_gradient_rad_per_mps2) * GRAVITY_MPS2

    @property
    def steer_character(self) -> str:
        """"understeer", "oversteer" or "neutral" (FWS)."""
        k = self.understeer_gradient_rad_per_mps2
        return "understeer" if k > 0 else ("oversteer" if k < 0 else "neutral")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping with the stable keys of ``fourws handling --json``."""
        return {"vehicle": self.vehicle, "law": self.law,
                "understeer_gradient_rad_per_mps2": self.understeer_gradient_rad_per_mps2,
                "understeer_gradient_deg_per_g": self.understeer_gradient_deg_per_g,
                "steer_character": self.steer_character,
                "characteristic_speed_mps": self.characteristic_speed_mps,
                "critical_speed_mps": self.critical_speed_mps,
                "law_critical_speed_mps": self.law_critical_speed_mps,
                "equal_slope_speed_mps": self.equal_slope_speed_mps,
                "slopes": [s.to_dict() for s in self.slopes],
                "speeds_model_level": self.speeds_model_level,
                **self.levels.to_dict()}


def handling_report(vehicle: Vehicle, law: Law | str = "fws",
                    speeds_mps: Sequence[float] = DEFAULT_SLOPE_SPEEDS_MPS) -> HandlingReport:
    """Understeer gradient, characteristic/critical speed, equal-slope speed and slopes (the
    2-DOF model), and every model level's speeds side by side."""
    law_obj = make_law(law, vehicle) if isinstance(law, str) else law
    levels = critical_speeds.compare_levels(vehicle, law_obj)
    two = levels.by_level("2dof")
    char, crit, law_crit = (two.characteristic_speed_mps, two.critical_speed_mps,
                            two.law_critical_speed_mps)
    u_ss = equal_slope_speed(vehicle, law_obj)
    rows = []
    per_g = math.degrees(1.0) * GRAVITY_MPS2
    for u in speeds_mps:
        u = check_speed(u, "speeds_mps")
        try:
            s_law: float | None = steer_slope(vehicle, law_obj, u)
        except IncompatibleError:
            s_law = None
        L = vehicle.chassis.wheelbase_m
        rows.append(SlopeRow(u, fws_steer_slope(vehicle, u) * per_g,
                             None if s_law is None else s_law * per_g,
                             None if s_law is None else (s_law - L / (u * u)) * per_g))
    return HandlingReport(vehicle.name, law_obj.name, understeer_gradient(vehicle), char, crit,
                          law_crit, u_ss, rows, levels)
