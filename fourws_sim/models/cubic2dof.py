# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Nonlinear 2-DOF bicycle model with the cubic tire law of Samsundar 1996, ch. 7.

Same yaw-plane equations as :mod:`fourws_sim.models.linear2dof` (eqs. 7.1-7.2), with the
axle force a cubic of the slip angle (eqs. 7.3-7.6):

.. math::

    F_{yi} = -C_i (1 - K_i \alpha_i^2)\,\alpha_i,\qquad
    \alpha_f = \frac{V + a r}{U} - \delta_f, \quad \alpha_r = \frac{V - b r}{U} - \delta_r,

where :math:`C_i = 2 C_{\alpha i}` is the per-axle stiffness (the vehicle file stores the
doubled per-tire value of Table 7.1) and :math:`K_i` (1/rad^2) is
``tire.cubic_coefficient_front/rear_per_rad2``. The force peaks at
:math:`\alpha = 1/\sqrt{3K}` and falls (a crude saturation) beyond; the model is meant for the
neighbourhood of straight running that chapter 7 studies. At the origin the Jacobian is the
linear 2-DOF A matrix. The slip angles are the paper's small-angle kinematics (eqs. 7.5-7.6).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from fourws_sim.models import check_speed, linear2dof
from fourws_sim.params import Vehicle


class STATE(IntEnum):
    """State components."""

    V = 0  #: lateral velocity, m/s
    R = 1  #: yaw rate, rad/s


#: Inputs: the front and rear road-wheel angles, as in the 2-DOF model.
INPUT = linear2dof.INPUT


@dataclass(frozen=True)
class Params:
    """Parameters of the cubic-tire 2-DOF model at one speed (SI units).

    Attributes
    ----------
    mass_kg, yaw_inertia_kgm2, a_m, b_m : float
        m (kg), Iz (kg m^2), CG to front / rear axle (m).
    cf_n_per_rad, cr_n_per_rad : float
        Per-axle cornering stiffness 2 C_alpha in N/rad.
    kf_per_rad2, kr_per_rad2 : float
        Cubic coefficients K of the front / rear axle in 1/rad^2.
    speed_mps : float
        Forward speed U in m/s.
    """

    mass_kg: float
    yaw_inertia_kgm2: float
    a_m: float
    b_m: float
    cf_n_per_rad: float
    cr_n_per_rad: float
    kf_per_rad2: float
    kr_per_rad2: float
    speed_mps: float


def params_for(vehicle: Vehicle, speed_mps: float) -> Params:
    """Build the model parameters of ``vehicle`` at ``speed_mps`` (m/s).

    Raises
    ------
    ParameterError
        If the speed is not finite and > 0 or the vehicle has no ``tire`` subsystem (the
        cubic coefficients live there).
    """
    vehicle.require("tire", user="2dof-cubic model")
    u = check_speed(speed_mps, vehicle.source or vehicle.name)
    c, t, tire = vehicle.chassis, vehicle.axle_tires, vehicle.tire
    return Params(c.mass_kg, c.yaw_inertia_kgm2, c.cg_to_front_axle_m, c.cg_to_rear_axle_m,
                  t.cornering_stiffness_front_n_per_rad, t.cornering_stiffness_rear_n_per_rad,
                  tire.cubic_coefficient_front_per_rad2, tire.cubic_coefficient_rear_per_rad2,
                  u)


def _slips(x: np.ndarray, u: np.ndarray, p: Params) -> tuple[float, float]:
    v, r = x[STATE.V], x[STATE.R]
    alpha_f = (v + p.a_m * r) / p.speed_mps - u[INPUT.DELTA_F]
    alpha_r = (v - p.b_m * r) / p.speed_mps - u[INPUT.DELTA_R]
    return alpha_f, alpha_r


def axle_forces(x: np.ndarray, u: np.ndarray, p: Params) -> tuple[float, float]:
    """Front and rear axle lateral forces in N (positive left) at state ``x``, input ``u``."""
    alpha_f, alpha_r = _slips(np.asarray(x, float), np.asarray(u, float), p)
    fyf = -p.cf_n_per_rad * (1.0 - p.kf_per_rad2 * alpha_f ** 2) * alpha_f
    fyr = -p.cr_n_per_rad * (1.0 - p.kr_per_rad2 * alpha_r ** 2) * alpha_r
    return fyf, fyr


def derivatives(t: float, x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """State derivative ``[dV/dt (m/s^2), dr/dt (rad/s^2)]``."""
    x = np.asarray(x, dtype=float)
    fyf, fyr = axle_forces(x, u, p)
    return np.array([
        (fyf + fyr) / p.mass_kg - p.speed_mps * x[STATE.R],
        (p.a_m * fyf - p.b_m * fyr) / p.yaw_inertia_kgm2,
    ])


def jacobian(x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """Analytic Jacobian d(dx/dt)/dx (2x2) at state ``x`` and input ``u``."""
    x = np.asarray(x, dtype=float)
    alpha_f, alpha_r = _slips(x, np.asarray(u, float), p)
    u_ = p.speed_mps
    # dF/dalpha of F = -C (1 - K a^2) a
    dff = -p.cf_n_per_rad * (1.0 - 3.0 * p.kf_per_rad2 * alpha_f ** 2)
    dfr = -p.cr_n_per_rad * (1.0 - 3.0 * p.kr_per_rad2 * alpha_r ** 2)
    dff_dx = dff * np.array([1.0, p.a_m]) / u_
    dfr_dx = dfr * np.array([1.0, -p.b_m]) / u_
    row_v = (dff_dx + dfr_dx) / p.mass_kg
    row_v[STATE.R] -= u_
    row_r = (p.a_m * dff_dx - p.b_m * dfr_dx) / p.yaw_inertia_kgm2
    return np.vstack([row_v, row_r])
