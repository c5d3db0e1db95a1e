r"""Free steering control: the critical speed of the linearized 8-DOF with its steering system
against the 2-DOF free-control model of the same car (Samsundar 1996, ch. 3.4/4.4).

The paper's free-control model (:mod:`fourws_sim.models.free2dof`, eq. 4.53) is the
first-order steering system :math:`\nu\dot\delta_f = T_f - \eta F_{yf}` on the linear 2-DOF;
its critical speed comes from the Routh-Hurwitz condition (4.59) (Table 4.4's car: 67.6 m/s).
The 8-DOF's steering system (:mod:`fourws_sim.models.eightdof`, model ``8dof-free``) adds the
inertia and the Coulomb friction and sits on the full car (roll, roll steer, load transfer,
the tire model's cornering stiffness and aligning moment). Its free-control critical speed is
the lowest speed at which an eigenvalue of the 8-DOF linearized at straight running, closed
with the law (the law's front-angle gain on the steering system's angle), crosses into the
right half plane.

Choice: the linearization leaves the Coulomb friction out (``coulomb_friction_nm`` set to 0).
A friction torque has no small-signal linearization: below its breakaway torque it holds the
steering wheel, so at small amplitude the car with friction is the fixed-control car, and a
finite difference through the stuck band gives a fast decay mode of the stick law instead of
the free system's dynamics. The paper's free-control system has viscous damping only; so has
the linearized 8-DOF here.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from fourws_analysis import linear, linearize
from fourws_sim.errors import ParameterError
from fourws_sim.params import Vehicle


@dataclass(frozen=True)
class FreeControlComparison:
    """Free-control critical speeds of one car and law.

    Attributes
    ----------
    law : str
    two_dof : linear.CriticalSpeed
        Of the 2-DOF free-control model (``2dof-free``).
    eight_dof : linear.CriticalSpeed or None
        Of the linearized 8-DOF with its steering system (None when the car has no 8-DOF
        data, ``eight_dof_unavailable`` says why).
    eight_dof_unavailable : str
    """

    law: str
    two_dof: linear.CriticalSpeed
    eight_dof: linear.CriticalSpeed | None
    eight_dof_unavailable: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"law": self.law, "2dof-free": self.two_dof.to_dict(),
                "8dof-free": None if self.eight_dof is None else self.eight_dof.to_dict(),
                "8dof-free_unavailable": self.eight_dof_unavailable or None,
                "8dof-free_coulomb_friction": "left out of the linearization (no small-signal "
                                              "linear form; see fourws_analysis.free_control)"}


def without_friction(vehicle: Vehicle) -> Vehicle:
    """``vehicle`` with the steering system's Coulomb friction set to 0 (module docstring)."""
    if vehicle.steering is None or vehicle.steering.coulomb_friction_nm == 0.0:
        return vehicle
    return dataclasses.replace(vehicle, steering=dataclasses.replace(
        vehicle.steering, coulomb_friction_nm=0.0))


def eightdof_free_max_real_part(vehicle: Vehicle, speed_mps: float, law: Any = "fws",
                                belief_vehicle: Vehicle | None = None,
                                law_options: Mapping[str, Any] | None = None) -> float:
    """Largest real part (1/s) of the closed-loop eigenvalues of the 8-DOF with its free
    steering system linearized at straight running at ``speed_mps`` (friction left out)."""
    loop = linearize.eightdof_loop(without_friction(vehicle), speed_mps, law, belief_vehicle,
                                   law_options, free_steering=True)
    return float(np.max(loop.lateral_eigenvalues().real))


def eightdof_free_critical_speed(vehicle: Vehicle, law: Any = "fws",
                                 belief_vehicle: Vehicle | None = None,
                                 law_options: Mapping[str, Any] | None = None,
                                 speed_range_mps: tuple[float, float] = (
                                     linear.CRITICAL_SPEED_RANGE_MPS),
                                 samples: int = 60) -> linear.CriticalSpeed:
    """Free-control critical speed of the linearized 8-DOF (module docstring).

    Parameters
    ----------
    vehicle : Vehicle
        Needs ``roll``, ``body`` and ``steering`` with ``inertia_kgm2 > 0``.
    law : str or Law
        Rear-steer law (``fws``: none).
    samples : int
        Speeds sampled (geometric grid) before the crossing is refined with brentq.

    Raises
    ------
    ParameterError
        The vehicle lacks what the 8dof-free model needs, or a bad range.
    """
    def margin(u: float) -> float:
        return -eightdof_free_max_real_part(vehicle, u, law, belief_vehicle, law_options)

    return linear.search_critical_speed(margin, speed_range_mps, samples)


def compare_free_control(vehicle: Vehicle, law: Any = "fws",
                         speed_range_mps: tuple[float, float] = linear.CRITICAL_SPEED_RANGE_MPS
                         ) -> FreeControlComparison:
    """The free-control critical speeds of the 2-DOF model and of the linearized 8-DOF for
    ``vehicle`` with ``law`` (the 8-DOF's left out, with the reason, when the car has no 8-DOF
    or steering-system data)."""
    law_obj = law if not isinstance(law, str) else linear._law(law, vehicle)
    two = linear.critical_speed("2dof-free", vehicle, law_obj, speed_range_mps)
    try:
        eight = eightdof_free_critical_speed(vehicle, law_obj, speed_range_mps=speed_range_mps)
        why = ""
    except ParameterError as exc:
        eight, why = None, str(exc)
    return FreeControlComparison(law_obj.name, two, eight, why)


__all__ = ["FreeControlComparison", "compare_free_control", "eightdof_free_critical_speed",
           "eightdof_free_max_real_part", "without_friction"]
