# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Pacejka Magic Formula tire (MF 5.2 steady state, zero camber) with combined slip.

Equations: H. B. Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., Butterworth-Heinemann, 2012,
chapter 4, the full set of Magic Formula (MF-Tyre 5.2) steady-state equations: pure slip,
combined slip with the cosine weighting functions, aligning moment with equivalent slip angles.
Default coefficients: the same book, Appendix 3, Table A3.1, the passenger-car tire
205/60R15 91V at 2.2 bar (nominal load ``FNOMIN = 4000 N``, unloaded radius ``R0 = 0.3135 m``).
Caution: the values were entered from that table without a copy of the book at hand to check
them against, so treat them as a representative passenger-car set (their derived properties,
peak mu_y 0.99 and 46 kN/rad cornering stiffness at FNOMIN, are typical of such a tire), not
as a verified reproduction of the book; they are given there in the book's sign convention in
which the lateral coefficients give ``Fy < 0`` for ``alpha > 0`` (``PDY1 = -0.990``,
``PKY1 = -14.95``): exactly fourws's ``Fy = -C_alpha alpha``, so the values are used as
printed. Only the coefficients the zero-camber equations use are kept (camber terms PDY3,
PEY4, PKY3, PHY3, PVY3/4, QBZ4/5, QDZ3/4/8/9, QEZ5, QHZ3/4 drop out at ``gamma = 0``).

With ``dfz = (Fz - FNOMIN)/FNOMIN`` and ``mu`` the friction scale (``lambda_mu``):

pure longitudinal slip (kappa_x = kappa + S_Hx)::

    mu_x = mu (PDX1 + PDX2 dfz),  D_x = mu_x Fz,  C_x = PCX1
    K_x  = Fz (PKX1 + PKX2 dfz) exp(PKX3 dfz)          (slip stiffness, N per unit slip)
    E_x  = (PEX1 + PEX2 dfz + PEX3 dfz^2)(1 - PEX4 sgn(kappa_x)) <= 1,   B_x = K_x/(C_x D_x)
    Fx0  = D_x sin(C_x atan(B_x k - E_x (B_x k - atan(B_x k)))) + Fz mu (PVX1 + PVX2 dfz)

pure side slip (alpha_y = alpha + PHY1 + PHY2 dfz)::

    mu_y = mu (PDY1 + PDY2 dfz),  D_y = mu_y Fz,  C_y = PCY1
    K_y  = PKY1 FNOMIN sin(2 atan(Fz / (PKY2 FNOMIN)))  (= dFy/dalpha at 0, N/rad)
    E_y  = (PEY1 + PEY2 dfz)(1 - PEY3 sgn(alpha_y)) <= 1,   B_y = K_y/(C_y D_y)
    Fy0  = D_y sin(C_y atan(B_y a - E_y (B_y a - atan(B_y a)))) + Fz mu (PVY1 + PVY2 dfz)

combined slip: ``Fx = G_xa Fx0`` and ``Fy = G_yk Fy0 + S_Vyk`` with the weighting functions
``G = cos(C atan(B s - E (B s - atan(B s)))) / cos(C atan(B S_H - E (B S_H - atan(B S_H))))``
(``B_xa = RBX1 cos(atan(RBX2 kappa))``, ``C_xa = RCX1``, ``E_xa = REX1 + REX2 dfz``,
``S_Hxa = RHX1``; ``B_yk = RBY1 cos(atan(RBY2 (alpha - RBY3)))``, ``C_yk = RCY1``,
``E_yk = REY1 + REY2 dfz``, ``S_Hyk = RHY1 + RHY2 dfz``; ``S_Vyk = mu_y Fz (RVY1 + RVY2 dfz)
cos(atan(RVY4 alpha)) sin(RVY5 atan(RVY6 kappa))``).

aligning moment: ``Mz = -t(alpha_t,eq) (Fy - S_Vyk) + Mzr(alpha_r,eq) + s Fx`` with the
pneumatic trail ``t = D_t cos(C_t atan(B_t a - E_t (B_t a - atan(B_t a)))) cos(alpha)``
(``B_t = QBZ1 + QBZ2 dfz + QBZ3 dfz^2``, ``C_t = QCZ1``, ``D_t = Fz (QDZ1 + QDZ2 dfz) R0/FNOMIN``,
``E_t = (QEZ1 + QEZ2 dfz + QEZ3 dfz^2)(1 + QEZ4 (2/pi) atan(B_t C_t a))``), the residual moment
``Mzr = mu Fz R0 (QDZ6 + QDZ7 dfz) cos(atan((QBZ9 + QBZ10 B_y C_y) a_r)) cos(alpha)``, the
equivalent slip angles ``a_eq = sqrt(a^2 + (K_x/K_y)^2 kappa^2) sgn(a)`` and
``s = R0 (SSZ1 + SSZ2 Fy/FNOMIN)``.

Choices: the slip angle enters as ``alpha`` (rad), not ``tan(alpha)``, so ``|alpha| = 90 deg``
stays finite (identical for the small angles the coefficients were fitted over); the weighting
functions are clipped at 0 so that wheel spin far beyond the fitted range (``|kappa| > 1``)
cannot reverse a force; ``E <= 1`` as the MF requires. ``vx_mps`` is unused (steady state,
no low-speed damping: the vehicle model handles ``vx -> 0`` in its slip definitions).

YAML: ``tire.magic_formula`` is a mapping of the upper-case names of :data:`PACEJKA_205_60R15`
(any subset; missing keys take :data:`DEFAULTS`, which is Table A3.1 with the shift and
asymmetry coefficients :data:`SHIFT_KEYS` set to zero, see there why).
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import Mapping

import numpy as np
from numba.extending import register_jitable

from fourws_sim.errors import ParameterError

#: Pacejka (2012), Appendix 3, Table A3.1: 205/60R15 91V, 2.2 bar (zero-camber subset).
PACEJKA_205_60R15: dict[str, float] = {
    "FNOMIN": 4000.0, "R0": 0.3135,
    # longitudinal, pure slip
    "PCX1": 1.685, "PDX1": 1.210, "PDX2": -0.037,
    "PEX1": 0.344, "PEX2": 0.095, "PEX3": -0.020, "PEX4": 0.0,
    "PKX1": 21.51, "PKX2": -0.163, "PKX3": 0.245,
    "PHX1": -0.002, "PHX2": 0.002, "PVX1": 0.0, "PVX2": 0.0,
    # lateral, pure slip
    "PCY1": 1.193, "PDY1": -0.990, "PDY2": 0.145,
    "PEY1": -1.003, "PEY2": -0.537, "PEY3": -0.083,
    "PKY1": -14.95, "PKY2": 2.130,
    "PHY1": 0.003, "PHY2": -0.001, "PVY1": 0.045, "PVY2": -0.024,
    # combined slip
    "RBX1": 12.35, "RBX2": -10.77, "RCX1": 1.092, "REX1": 0.0, "REX2": 0.0, "RHX1": 0.007,
    "RBY1": 6.461, "RBY2": 4.196, "RBY3": -0.015, "RCY1": 1.081, "REY1": 0.0, "REY2": 0.0,
    "RHY1": 0.009, "RHY2": 0.0,
    "RVY1": 0.053, "RVY2": -0.073, "RVY4": 35.44, "RVY5": 1.9, "RVY6": -10.71,
    # aligning moment
    "QBZ1": 8.964, "QBZ2": -1.106, "QBZ3": -0.842, "QBZ9": 18.47, "QBZ10": 0.0,
    "QCZ1": 1.180, "QDZ1": 0.100, "QDZ2": -0.001, "QDZ6": -0.008, "QDZ7": 0.0,
    "QEZ1": -1.609, "QEZ2": -0.359, "QEZ3": 0.0, "QEZ4": 0.174,
    "QHZ1": 0.007, "QHZ2": -0.002, "SSZ1": 0.043, "SSZ2": 0.001,
}

#: Coefficients that are shifts or left/right asymmetries (ply-steer, conicity, the Mz offset
#: of SSZ1, the residual torque QDZ6/7, the sign-dependent trail curvature QEZ4):
#: zero in :data:`DEFAULTS`.
SHIFT_KEYS = ("PHX1", "PHX2", "PVX1", "PVX2", "PHY1", "PHY2", "PVY1", "PVY2", "PEY3",
              "RBY3", "RHX1", "RHY1", "RHY2", "RVY1", "RVY2", "QHZ1", "QHZ2", "QDZ6", "QDZ7",
              "QEZ4", "SSZ1")

#: fourws defaults: Table A3.1 with the shift/asymmetry coefficients set to zero. The vehicle
#: models mount the same tire on the left and the right without mirroring it, so the published
#: shifts (a lateral force of 4.5 % Fz at zero slip) would make the car drift with no input,
#: and the paper's analyses assume left/right-symmetric tires. Give the published values in
#: ``tire.magic_formula`` to study them.
DEFAULTS: dict[str, float] = {k: (0.0 if k in SHIFT_KEYS else v)
                              for k, v in PACEJKA_205_60R15.items()}

#: Slots of the coefficient array, in the order of :data:`PACEJKA_205_60R15`.
COEF = IntEnum("COEF", [(name, i) for i, name in enumerate(PACEJKA_205_60R15)])
COEF.__doc__ = "Slots of the Magic Formula coefficient array (names as in MF-Tyre .tir files)."
N_COEFFS = len(COEF)

# plain int slots (numba freezes module-level ints); order checked by the tests
(_FNOMIN, _R0, _PCX1, _PDX1, _PDX2, _PEX1, _PEX2, _PEX3, _PEX4, _PKX1, _PKX2, _PKX3, _PHX1,
 _PHX2, _PVX1, _PVX2, _PCY1, _PDY1, _PDY2, _PEY1, _PEY2, _PEY3, _PKY1, _PKY2, _PHY1, _PHY2,
 _PVY1, _PVY2, _RBX1, _RBX2, _RCX1, _REX1, _REX2, _RHX1, _RBY1, _RBY2, _RBY3, _RCY1, _REY1,
 _REY2, _RHY1, _RHY2, _RVY1, _RVY2, _RVY4, _RVY5, _RVY6, _QBZ1, _QBZ2, _QBZ3, _QBZ9, _QBZ10,
 _QCZ1, _QDZ1, _QDZ2, _QDZ6, _QDZ7, _QEZ1, _QEZ2, _QEZ3, _QEZ4, _QHZ1, _QHZ2, _SSZ1,
 _SSZ2) = range(N_COEFFS)

_TWO_OVER_PI = 2.0 / math.pi


@register_jitable(error_model="numpy")
def _curved(x: float, e: float) -> float:
    """The Magic Formula's ``x - E (x - atan(x))``; ``x`` itself when ``E = 0`` (the
    defaults' combined-slip curvatures), without the atan that would be multiplied by 0."""
    if e == 0.0:
        return x
    return x - e * (x - math.atan(x))


@register_jitable(error_model="numpy")
def _cos_atan(x: float) -> float:
    """``cos(atan(x)) = 1/sqrt(1 + x^2)`` without the two transcendental calls (equal to
    round-off; for ``|x| > 1e154`` it gives 0 instead of ~1e-17/|x|)."""
    return 1.0 / math.sqrt(1.0 + x * x)


@register_jitable(error_model="numpy")
def _sin_2atan(y: float) -> float:
    """``sin(2 atan(y)) = 2 y / (1 + y^2)`` (equal to round-off; ``y`` is a load ratio)."""
    return 2.0 * y / (1.0 + y * y)


def forces(fz_n: float, alpha_rad: float, kappa: float, vx_mps: float, mu: float,
           coeffs: np.ndarray) -> tuple[float, float, float]:
    """Tire-frame forces of the Magic Formula tire.

    Parameters
    ----------
    fz_n : float
        Normal load in N; ``<= 0`` gives zero force.
    alpha_rad : float
        Slip angle in rad (``Fy = -C_alpha alpha`` for small alpha).
    kappa : float
        Slip ratio, positive under drive, -1 locked.
    vx_mps : float
        Wheel forward speed in m/s (not used).
    mu : float
        Friction scale ``lambda_mu`` (1.0 = the tire's test surface); scales the peaks.
    coeffs : numpy.ndarray
        Array from :func:`pack`.

    Returns
    -------
    fx_n, fy_n, mz_nm : float
        Longitudinal force (N), lateral force (N), aligning moment (N m).
    """
    if not (fz_n > 0.0 and mu > 0.0):
        return 0.0, 0.0, 0.0
    c = coeffs
    fz0 = c[_FNOMIN]
    r0 = c[_R0]
    dfz = (fz_n - fz0) / fz0
    a = alpha_rad
    k = kappa

    # ---- pure longitudinal slip
    shx = c[_PHX1] + c[_PHX2] * dfz
    kx = k + shx
    cx = c[_PCX1]
    mux = mu * (c[_PDX1] + c[_PDX2] * dfz)
    dx = mux * fz_n
    ex = (c[_PEX1] + c[_PEX2] * dfz + c[_PEX3] * dfz * dfz)
    ex *= 1.0 - c[_PEX4] * (1.0 if kx > 0.0 else (-1.0 if kx < 0.0 else 0.0))
    if ex > 1.0:
        ex = 1.0
    kxk = fz_n * (c[_PKX1] + c[_PKX2] * dfz) * math.exp(c[_PKX3] * dfz)
    svx = fz_n * mu * (c[_PVX1] + c[_PVX2] * dfz)
    fx0 = svx
    if dx != 0.0:
        bx = kxk / (cx * dx)
        bk = bx * kx
        fx0 = dx * math.sin(cx * math.atan(bk - ex * (bk - math.atan(bk)))) + svx

    # ---- pure side slip
    shy = c[_PHY1] + c[_PHY2] * dfz
    ay = a + shy
    cy = c[_PCY1]
    muy = mu * (c[_PDY1] + c[_PDY2] * dfz)
    dy = muy * fz_n
    ey = (c[_PEY1] + c[_PEY2] * dfz)
    ey *= 1.0 - c[_PEY3] * (1.0 if ay > 0.0 else (-1.0 if ay < 0.0 else 0.0))
    if ey > 1.0:
        ey = 1.0
    kya = c[_PKY1] * fz0 * _sin_2atan(fz_n / (c[_PKY2] * fz0))
    svy = fz_n * mu * (c[_PVY1] + c[_PVY2] * dfz)
    by = 0.0
    fy0 = svy
    if dy != 0.0:
        by = kya / (cy * dy)
        ba = by * ay
        fy0 = dy * math.sin(cy * math.atan(ba - ey * (ba - math.atan(ba)))) + svy

    # ---- combined slip weighting
    shxa = c[_RHX1]
    bxa = c[_RBX1] * _cos_atan(c[_RBX2] * k)
    cxa = c[_RCX1]
    exa = c[_REX1] + c[_REX2] * dfz
    if exa > 1.0:
        exa = 1.0
    s1 = bxa * (a + shxa)
    s0 = bxa * shxa
    gxa = math.cos(cxa * math.atan(_curved(s1, exa)))
    if shxa != 0.0:  # with no shift the normalizing cosine is cos(0) = 1
        gxa /= math.cos(cxa * math.atan(_curved(s0, exa)))
    if gxa < 0.0:
        gxa = 0.0
    fx = gxa * fx0

    shyk = c[_RHY1] + c[_RHY2] * dfz
    byk = c[_RBY1] * _cos_atan(c[_RBY2] * (a - c[_RBY3]))
    cyk = c[_RCY1]
    eyk = c[_REY1] + c[_REY2] * dfz
    if eyk > 1.0:
        eyk = 1.0
    s1 = byk * (k + shyk)
    s0 = byk * shyk
    gyk = math.cos(cyk * math.atan(_curved(s1, eyk)))
    if shyk != 0.0:
        gyk /= math.cos(cyk * math.atan(_curved(s0, eyk)))
    if gyk < 0.0:
        gyk = 0.0
    rvy = c[_RVY1] + c[_RVY2] * dfz
    svyk = 0.0
    if rvy != 0.0:
        dvyk = muy * fz_n * rvy * _cos_atan(c[_RVY4] * a)
        svyk = dvyk * math.sin(c[_RVY5] * math.atan(c[_RVY6] * k))
    fy = gyk * fy0 + svyk

    # ---- aligning moment (equivalent slip angles)
    cos_a = math.cos(a)
    sht = c[_QHZ1] + c[_QHZ2] * dfz
    at = a + sht
    shf = shy + (svy / kya if kya != 0.0 else 0.0)
    ar = a + shf
    kratio = kxk / kya if kya != 0.0 else 0.0
    kratio2 = kratio * kratio * k * k
    at_eq = math.sqrt(at * at + kratio2)
    if at < 0.0:
        at_eq = -at_eq
    ar_eq = math.sqrt(ar * ar + kratio2)
    if ar < 0.0:
        ar_eq = -ar_eq
    bt = c[_QBZ1] + c[_QBZ2] * dfz + c[_QBZ3] * dfz * dfz
    ct = c[_QCZ1]
    dt = fz_n * (c[_QDZ1] + c[_QDZ2] * dfz) * r0 / fz0
    et = c[_QEZ1] + c[_QEZ2] * dfz + c[_QEZ3] * dfz * dfz
    if c[_QEZ4] != 0.0:
        et *= 1.0 + c[_QEZ4] * _TWO_OVER_PI * math.atan(bt * ct * at)
    if et > 1.0:
        et = 1.0
    bta = bt * at_eq
    trail = dt * math.cos(ct * math.atan(bta - et * (bta - math.atan(bta)))) * cos_a
    br = c[_QBZ9] + c[_QBZ10] * by * cy
    qdz = c[_QDZ6] + c[_QDZ7] * dfz
    mzr = 0.0
    if qdz != 0.0:
        dr = mu * fz_n * r0 * qdz
        mzr = dr * _cos_atan(br * ar_eq) * cos_a
    arm = r0 * (c[_SSZ1] + c[_SSZ2] * fy / fz0)
    mz = -trail * (fy - svyk) + mzr + arm * fx
    return fx, fy, mz


def peak_lateral_friction(coeffs: np.ndarray, fz_n: float, mu: float = 1.0) -> float:
    """``|mu_y| = |mu (PDY1 + PDY2 dfz)|``: the pure-slip lateral peak is ``|mu_y| Fz + S_Vy``."""
    dfz = (fz_n - coeffs[_FNOMIN]) / coeffs[_FNOMIN]
    return abs(mu * (coeffs[_PDY1] + coeffs[_PDY2] * dfz))


def cornering_stiffness_analytic(coeffs: np.ndarray, fz_n: float) -> float:
    """``-K_y = -PKY1 FNOMIN sin(2 atan(Fz/(PKY2 FNOMIN)))`` in N/rad (positive)."""
    if not fz_n > 0.0:
        return 0.0
    fz0 = coeffs[_FNOMIN]
    return float(-coeffs[_PKY1] * fz0 * math.sin(2.0 * math.atan(fz_n / (coeffs[_PKY2] * fz0))))


def pack_mapping(values: Mapping[str, float], source: str | None = None,
                 prefix: str = "tire.magic_formula.") -> np.ndarray:
    """Coefficient array from a mapping of MF names (missing keys take :data:`DEFAULTS`).

    Raises
    ------
    ParameterError
        On an unknown name or a bad value (named ``tire.magic_formula.<key>``).
    """
    merged = dict(DEFAULTS)
    for key, value in values.items():
        if key not in merged:
            raise ParameterError(f"{prefix}{key}",
                                 "unknown Magic Formula coefficient (valid: "
                                 f"{', '.join(PACEJKA_205_60R15)})", source)
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise ParameterError(f"{prefix}{key}", f"must be a finite number, got {value!r}",
                                 source)
        merged[key] = float(value)
    for key in ("FNOMIN", "R0", "PCX1", "PCY1", "PKY2", "QCZ1"):
        if not merged[key] > 0.0:
            raise ParameterError(f"{prefix}{key}", f"must be > 0, got {merged[key]!r}", source)
    for key in ("PDX1", "PDY1", "PKX1", "PKY1"):
        if merged[key] == 0.0:
            raise ParameterError(f"{prefix}{key}", "must be non-zero", source)
    return np.array([merged[name] for name in PACEJKA_205_60R15], dtype=np.float64)


def pack(vehicle: object, axle: str) -> np.ndarray:
    """Coefficient array of one tire on ``axle`` from the vehicle's ``tire.magic_formula``.

    Raises
    ------
    ParameterError
        On a bad axle name, an unknown key or a bad value (with the file).
    """
    source = getattr(vehicle, "source", None)
    if axle not in ("front", "rear"):
        raise ParameterError("axle", f"must be 'front' or 'rear', got {axle!r}", source)
    tire = getattr(vehicle, "tire", None)
    values = tire.magic_formula if tire is not None else {}
    return pack_mapping(values, source)
