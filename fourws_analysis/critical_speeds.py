# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Critical and characteristic speeds per model level, and why the levels differ.

Three levels of the same car (each the one function behind its number in ``fourws handling``,
``fourws linear`` and the analysis report):

``2dof``
    the bicycle model with ``axle_tires`` (no roll): understeer gradient
    :math:`K_{us} = \frac{m}{L}(\frac{b}{C_f} - \frac{a}{C_r})`, characteristic speed
    :math:`\sqrt{L/K_{us}}` (understeer) or critical speed
    :math:`U_{crit} = \sqrt{-L/K_{us}} = \sqrt{L^2 C_f C_r / (m (a C_f - b C_r))}`
    (oversteer; the paper's eq. 4.93, Wong, *Theory of Ground Vehicles*; ``C`` per axle);
``3dof``
    the same tires with the roll degree of freedom and roll steer
    (:mod:`fourws_sim.models.roll3dof`). In a steady turn the body rolls by
    :math:`\phi = R_\phi a_y`, :math:`R_\phi = m_s h/(K_\phi - m_s g h)`, and the wheels steer
    by :math:`\varepsilon_i \phi` more, so the axles act with the effective cornering
    stiffnesses :math:`C_f^* = C_f/(1 - C_f \varepsilon_f R_\phi L/(m b))`,
    :math:`C_r^* = C_r/(1 - C_r \varepsilon_r R_\phi L/(m a))` (from
    :math:`F_f = C_f(\delta_f + \varepsilon_f\phi - \alpha_{kin})` with
    :math:`a_y = L F_f/(m b) = L F_r/(m a)`), i.e.
    :math:`K^* = K_{us} - (\varepsilon_f - \varepsilon_r) R_\phi`: positive roll steer at the
    front or negative at the rear turns an understeering tire set into an oversteering car;
``8dof-lin``
    the 8-DOF linearized at straight running (:func:`fourws_analysis.linearize.eightdof_loop`):
    its cornering stiffnesses are its tire model's at the static loads, not ``axle_tires``',
    and it adds the tires' aligning moments, roll steer, tire lag and the wheels; lateral load
    transfer has no first-order effect at straight running.

The critical speed is the lowest speed of the search range where the closed loop (the
level's model with the law's linear gains) has an eigenvalue right of the imaginary axis
(:func:`fourws_analysis.linear.search_critical_speed`). The understeer gradient of a level is
its steady-state steer gradient less the kinematic part, :math:`\delta_f/a_y - L/U^2`
(FWS), evaluated at :data:`GRADIENT_SPEED_MPS` (independent of the speed for these models).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import control
import numpy as np

from fourws_analysis import linear, linearize, units
from fourws_analysis.frequency import dc_gain
from fourws_analysis.memo import Memo
from fourws_control import Law, make_law
from fourws_sim.errors import FourwsError
from fourws_sim.params import Vehicle

#: Model levels, name -> label (the label names the level wherever a speed is printed).
LEVELS: dict[str, str] = {
    "2dof": "2-DOF",
    "3dof": "3-DOF with roll steer",
    "8dof-lin": "8-DOF linearized",
}
#: What each level is, for a legend.
LEVEL_DESCRIPTIONS: dict[str, str] = {
    "2dof": "bicycle model with the axle_tires cornering stiffnesses, no roll",
    "3dof": "axle_tires with roll and roll steer",
    "8dof-lin": "8-DOF linearized at straight running: its tire model at the static loads, "
                "aligning moments, roll steer, tire lag, wheels",
}
#: Subsystems each level needs of the vehicle.
LEVEL_NEEDS: dict[str, tuple[str, ...]] = {"2dof": (), "3dof": ("roll",),
                                           "8dof-lin": ("roll", "body")}
#: Speed at which a level's understeer gradient is evaluated, m/s.
GRADIENT_SPEED_MPS = 10.0
#: Eigenvalues of the linearized 8-DOF nearer zero than this (1/s) are its position, heading,
#: speed and wheel-spin modes at a trim without drag (not a loss of lateral stability).
EIGHTDOF_ZERO_TOL_PER_S = 1e-6


def _law(law: Law | str | None, vehicle: Vehicle) -> Law:
    return make_law(law or "fws", vehicle) if not isinstance(law, Law) else law


def critical_speed(level: str, vehicle: Vehicle, law: Law | str | None = "fws",
                   speed_range_mps: tuple[float, float] = linear.CRITICAL_SPEED_RANGE_MPS
                   ) -> linear.CriticalSpeed:
    """The critical speed of ``vehicle`` closed with ``law`` at model level ``level`` (a key of
    :data:`LEVELS`): the one function behind every tool's number for that level.

    Raises
    ------
    ParameterError
        The vehicle lacks what the level needs (``roll``, ``body``), or a bad range.
    UnknownNameError
        Unknown level.
    """
    _check_level(level)
    law_obj = _law(law, vehicle)
    if level != "8dof-lin":
        return linear.critical_speed(level, vehicle, law_obj, speed_range_mps)
    vehicle.require(*LEVEL_NEEDS[level], user="the linearized 8-DOF")

    def margin(u: float) -> float:
        ev = linearize.eightdof_loop(vehicle, u, law_obj).lateral_eigenvalues(
            EIGHTDOF_ZERO_TOL_PER_S)
        return -float(np.max(ev.real))

    return linear.search_critical_speed(margin, speed_range_mps)


def understeer_gradient(level: str, vehicle: Vehicle,
                        speed_mps: float = GRADIENT_SPEED_MPS) -> float:
    """FWS understeer gradient of level ``level``, rad/(m/s^2) (> 0 understeer):
    ``delta_f/a_y - L/U^2`` of its steady state (the 2-DOF's is exactly K_us)."""
    _check_level(level)
    if level == "8dof-lin":
        vehicle.require(*LEVEL_NEEDS[level], user="the linearized 8-DOF")
        loop = linearize.eightdof_loop(vehicle, speed_mps, "fws")
        mod = loop.model
        inp = units.ROAD_WHEEL.channel
        sys = control.ss(loop.closed, loop.b[:, [mod.INPUT.DELTA_F]],
                         np.eye(loop.a.shape[0])[[mod.STATE.R]], np.zeros((1, 1)),
                         inputs=[inp], outputs=["yaw_rate"])
        yaw_gain = dc_gain(sys, "yaw_rate", inp)
    else:
        cl = linear.closed_loop(level, vehicle, "fws", speed_mps)
        yaw_gain = linear.steady_state_gains(cl)[f"yaw_rate/{cl.input_names[0]}"]
    return 1.0 / (speed_mps * yaw_gain) - vehicle.chassis.wheelbase_m / speed_mps ** 2


def roll_gradient_rad_per_mps2(vehicle: Vehicle) -> float:
    """Steady roll per lateral acceleration of the 3-DOF, ``m_s h/(K_phi - m_s g h)``."""
    vehicle.require("roll", user="roll_gradient")
    r = vehicle.roll
    assert r is not None
    msh = r.sprung_mass_kg * r.roll_arm_m
    return msh / (r.roll_stiffness_nm_per_rad - msh * 9.80665)


def effective_cornering_stiffness(vehicle: Vehicle) -> tuple[float, float]:
    """The 3-DOF's effective axle cornering stiffnesses with roll steer (module docstring),
    N/rad: ``(C_f*, C_r*)``."""
    c, t, r = vehicle.chassis, vehicle.axle_tires, vehicle.roll
    vehicle.require("roll", user="effective_cornering_stiffness")
    assert r is not None
    k = roll_gradient_rad_per_mps2(vehicle) * c.wheelbase_m / c.mass_kg
    cf, cr = t.cornering_stiffness_front_n_per_rad, t.cornering_stiffness_rear_n_per_rad
    return (cf / (1.0 - cf * r.roll_steer_front * k / c.cg_to_rear_axle_m),
            cr / (1.0 - cr * r.roll_steer_rear * k / c.cg_to_front_axle_m))


def _check_level(level: str) -> None:
    if level not in LEVELS:
        from fourws_sim.errors import UnknownNameError  # only on the error path

        raise UnknownNameError("model level", level, list(LEVELS))


@dataclass(frozen=True)
class LevelSpeeds:
    """One model level's speeds (m/s) and FWS understeer gradient (rad/(m/s^2)).

    ``critical_speed_mps`` is FWS's, ``law_critical_speed_mps`` the law's closed loop;
    ``unavailable`` says why a level was not computed (then every number is None).
    """

    level: str
    understeer_gradient_rad_per_mps2: float | None = None
    characteristic_speed_mps: float | None = None
    critical_speed_mps: float | None = None
    law_critical_speed_mps: float | None = None
    searched_range_mps: tuple[float, float] = linear.CRITICAL_SPEED_RANGE_MPS
    unavailable: str = ""

    @property
    def label(self) -> str:
        """The level's name as printed."""
        return LEVELS[self.level]

    @property
    def steer_character(self) -> str | None:
        """"understeer", "oversteer" or "neutral" (FWS), None when unavailable."""
        k = self.understeer_gradient_rad_per_mps2
        if k is None:
            return None
        return "understeer" if k > 0 else ("oversteer" if k < 0 else "neutral")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (stable keys)."""
        return {"level": self.level, "label": self.label,
                "understeer_gradient_rad_per_mps2": self.understeer_gradient_rad_per_mps2,
                "steer_character": self.steer_character,
                "characteristic_speed_mps": self.characteristic_speed_mps,
                "critical_speed_mps": self.critical_speed_mps,
                "law_critical_speed_mps": self.law_critical_speed_mps,
                "searched_range_mps": list(self.searched_range_mps),
                "unavailable": self.unavailable or None}


#: FWS critical speeds already found in this process, by level, range and vehicle: every
#: law's comparison of one car starts from the same FWS speeds (a demo's laws of one car).
_FWS_CACHE: Memo[linear.CriticalSpeed] = Memo(64)


def _fws_critical_speed(level: str, vehicle: Vehicle, speed_range_mps: tuple[float, float]
                        ) -> linear.CriticalSpeed:
    """:func:`critical_speed` of ``vehicle`` without rear steer (kept in :data:`_FWS_CACHE`;
    a search that raises is not kept)."""
    key = f"{level}|{tuple(float(s) for s in speed_range_mps)}|{vehicle.cache_key()}"
    found = _FWS_CACHE.get(key, lambda: critical_speed(level, vehicle, "fws", speed_range_mps))
    assert found is not None  # (critical_speed returns a result or raises)
    return found


def level_speeds(level: str, vehicle: Vehicle, law: Law | str | None = "fws",
                 speed_range_mps: tuple[float, float] = linear.CRITICAL_SPEED_RANGE_MPS
                 ) -> LevelSpeeds:
    """:class:`LevelSpeeds` of one level (``unavailable`` set instead of raising when the
    vehicle lacks the level's data)."""
    _check_level(level)
    missing = [s for s in LEVEL_NEEDS[level] if getattr(vehicle, s) is None]
    if missing:
        return LevelSpeeds(level, searched_range_mps=tuple(speed_range_mps),  # type: ignore
                           unavailable=f"the vehicle has no {' and no '.join(missing)} data")
    law_obj = _law(law, vehicle)
    try:
        k = understeer_gradient(level, vehicle)
        fws = _fws_critical_speed(level, vehicle, speed_range_mps)
        with_law = fws if law_obj.name == "fws" else \
            critical_speed(level, vehicle, law_obj, speed_range_mps)
    except (FourwsError, np.linalg.LinAlgError) as exc:
        return LevelSpeeds(level, searched_range_mps=tuple(speed_range_mps),  # type: ignore
                           unavailable=str(exc))
    char = math.sqrt(vehicle.chassis.wheelbase_m / k) if k > 0.0 else None
    return LevelSpeeds(level, k, char, fws.critical_speed_mps, with_law.critical_speed_mps,
                       tuple(speed_range_mps))  # type: ignore[arg-type]


@dataclass(frozen=True)
class LevelComparison:
    """Every level's speeds side by side, and the sentences on why they differ."""

    levels: list[LevelSpeeds] = field(default_factory=list)
    why: list[str] = field(default_factory=list)

    def by_level(self, level: str) -> LevelSpeeds:
        """The entry of ``level``."""
        return next(s for s in self.levels if s.level == level)

    @property
    def roll_steer_oversteer(self) -> bool:
        """The tire set understeers (2-DOF) but the car with roll steer oversteers (3-DOF)."""
        two, three = (self.by_level(n).understeer_gradient_rad_per_mps2
                      for n in ("2dof", "3dof"))
        return two is not None and three is not None and two > 0.0 > three

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"levels": [s.to_dict() for s in self.levels], "why_they_differ": self.why,
                "roll_steer_makes_oversteer": self.roll_steer_oversteer}


def _fmt_k(k: float) -> str:
    return f"{k:+.3g} rad/(m/s^2)"


def _why(vehicle: Vehicle, levels: dict[str, LevelSpeeds]) -> list[str]:
    """One sentence per pair of neighbouring levels that both have numbers."""
    out = []
    two, three, eight = levels.get("2dof"), levels.get("3dof"), levels.get("8dof-lin")
    if two and three and two.understeer_gradient_rad_per_mps2 is not None \
            and three.understeer_gradient_rad_per_mps2 is not None:
        r = vehicle.roll
        assert r is not None
        k2, k3 = two.understeer_gradient_rad_per_mps2, three.understeer_gradient_rad_per_mps2
        eps = r.roll_steer_front - r.roll_steer_rear
        cf, cr = effective_cornering_stiffness(vehicle)
        turn = ("makes the understeering tire set an oversteering car" if k2 > 0.0 > k3 else
                "makes the oversteering tire set an understeering car" if k2 < 0.0 < k3 else
                "shifts it")
        out.append(f"2-DOF vs 3-DOF: roll steer (eps_f - eps_r = {eps:+.3g} rad/rad at a roll "
                   f"gradient of {roll_gradient_rad_per_mps2(vehicle):.3g} rad/(m/s^2)) "
                   f"changes K_us from {_fmt_k(k2)} to {_fmt_k(k3)} and {turn}: the axles act "
                   f"with {cf / 1e3:.1f}/{cr / 1e3:.1f} kN/rad instead of "
                   f"{vehicle.axle_tires.cornering_stiffness_front_n_per_rad / 1e3:.1f}/"
                   f"{vehicle.axle_tires.cornering_stiffness_rear_n_per_rad / 1e3:.1f}.")
    if three and eight and three.understeer_gradient_rad_per_mps2 is not None \
            and eight.understeer_gradient_rad_per_mps2 is not None:
        tire, cf8, cr8 = _tire_axle_stiffness(vehicle)
        out.append(f"3-DOF vs 8-DOF linearized: the 8-DOF takes its cornering stiffnesses from "
                   f"its {tire} tire at the static loads ({cf8 / 1e3:.1f}/{cr8 / 1e3:.1f} "
                   f"kN/rad per axle, not axle_tires') and adds the tires' aligning moments, "
                   f"tire lag and the wheels (K_us "
                   f"{_fmt_k(eight.understeer_gradient_rad_per_mps2)}); lateral load transfer "
                   "does not act at straight running, so it moves only the limit of the "
                   "nonlinear car in a turn.")
    return out


def _tire_axle_stiffness(vehicle: Vehicle) -> tuple[str, float, float]:
    """The 8-DOF's tire model name and its per-axle cornering stiffness at the static loads,
    N/rad."""
    from fourws_sim.tires import cornering_stiffness, get_tire  # numba: the tires load it

    name = vehicle.tire.model if vehicle.tire is not None else "linear"
    module = get_tire(name)
    c = vehicle.chassis
    mu = vehicle.tire.friction_coefficient if vehicle.tire is not None else 1.0
    loads = (c.mass_kg * 9.80665 * c.cg_to_rear_axle_m / (2.0 * c.wheelbase_m),
             c.mass_kg * 9.80665 * c.cg_to_front_axle_m / (2.0 * c.wheelbase_m))
    cf, cr = (2.0 * cornering_stiffness(name, module.pack(vehicle, axle), fz, mu)
              for axle, fz in zip(("front", "rear"), loads))
    return name, cf, cr


def compare_levels(vehicle: Vehicle, law: Law | str | None = "fws",
                   speed_range_mps: tuple[float, float] = linear.CRITICAL_SPEED_RANGE_MPS,
                   levels: tuple[str, ...] = tuple(LEVELS)) -> LevelComparison:
    """Every level's :class:`LevelSpeeds` and the sentences on why they differ."""
    got = {n: level_speeds(n, vehicle, law, speed_range_mps) for n in levels}
    return LevelComparison(list(got.values()), _why(vehicle, got))


__all__ = ["LEVELS", "LEVEL_DESCRIPTIONS", "LevelComparison", "LevelSpeeds", "compare_levels",
           "critical_speed", "effective_cornering_stiffness", "level_speeds",
           "roll_gradient_rad_per_mps2", "understeer_gradient"]
