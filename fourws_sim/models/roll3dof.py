# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Linear 3-DOF yaw/sideslip/roll model with roll steer (Samsundar 1996, ch. 3.5 and 6.1).

A sprung mass :math:`m_s` rolls by :math:`\phi` about a fixed roll axis, its CG a height
:math:`h` above it; roll stiffness :math:`K_\phi` and damping :math:`C_\phi` (totals of both
axles), roll inertia :math:`I_x` about the roll axis and roll-yaw product :math:`I_{xz}`.
Roll steer adds :math:`\varepsilon_i \phi` to each road-wheel angle. Re-derived in fourws
axes (ISO 8855: y left, z up, :math:`\phi` positive right side down, so a left turn rolls the
body to positive :math:`\phi`); the sprung CG moves by :math:`-h\phi` laterally:

.. math::

    m(\dot V + U r) - m_s h \ddot\phi &= F_{yf} + F_{yr} \\
    I_z \dot r - I_{xz} \ddot\phi &= a F_{yf} - b F_{yr} \\
    I_x \ddot\phi - I_{xz} \dot r - m_s h (\dot V + U r)
        &= (m_s g h - K_\phi)\phi - C_\phi \dot\phi \\
    F_{yf} = -C_f\left(\frac{V + a r}{U} - \delta_f - \varepsilon_f \phi\right), &\quad
    F_{yr} = -C_r\left(\frac{V - b r}{U} - \delta_r - \varepsilon_r \phi\right).

This is the paper's eq. 6.1-6.3 with its signs mapped to fourws axes: the paper writes
:math:`+m_s h \ddot\phi` and :math:`+I_{xz}` couplings because its roll angle is positive the
other way round; :math:`I_{xz}` keeps the paper's value and meaning (the coupling sign
above). States ``[V, r, phi, phi_dot]``, inputs ``[delta_f, delta_r]``. With
:math:`m_s h = I_{xz} = \varepsilon_f = \varepsilon_r = 0` the V-r block is the 2-DOF model.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from fourws_sim.models import check_speed
from fourws_sim.models import linear2dof
from fourws_sim.params import GRAVITY_MPS2, Vehicle


class STATE(IntEnum):
    """State components."""

    V = 0  #: lateral velocity, m/s
    R = 1  #: yaw rate, rad/s
    PHI = 2  #: roll angle, rad (positive right side down)
    PHI_DOT = 3  #: roll rate, rad/s


#: Inputs: the front and rear road-wheel angles, as in the 2-DOF model.
INPUT = linear2dof.INPUT


@dataclass(frozen=True)
class Params:
    """Parameters of the 3-DOF roll model at one speed.

    Attributes
    ----------
    fixed : linear2dof.Params
        The 2-DOF parameters at the same speed.
    sprung_mass_kg, roll_arm_m, roll_inertia_kgm2, roll_yaw_product_kgm2 : float
        m_s (kg), h (m), I_x (kg m^2), I_xz (kg m^2).
    roll_stiffness_nm_per_rad, roll_damping_nms_per_rad : float
        Total K_phi (N m/rad) and C_phi (N m s/rad).
    roll_steer_front, roll_steer_rear : float
        eps_f, eps_r in rad of road-wheel steer per rad of roll.
    M, A, B : numpy.ndarray
        Mass matrix of the second-order form and the first-order A (4x4), B (4x2).
    """

    fixed: linear2dof.Params
    sprung_mass_kg: float
    roll_arm_m: float
    roll_inertia_kgm2: float
    roll_yaw_product_kgm2: float
    roll_stiffness_nm_per_rad: float
    roll_damping_nms_per_rad: float
    roll_steer_front: float
    roll_steer_rear: float
    M: np.ndarray
    A: np.ndarray
    B: np.ndarray


def params_for(vehicle: Vehicle, speed_mps: float) -> Params:
    """Build the model parameters of ``vehicle`` at ``speed_mps`` (m/s).

    Raises
    ------
    ParameterError
        If the speed is not finite and > 0 or the vehicle has no ``roll`` subsystem.
    """
    vehicle.require("roll", user="3dof model")
    u = check_speed(speed_mps, vehicle.source or vehicle.name)
    fixed = linear2dof.params_for(vehicle, u)
    rl = vehicle.roll
    m, iz, a, b = fixed.mass_kg, fixed.yaw_inertia_kgm2, fixed.a_m, fixed.b_m
    cf, cr = fixed.cf_n_per_rad, fixed.cr_n_per_rad
    msh = rl.sprung_mass_kg * rl.roll_arm_m
    ix, ixz = rl.roll_inertia_kgm2, rl.roll_yaw_product_kgm2
    k_phi, c_phi = rl.roll_stiffness_nm_per_rad, rl.roll_damping_nms_per_rad
    ef, er = rl.roll_steer_front, rl.roll_steer_rear
    S = STATE
    # Second-order form  M x' = F x + G u  (rows: lateral, yaw, roll kinematics, roll).
    M = np.zeros((4, 4))
    M[0, [S.V, S.PHI_DOT]] = [m, -msh]
    M[1, [S.R, S.PHI_DOT]] = [iz, -ixz]
    M[2, S.PHI] = 1.0
    M[3, [S.V, S.R, S.PHI_DOT]] = [-msh, -ixz, ix]
    # Axle forces as rows over x: Fyf = kf @ x + gf @ u
    kf = np.array([-cf / u, -cf * a / u, cf * ef, 0.0])
    kr = np.array([-cr / u, cr * b / u, cr * er, 0.0])
    gf = np.array([cf, 0.0])
    gr = np.array([0.0, cr])
    F = np.zeros((4, 4))
    F[0] = kf + kr
    F[0, S.R] -= m * u
    F[1] = a * kf - b * kr
    F[2, S.PHI_DOT] = 1.0
    F[3, S.R] = msh * u
    F[3, S.PHI] = rl.sprung_mass_kg * GRAVITY_MPS2 * rl.roll_arm_m - k_phi
    F[3, S.PHI_DOT] = -c_phi
    G = np.zeros((4, 2))
    G[0] = gf + gr
    G[1] = a * gf - b * gr
    A = np.linalg.solve(M, F)
    B = np.linalg.solve(M, G)
    return Params(fixed, rl.sprung_mass_kg, rl.roll_arm_m, ix, ixz, k_phi, c_phi, ef, er,
                  M, A, B)


def matrices(vehicle: Vehicle, speed_mps: float) -> tuple[np.ndarray, np.ndarray]:
    """State matrix A (4x4) and input matrix B (4x2) at ``speed_mps`` (m/s)."""
    p = params_for(vehicle, speed_mps)
    return p.A.copy(), p.B.copy()


def derivatives(t: float, x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """State derivative ``[dV/dt, dr/dt, dphi/dt, dphi_dot/dt] = A x + B u`` (SI)."""
    return p.A @ np.asarray(x, dtype=float) + p.B @ np.asarray(u, dtype=float)
