# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Linear tire: constant cornering and longitudinal stiffness, optionally friction-limited.

.. math::

    F_y = -C_\\alpha \\alpha, \\qquad F_x = C_s \\kappa, \\qquad M_z = 0

in the tire frame (``alpha`` in rad, ``kappa`` the slip ratio, positive under drive), with the
sign conventions of ``docs/architecture.md``. ``C_alpha`` is per tire: half the per-axle value
of the vehicle's ``axle_tires`` subsystem. ``C_s`` is ``tire.longitudinal_stiffness_n``; when it
is 0 (the default) it is taken as 1.5 times the per-tire ``C_alpha`` — for passenger-car radial
tires the longitudinal slip stiffness per unit slip ratio is typically 1-2 times the cornering
stiffness per rad (Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., 2012, ch. 1 and App. 3:
C_Fkappa ~ 1.3-1.6 C_Falpha at nominal load), so 1.5 is a middle value.

With saturation on (the default), the force vector is scaled back onto the friction circle
``|F| <= mu * Fz`` when it leaves it; direction is kept. No aligning moment: the linear tire has
no pneumatic-trail model. ``fz <= 0`` (wheel off the ground) gives zero force.

Coefficient array (:func:`pack`), index names in :class:`COEF`:

``C_ALPHA_N_PER_RAD``  cornering stiffness of one tire, N/rad
``C_S_N``              longitudinal slip stiffness of one tire, N per unit slip ratio
``SATURATE``           1.0: limit to the friction circle ``mu * Fz``; 0.0: purely linear
"""

from __future__ import annotations

import math
from enum import IntEnum

import numpy as np

from fourws_sim.errors import ParameterError

#: Longitudinal stiffness per cornering stiffness used when ``tire.longitudinal_stiffness_n``
#: is 0 (see the module docstring for the reason).
DEFAULT_CS_PER_CALPHA = 1.5


class COEF(IntEnum):
    """Slots of the linear tire's coefficient array."""

    C_ALPHA_N_PER_RAD = 0
    C_S_N = 1
    SATURATE = 2


N_COEFFS = len(COEF)
# plain int slots: numba freezes module-level ints as compile-time constants
_I_CA = int(COEF.C_ALPHA_N_PER_RAD)
_I_CS = int(COEF.C_S_N)
_I_SAT = int(COEF.SATURATE)


def forces(fz_n: float, alpha_rad: float, kappa: float, vx_mps: float, mu: float,
           coeffs: np.ndarray) -> tuple[float, float, float]:
    """Tire-frame forces of the linear tire.

    Parameters
    ----------
    fz_n : float
        Normal load in N (compression positive); ``<= 0`` gives zero force.
    alpha_rad : float
        Slip angle in rad.
    kappa : float
        Longitudinal slip ratio (positive under drive, -1 locked).
    vx_mps : float
        Wheel-centre forward speed in m/s (unused: the linear tire has no speed dependence).
    mu : float
        Friction coefficient; the force magnitude is limited to ``mu * fz_n`` when
        ``coeffs[COEF.SATURATE]`` is 1.
    coeffs : numpy.ndarray
        Array from :func:`pack`.

    Returns
    -------
    fx_n, fy_n, mz_nm : float
        Longitudinal force (N), lateral force (N), aligning moment (N m, always 0).
    """
    if not fz_n > 0.0:
        return 0.0, 0.0, 0.0
    fx = coeffs[_I_CS] * kappa
    fy = -coeffs[_I_CA] * alpha_rad
    if coeffs[_I_SAT] > 0.5:
        limit = mu * fz_n
        if limit < 0.0:
            limit = 0.0
        mag = math.sqrt(fx * fx + fy * fy)
        if mag > limit:
            scale = limit / mag
            fx *= scale
            fy *= scale
    return fx, fy, 0.0


def pack(vehicle: object, axle: str, saturate: bool = True) -> np.ndarray:
    """Coefficient array of one tire on ``axle`` ("front" or "rear").

    Parameters
    ----------
    vehicle : fourws_sim.params.Vehicle
        Uses ``axle_tires`` (per-axle cornering stiffness, halved per tire) and, if present,
        ``tire.longitudinal_stiffness_n``.
    axle : str
        ``"front"`` or ``"rear"``.
    saturate : bool
        Limit the force to the friction circle (default True).

    Returns
    -------
    numpy.ndarray
        float64 array of length :data:`N_COEFFS`, slots named by :class:`COEF`.

    Raises
    ------
    ParameterError
        If ``axle`` is not "front" or "rear".
    """
    axle_tires = vehicle.axle_tires  # type: ignore[attr-defined]
    if axle == "front":
        c_axle = axle_tires.cornering_stiffness_front_n_per_rad
    elif axle == "rear":
        c_axle = axle_tires.cornering_stiffness_rear_n_per_rad
    else:
        raise ParameterError("axle", f"must be 'front' or 'rear', got {axle!r}",
                             getattr(vehicle, "source", None))
    c_alpha = 0.5 * float(c_axle)
    tire = getattr(vehicle, "tire", None)
    c_s = float(tire.longitudinal_stiffness_n) if tire is not None else 0.0
    if c_s == 0.0:
        c_s = DEFAULT_CS_PER_CALPHA * c_alpha
    out = np.zeros(N_COEFFS, dtype=np.float64)
    out[COEF.C_ALPHA_N_PER_RAD] = c_alpha
    out[COEF.C_S_N] = c_s
    out[COEF.SATURATE] = 1.0 if saturate else 0.0
    return out


def cornering_stiffness_analytic(coeffs: np.ndarray, fz_n: float) -> float:
    """Cornering stiffness ``-dFy/dalpha`` at zero slip in N/rad (load independent)."""
    return float(coeffs[COEF.C_ALPHA_N_PER_RAD]) if fz_n > 0.0 else 0.0
