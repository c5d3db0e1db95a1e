# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Linear 2-DOF bicycle model, fixed steering control (Samsundar 1996, ch. 3.3 and 4.1).

Lateral velocity V and yaw rate r of a rigid vehicle at constant forward speed U, one
equivalent wheel per axle, front and rear road-wheel angles as inputs:

.. math::

    m(\dot V + U r) = F_{yf} + F_{yr}, \qquad I_z \dot r = a F_{yf} - b F_{yr},

    \alpha_f = \frac{V + a r}{U} - \delta_f, \quad
    \alpha_r = \frac{V - b r}{U} - \delta_r, \quad F_{yi} = -C_i \alpha_i,

with :math:`a`, :math:`b` the CG-to-axle distances and :math:`C_f`, :math:`C_r` the per-axle
cornering stiffnesses (fourws convention: ISO 8855 axes, y and r positive to the left, a
positive steer angle turns left, so a left turn has negative front slip). Hence

.. math::

    A = \begin{bmatrix} -\frac{C_f + C_r}{m U} & -U - \frac{a C_f - b C_r}{m U} \\
        -\frac{a C_f - b C_r}{I_z U} & -\frac{a^2 C_f + b^2 C_r}{I_z U} \end{bmatrix},
    \qquad
    B = \begin{bmatrix} \frac{C_f}{m} & \frac{C_r}{m} \\
        \frac{a C_f}{I_z} & -\frac{b C_r}{I_z} \end{bmatrix}

(the paper's eqs. 3.6-3.10 and 4.1-4.2, re-derived). This matches Table 4.3's FWS
eigenvalues for both data sets of Table 4.1 (see ``test/test_linear_models.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from fourws_sim.models import check_speed
from fourws_sim.params import Vehicle


class STATE(IntEnum):
    """State components."""

    V = 0  #: lateral velocity of the CG in the body frame, m/s (positive left)
    R = 1  #: yaw rate, rad/s (positive left)


class INPUT(IntEnum):
    """Input components."""

    DELTA_F = 0  #: front road-wheel angle, rad (positive left)
    DELTA_R = 1  #: rear road-wheel angle, rad (positive left)


@dataclass(frozen=True)
class Params:
    """Parameters of the linear 2-DOF model at one speed (SI units).

    Attributes
    ----------
    mass_kg, yaw_inertia_kgm2 : float
        m in kg, Iz in kg m^2.
    a_m, b_m : float
        CG to front / rear axle in m.
    cf_n_per_rad, cr_n_per_rad : float
        Per-axle cornering stiffness in N/rad.
    speed_mps : float
        Forward speed U in m/s.
    A, B : numpy.ndarray
        State and input matrices (rows/cols in ``STATE``/``INPUT`` order).
    """

    mass_kg: float
    yaw_inertia_kgm2: float
    a_m: float
    b_m: float
    cf_n_per_rad: float
    cr_n_per_rad: float
    speed_mps: float
    A: np.ndarray
    B: np.ndarray


def _matrices(m: float, iz: float, a: float, b: float, cf: float, cr: float,
              u: float) -> tuple[np.ndarray, np.ndarray]:
    A = np.array([
        [-(cf + cr) / (m * u), -u - (a * cf - b * cr) / (m * u)],
        [-(a * cf - b * cr) / (iz * u), -(a * a * cf + b * b * cr) / (iz * u)],
    ])
    B = np.array([
        [cf / m, cr / m],
        [a * cf / iz, -b * cr / iz],
    ])
    return A, B


def params_for(vehicle: Vehicle, speed_mps: float) -> Params:
    """Build the model parameters of ``vehicle`` at forward speed ``speed_mps`` (m/s).

    Raises
    ------
    ParameterError
        If the speed is not finite and > 0.
    """
    u = check_speed(speed_mps, vehicle.source or vehicle.name)
    c, t = vehicle.chassis, vehicle.axle_tires
    args = (c.mass_kg, c.yaw_inertia_kgm2, c.cg_to_front_axle_m, c.cg_to_rear_axle_m,
            t.cornering_stiffness_front_n_per_rad, t.cornering_stiffness_rear_n_per_rad)
    A, B = _matrices(*args, u)
    return Params(*args, u, A, B)


def matrices(vehicle: Vehicle, speed_mps: float) -> tuple[np.ndarray, np.ndarray]:
    """State matrix A (2x2, 1/s and m/s/rad units) and input matrix B (2x2) at ``speed_mps``."""
    p = params_for(vehicle, speed_mps)
    return p.A.copy(), p.B.copy()


def derivatives(t: float, x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """State derivative ``[dV/dt (m/s^2), dr/dt (rad/s^2)] = A x + B u``."""
    return p.A @ np.asarray(x, dtype=float) + p.B @ np.asarray(u, dtype=float)
