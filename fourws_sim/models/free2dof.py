# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Linear 2-DOF bicycle model, free steering control (Samsundar 1996, ch. 3.4 and 4.4).

The front road-wheel angle is a state: the steering system is the first-order (highly damped)
system of eq. 3.19 / 4.53, viscous damping :math:`\nu` about the kingpin, driver torque
:math:`T_f` and the aligning torque of the front lateral force acting a caster/trail
:math:`\eta` behind the steering axis. Rear wheels are steered by an independent actuator, so
the rear force exerts no steering torque (the paper drops that term):

.. math::

    \nu \dot\delta_f = T_f - \eta F_{yf}
        = T_f - \eta C_f \left(\delta_f - \frac{V + a r}{U}\right),

i.e. the lateral force self-aligns the wheel. With the yaw-plane equations of
:mod:`fourws_sim.models.linear2dof` this gives states ``[V, r, delta_f]`` and inputs
``[T_f, delta_r]``. The sign of the aligning term (OCR of eq. 3.19 is damaged) is fixed by the
paper's own result: Table 4.4's vehicle becomes unstable at 67.6 m/s with steering dynamics
(section 4.4.3); the self-aligning sign reproduces that (the opposite sign is unstable at any
speed). :math:`T_f` is the torque about the kingpin, in N m (no steering ratio).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from fourws_sim.errors import ParameterError
from fourws_sim.models import linear2dof
from fourws_sim.params import Vehicle


class STATE(IntEnum):
    """State components."""

    V = 0  #: lateral velocity, m/s
    R = 1  #: yaw rate, rad/s
    DELTA_F = 2  #: front road-wheel angle, rad


class INPUT(IntEnum):
    """Input components."""

    T_F = 0  #: driver steering torque about the front kingpin, N m
    DELTA_R = 1  #: rear road-wheel angle, rad


@dataclass(frozen=True)
class Params:
    """Parameters of the free-control model at one speed.

    Attributes
    ----------
    fixed : linear2dof.Params
        The fixed-control 2-DOF parameters at the same speed.
    damping_nms_per_rad : float
        Steering viscous damping nu in N m s/rad.
    trail_m : float
        Caster/trail eta in m.
    A, B : numpy.ndarray
        3x3 state and 3x2 input matrices (``STATE``/``INPUT`` order).
    """

    fixed: linear2dof.Params
    damping_nms_per_rad: float
    trail_m: float
    A: np.ndarray
    B: np.ndarray


def params_for(vehicle: Vehicle, speed_mps: float) -> Params:
    """Build the model parameters of ``vehicle`` at ``speed_mps`` (m/s).

    Raises
    ------
    ParameterError
        If the speed is not finite and > 0, the vehicle has no ``steering`` subsystem, or its
        steering damping is zero (the first-order steering model divides by it).
    """
    vehicle.require("steering", user="2dof-free model")
    fixed = linear2dof.params_for(vehicle, speed_mps)
    s = vehicle.steering
    nu, eta = s.damping_nms_per_rad, s.trail_m
    if nu <= 0.0:
        raise ParameterError("steering.damping_nms_per_rad",
                             f"must be > 0 for the 2dof-free model, got {nu!r}",
                             vehicle.source or vehicle.name)
    u, a, cf = fixed.speed_mps, fixed.a_m, fixed.cf_n_per_rad
    A = np.zeros((3, 3))
    A[:2, :2] = fixed.A
    A[:2, STATE.DELTA_F] = fixed.B[:, linear2dof.INPUT.DELTA_F]
    A[STATE.DELTA_F] = [eta * cf / (nu * u), eta * cf * a / (nu * u), -eta * cf / nu]
    B = np.zeros((3, 2))
    B[:2, INPUT.DELTA_R] = fixed.B[:, linear2dof.INPUT.DELTA_R]
    B[STATE.DELTA_F, INPUT.T_F] = 1.0 / nu
    return Params(fixed, nu, eta, A, B)


def matrices(vehicle: Vehicle, speed_mps: float) -> tuple[np.ndarray, np.ndarray]:
    """State matrix A (3x3) and input matrix B (3x2) at ``speed_mps`` (m/s)."""
    p = params_for(vehicle, speed_mps)
    return p.A.copy(), p.B.copy()


def derivatives(t: float, x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """State derivative ``[dV/dt, dr/dt, d delta_f/dt] = A x + B u`` (SI)."""
    return p.A @ np.asarray(x, dtype=float) + p.B @ np.asarray(u, dtype=float)
