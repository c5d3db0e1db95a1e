# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Linear 2-DOF bicycle model with time-lagged tire side force (Samsundar 1996, ch. 5).

Stretched-string tire (von Schlippe): the axle side force builds up over the relaxation
length :math:`\sigma_i` of rolled distance, i.e. a first-order lag of time constant
:math:`\sigma_i/U` behind the quasi-static force of the kinematic slip angle (eqs. 5.8-5.19;
the paper has one :math:`\sigma` for both axles, fourws one per axle,
``tire.relaxation_length_front_m`` and ``tire.relaxation_length_rear_m``, since tire lag depends
on the load an axle carries):

.. math::

    \frac{\sigma_i}{U}\dot F_{yi} + F_{yi} = -C_i \alpha_{0i}, \qquad
    \alpha_{0f} = \frac{V + a r}{U} - \delta_f, \quad
    \alpha_{0r} = \frac{V - b r}{U} - \delta_r,

    m(\dot V + U r) = F_{yf} + F_{yr}, \qquad I_z \dot r = a F_{yf} - b F_{yr}.

The paper carries the compliant slip angles :math:`\alpha_c = -F/C` as states; fourws carries
the forces themselves (same dynamics, states in N). States ``[V, r, Fyf, Fyr]``, inputs
``[delta_f, delta_r]``. As :math:`\sigma \to 0` the force states become infinitely fast and
the slow eigenvalues tend to those of :mod:`fourws_sim.models.linear2dof`; the steady state
does not depend on :math:`\sigma_i` (section 5.7).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from fourws_sim.errors import ParameterError
from fourws_sim.models import check_speed
from fourws_sim.models import linear2dof
from fourws_sim.params import Vehicle


class STATE(IntEnum):
    """State components."""

    V = 0  #: lateral velocity, m/s
    R = 1  #: yaw rate, rad/s
    FY_F = 2  #: front axle lateral force, N (positive left)
    FY_R = 3  #: rear axle lateral force, N (positive left)


#: Inputs: the front and rear road-wheel angles, as in the 2-DOF model.
INPUT = linear2dof.INPUT


@dataclass(frozen=True)
class Params:
    """Parameters of the lagged-force model at one speed.

    Attributes
    ----------
    fixed : linear2dof.Params
        The 2-DOF parameters at the same speed.
    relaxation_length_front_m, relaxation_length_rear_m : float
        sigma of the front and rear tires in m (> 0).
    A, B : numpy.ndarray
        4x4 state and 4x2 input matrices.
    """

    fixed: linear2dof.Params
    relaxation_length_front_m: float
    relaxation_length_rear_m: float
    A: np.ndarray
    B: np.ndarray


def params_for(vehicle: Vehicle, speed_mps: float, *,
               relaxation_length_m: float | None = None) -> Params:
    """Build the model parameters of ``vehicle`` at ``speed_mps`` (m/s).

    Parameters
    ----------
    vehicle : Vehicle
        Needs the ``tire`` subsystem (its ``relaxation_length_front_m`` and
        ``relaxation_length_rear_m``) unless ``relaxation_length_m`` is given.
    speed_mps : float
        Forward speed U in m/s.
    relaxation_length_m : float, optional
        Override: sigma in m of both axles (e.g. to sweep it).

    Raises
    ------
    ParameterError
        If the speed is not finite and > 0, or a sigma is missing or not > 0 (sigma = 0 is
        the plain ``2dof`` model).
    """
    source = vehicle.source or vehicle.name
    u = check_speed(speed_mps, source)
    if relaxation_length_m is None:
        vehicle.require("tire", user="2dof-lagged model")
        assert vehicle.tire is not None
        sigma_f = vehicle.tire.relaxation_length_front_m
        sigma_r = vehicle.tire.relaxation_length_rear_m
        fields = ("tire.relaxation_length_front_m", "tire.relaxation_length_rear_m")
    else:
        sigma_f = sigma_r = float(relaxation_length_m)
        fields = ("relaxation_length_m", "relaxation_length_m")
    for field, sigma in zip(fields, (sigma_f, sigma_r)):
        if not np.isfinite(sigma) or sigma <= 0.0:
            raise ParameterError(field, f"must be > 0 for the 2dof-lagged model (0 is the "
                                 f"2dof model; tire.relaxation_length_m sets both axles), "
                                 f"got {sigma!r}", source)
    fixed = linear2dof.params_for(vehicle, u)
    m, iz, a, b = fixed.mass_kg, fixed.yaw_inertia_kgm2, fixed.a_m, fixed.b_m
    cf, cr = fixed.cf_n_per_rad, fixed.cr_n_per_rad
    lag_f = u / sigma_f  # 1/s, inverse time constants of the force build-up
    lag_r = u / sigma_r
    S, IN = STATE, INPUT
    A = np.zeros((4, 4))
    A[S.V, S.R] = -u
    A[S.V, S.FY_F] = A[S.V, S.FY_R] = 1.0 / m
    A[S.R, S.FY_F] = a / iz
    A[S.R, S.FY_R] = -b / iz
    A[S.FY_F] = [-lag_f * cf / u, -lag_f * cf * a / u, -lag_f, 0.0]
    A[S.FY_R] = [-lag_r * cr / u, lag_r * cr * b / u, 0.0, -lag_r]
    B = np.zeros((4, 2))
    B[S.FY_F, IN.DELTA_F] = lag_f * cf
    B[S.FY_R, IN.DELTA_R] = lag_r * cr
    return Params(fixed, sigma_f, sigma_r, A, B)


def matrices(vehicle: Vehicle, speed_mps: float, *,
             relaxation_length_m: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """State matrix A (4x4) and input matrix B (4x2) at ``speed_mps`` (m/s)."""
    p = params_for(vehicle, speed_mps, relaxation_length_m=relaxation_length_m)
    return p.A.copy(), p.B.copy()


def derivatives(t: float, x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """State derivative ``[dV/dt, dr/dt, dFyf/dt, dFyr/dt] = A x + B u`` (SI)."""
    return p.A @ np.asarray(x, dtype=float) + p.B @ np.asarray(u, dtype=float)
