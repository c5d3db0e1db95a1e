# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""STI (Systems Technology Inc.) / Calspan composite-slip tire of Appendix C (Table C.1).

The paper's Appendix C gives the model of Allen, Rosenthal, Chrstos et al. (the tire of the
NHTSA VDANL simulation); its OCR is too damaged to read the formulas, so this module rebuilds
them from the published description of the model and from the legible fragments of (C.1),
(C.5), (C.11) and (C.12) of the paper:

* R. W. Allen, T. J. Rosenthal, H. T. Szostak, "Steady state and transient analysis of ground
  vehicle handling", SAE 870495 (1987), and R. W. Allen, J. P. Chrstos, T. J. Rosenthal et al.,
  "A tire model for use with vehicle dynamics simulations on pavement and off-road surfaces",
  Vehicle System Dynamics 27 (1997): tire parameters from load and pressure, composite slip,
  saturation function, slip-to-slide transition, normalized forces;
* H. Dugoff, P. S. Fancher, L. Segel, SAE 700377 (1970): the composite-slip idea the model
  generalizes (force magnitude from one saturating function of the combined slip, direction
  from the ratio of the two slip-stiffness terms);
* the same equations as written in a public implementation of the STI model
  (github.com/tungminhphan/traffic-intersection, ``traffic_intersection/components/car.py``),
  used only to confirm the reading of the equations.

Model (original units: load lb, length ft/in, pressure psi, angle rad; ``S`` is the braking slip
ratio, ``S = -kappa``, 0 free rolling, 1 locked)::

    a_p0  = 0.0768 sqrt(Fz FZT) / (TW (TP + 5))            contact length at Fx = 0, ft  (C.1)
    a_p   = a_p0 (1 - KA |Fx| / Fz)                        contact length under Fx
    C_a   = A0 + A1 Fz - (A1/A2) Fz^2                      cornering stiffness, lb/rad  (C.2)
    C_s   = CS/FZ * Fz                                     longitudinal stiffness, lb   (C.3)
    (K_s = 2 C_a / a_p0^2,  K_c = 2 C_s / a_p0^2 are the paper's stiffness coefficients)
    mu_0  = mu_road (B1 Fz + B3 + B4 Fz^2)                 peak friction                (C.6)
    sigma = pi a_p^2 / (8 mu_0 Fz) sqrt(K_s^2 tan^2 a + K_c^2 S^2)         composite slip
    f     = (C1 sigma^3 + C2 sigma^2 + (4/pi) sigma) / (C1 sigma^3 + C3 sigma^2 + C4 sigma + 1)
    q     = sqrt(sin^2 a + S^2 cos^2 a)                    sliding speed / wheel speed
    K_c'  = K_c + (K_s - K_c) q                            slip-to-slide transition   (C.11)
    mu    = mu_0 (1 - KMU q)                               friction at sliding         (C.12)
    Fy/(mu Fz) = f K_s tan a  / sqrt(K_s^2 tan^2 a + K_c'^2 S^2)
    Fx_b/(mu Fz) = f K_c' S   / sqrt(K_s^2 tan^2 a + K_c'^2 S^2)
    Mz    = -t Fy + K_m Fx Fy / Fz,   t = G1 (a_p/4) (1 - f)^G2,   K_m = K1 Fz          (C.5)

For small slip ``f = (4/pi) sigma`` so ``Fy = C_a tan(alpha)``: ``C_a`` is exactly the tire's
cornering stiffness (:func:`cornering_stiffness_analytic`), and the force magnitude never
exceeds ``mu Fz`` because ``f`` rises monotonically to 1 for the Table C.1 ``C1..C4``.

Choices where the paper is silent or unreadable (an expert's choice, reason given):

* ``a_p0`` is in ft: at the design load it is 0.338 ft = 4.05 in, the contact length of a
  1000-lb load on a 6.5-in tread at 30 psi (load/pressure/width = 5.1 in). Only the ratio
  ``a_p / a_p0`` enters the forces; the absolute length sets the pneumatic trail.
* ``Fx`` in ``a_p`` was the previous time step's force in the paper (step 0.005 s). A pure
  function has no memory, so ``forces`` evaluates the model twice: once at ``a_p = a_p0``, then
  with the ``Fx`` of that pass (one fixed-point step; ``KA = 0.05`` changes ``a_p`` by < 5 %).
* ``KMU`` (C.12) has no row in Table C.1. fourws uses 0.124, the value the public
  implementation above uses with this model for a passenger-car tire; it puts the
  locked-wheel friction 12.4 % below the peak (dry asphalt: 0.8-0.9 of peak) and gives
  Figure C.1 its shape (peak 0.81 at 13 deg, the figure's y axis reaches 0.8).
* ``B1, B3, B4``: (C.6) is a sum of three terms of which only the constant ``B3 = 0.85``
  survives with Table C.1 (``B1 = B4 = 0``), so their order does not change any result.
* ``SNT`` (test skid number, 85) enters as ``mu_road = SN / SNT``: the ``mu`` argument of
  :func:`forces` *is* that ratio (1.0 = the test surface), so SNT is kept for the record only
  (consistently, ``SNT/100 = 0.85 = B3``, the nominal friction).
* Table C.1's OCR writes ``Ai, Bi, Ci, Gi, ki`` where the list of symbols has subscript 1
  (``A1, B1, C1, G1``); "ki" is therefore ``K1`` and "CS/F3" is ``CS/FZ``.
* ``K1 = -0.0002`` ("aligning torque coefficient", OCR "ki"): read as ft/lb in
  ``K_m = K1 Fz`` of (C.5), the moment of the longitudinal force about the laterally deflected
  contact patch, ``Mz = K1 Fx Fy`` (``-1/K1`` = 5000 lb/ft lateral carcass stiffness, the
  right order for a passenger tire; with ``Fx`` drive-positive the sign is the physical one).
* The trail ``t = (a_p/4)(1 - f)`` (OCR of (C.13)/(C.14) shows ``(1.0 - f(sigma))`` and
  ``1/4``): 26 mm at the design load, typical for a passenger tire; ``G1`` scales it and ``G2``
  is the exponent of its decay, both 1.0 in Table C.1.
* ``A3, A4`` (camber thrust stiffness) are kept for the record; camber is zero in all the
  paper's simulations ("Tire camber angle is assumed zero") and ``forces`` has no camber input.
* Cornering stiffness is held at its maximum beyond the vertex of the parabola
  ``Fz = A2/2`` (1450 lb, 6.45 kN) instead of falling to zero at 2937 lb.
* Drive slip (``kappa > 0``) uses the same equations with ``S = -kappa`` (the original is
  written for braking, ``0 <= S <= 1``): the tire is symmetric in drive and brake, so ``a_p``
  shortens with ``|Fx|`` either way, and ``q`` is capped at 1 (full sliding) so that wheel
  spin (``|kappa| > 1``) never drives the friction negative.
* ``vx_mps`` is not used: with ``SN = SNT`` fixed the model has no speed term.

YAML (``tire.sti`` mapping, every key optional, default = Table C.1 in :data:`TABLE_C1`)::

    tw_in   tread width TW, in               tp_psi  inflation pressure TP, psi
    fzt_lb  design load FZT, lb              a0, a1, a2   lateral stiffness coefficients
    a3, a4  camber coefficients (unused)     ka      contact-length change with Fx
    k1      aligning-torque coefficient, ft/lb
    b1, b3, b4  peak friction vs load (B1 per lb, B4 per lb^2)
    cs_per_fz   longitudinal stiffness per load CS/FZ
    snt     test skid number (record only)   c1, c2, c3, c4   saturation function
    g1, g2  trail shaping                    kmu     friction drop at full sliding
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import Mapping

import numpy as np
from numba.extending import register_jitable

from fourws_sim.errors import ParameterError
from fourws_sim.lanes import LANES
from fourws_sim.trig import sincos

#: Newtons per pound-force.
N_PER_LBF = 4.4482216152605
#: Metres per foot.
M_PER_FT = 0.3048
#: Small-sigma slope of the saturation function: makes ``Fy -> C_a tan(alpha)``.
_F_SLOPE = 4.0 / math.pi
#: Constant of the contact-length formula (C.1), ft for in, psi, lb.
_AP_CONSTANT = 0.0768
#: Pressure offset of the contact-length formula (C.1), psi.
_AP_PRESSURE_OFFSET_PSI = 5.0
#: Pneumatic trail at zero slip per contact length (see module docstring).
_TRAIL_PER_LENGTH = 0.25


class COEF(IntEnum):
    """Slots of the STI coefficient array (original units)."""

    TW_IN = 0
    TP_PSI = 1
    FZT_LB = 2
    A0 = 3
    A1 = 4
    A2 = 5
    A3 = 6
    A4 = 7
    KA = 8
    K1 = 9
    B1 = 10
    B3 = 11
    B4 = 12
    CS_PER_FZ = 13
    SNT = 14
    C1 = 15
    C2 = 16
    C3 = 17
    C4 = 18
    G1 = 19
    G2 = 20
    KMU = 21


N_COEFFS = len(COEF)

#: Table C.1 of the paper (tire of Xia's vehicle), plus KMU (not in the table, see docstring).
TABLE_C1: dict[str, float] = {
    "tw_in": 6.5,
    "tp_psi": 30.0,
    "fzt_lb": 1000.0,
    "a0": 733.0,
    "a1": 19.5,
    "a2": 2900.0,
    "a3": 1.37,
    "a4": 4420.0,
    "ka": 0.05,
    "k1": -0.0002,
    "b1": 0.0,
    "b3": 0.85,
    "b4": 0.0,
    "cs_per_fz": 6.0,
    "snt": 85.0,
    "c1": 0.535,
    "c2": 1.05,
    "c3": 1.15,
    "c4": 0.8,
    "g1": 1.0,
    "g2": 1.0,
    "kmu": 0.124,
}

# key -> (slot, check, message)
_POSITIVE = ("tw_in", "fzt_lb", "a2", "a4", "c1", "snt")
_NONNEG = ("a0", "a1", "cs_per_fz", "c2", "c3", "c4", "g1", "g2")

# plain int slots so that numba freezes them as constants
_TW, _TP, _FZT = int(COEF.TW_IN), int(COEF.TP_PSI), int(COEF.FZT_LB)
_A0, _A1, _A2 = int(COEF.A0), int(COEF.A1), int(COEF.A2)
_KA, _K1 = int(COEF.KA), int(COEF.K1)
_B1, _B3, _B4 = int(COEF.B1), int(COEF.B3), int(COEF.B4)
_CSFZ = int(COEF.CS_PER_FZ)
_C1, _C2, _C3, _C4 = int(COEF.C1), int(COEF.C2), int(COEF.C3), int(COEF.C4)
_G1, _G2, _KMU = int(COEF.G1), int(COEF.G2), int(COEF.KMU)


#: Pounds-force per newton.
_LBF_PER_N = 1.0 / N_PER_LBF
#: ``_prepare``'s result for a tire that gives no force (no load, no friction, no slip);
#: fz = den = 1 keep the passes free of 0/0.
_NO_FORCE = (False, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)


# The model is split into three phases (numba-compilable helpers, also plain Python) so that
# the 8-DOF kernels can interleave the four wheels phase by phase (``forces4``); ``forces`` runs
# them for one wheel. error_model="numpy": IEEE division (inf/nan, no ZeroDivisionError checks),
# as the kernels compile ``forces``.
@register_jitable(error_model="numpy")
def _prepare(fz_n: float, alpha_rad: float, kappa: float, mu: float,
             coeffs: np.ndarray) -> tuple[bool, float, float, float, float, float, float,
                                          float]:
    """Load and slip terms: (valid, Fz lb, a_p0 ft, ux, uy, kq, h, den), where
    ``(Fx_b, Fy) = Fz f (ux, uy)`` and the contact-length ratio under that force is
    ``1 - kq f``."""
    if not (fz_n > 0.0 and mu > 0.0):
        return _NO_FORCE
    fz = fz_n * _LBF_PER_N
    ap0 = (_AP_CONSTANT * math.sqrt(fz * coeffs[_FZT])
           / (coeffs[_TW] * (coeffs[_TP] + _AP_PRESSURE_OFFSET_PSI)))
    a1 = coeffs[_A1]
    a2 = coeffs[_A2]
    fz_c = fz if fz < 0.5 * a2 else 0.5 * a2
    c_a = coeffs[_A0] + a1 * fz_c - a1 / a2 * fz_c * fz_c  # lb/rad (C.2)
    if c_a < 0.0:
        c_a = 0.0
    c_s = coeffs[_CSFZ] * fz  # lb per unit slip (C.3)
    mu0 = mu * (coeffs[_B1] * fz + coeffs[_B3] + coeffs[_B4] * fz * fz)
    if not mu0 > 0.0:
        return _NO_FORCE

    sa, ca = sincos(alpha_rad)
    ca = abs(ca)
    s = -kappa  # braking slip of the original model
    q = math.sqrt(sa * sa + s * s * ca * ca)
    if q > 1.0:
        q = 1.0
    c_s_slide = c_s + (c_a - c_s) * q  # K_c' (C.11), in stiffness units
    mu_slide = mu0 * (1.0 - coeffs[_KMU] * q)
    if mu_slide < 0.0:
        mu_slide = 0.0

    # direction of the force (both terms multiplied by cos(alpha) to avoid tan(90 deg))
    gy = c_a * sa
    gx = c_s_slide * s * ca
    g = math.sqrt(gy * gy + gx * gx)
    if not g > 0.0:
        return _NO_FORCE
    # composite slip sigma = h (a_p/a_p0)^2 / den, den = 0 means sigma = infinity
    hx = c_s * s * ca
    h = 0.25 * math.pi * math.sqrt(gy * gy + hx * hx)
    den = mu0 * fz * ca
    # force per Fz f: mu_slide (gx, gy)/g; g >= 2e-162 here (g^2 > 0), so the quotient is finite
    ig = mu_slide / g
    ux = ig * gx
    uy = ig * gy
    # a_p/a_p0 = 1 - KA |Fx_b|/Fz = 1 - KA |ux| f
    return True, fz, ap0, ux, uy, coeffs[_KA] * abs(ux), h, den


@register_jitable(error_model="numpy", inline="always")
def _saturation(sg: float, c1: float, c2: float, c3: float, c4: float) -> float:
    """The saturation function f of the composite slip ``sg`` (for ``sg <= 1``)."""
    sg2 = sg * sg
    return ((c1 * sg2 * sg + c2 * sg2 + _F_SLOPE * sg)
            / (c1 * sg2 * sg + c3 * sg2 + c4 * sg + 1.0))


@register_jitable(error_model="numpy", inline="always")
def _saturation_beyond(u: float, c1: float, c2: float, c3: float, c4: float) -> float:
    """f written in ``u = 1/sigma`` (for ``sigma > 1``): the sigma -> infinity limit stays
    finite."""
    u2 = u * u
    return (c1 + c2 * u + _F_SLOPE * u2) / (c1 + c3 * u + c4 * u2 + u2 * u)


@register_jitable(error_model="numpy")
def _pass(p: tuple[bool, float, float, float, float, float, float, float], ratio: float,
          coeffs: np.ndarray) -> tuple[float, float]:
    """One evaluation at contact-length ratio ``a_p/a_p0 = ratio``: (f, the ratio that the
    resulting Fx gives)."""
    h = p[6]
    den = p[7]
    c1 = coeffs[_C1]
    c2 = coeffs[_C2]
    c3 = coeffs[_C3]
    c4 = coeffs[_C4]
    num = h * ratio * ratio
    if not num > 0.0:
        f = 0.0
    elif num <= den:
        f = _saturation(num / den, c1, c2, c3, c4)
    else:
        f = _saturation_beyond(den / num, c1, c2, c3, c4)
    new_ratio = 1.0 - p[5] * f
    if new_ratio < 0.0:
        new_ratio = 0.0
    return f, new_ratio


@register_jitable(error_model="numpy")
def _finish(p: tuple[bool, float, float, float, float, float, float, float], f: float,
            ratio: float, coeffs: np.ndarray) -> tuple[float, float, float]:
    """Forces and moment in fourws' frame and units from the last pass."""
    if not p[0]:
        return 0.0, 0.0, 0.0
    fzf = p[1] * f
    # original model: Fy positive for positive alpha, Fx_b positive braking; fourws frame:
    fx_lb = -fzf * p[3]
    fy_lb = -fzf * p[4]
    decay = 1.0 - f
    if decay < 0.0:
        decay = 0.0
    g2 = coeffs[_G2]
    shape = decay if g2 == 1.0 else decay ** g2  # pow only when G2 is not Table C.1's 1.0
    trail_ft = coeffs[_G1] * _TRAIL_PER_LENGTH * p[2] * ratio * shape
    mz_ftlb = -trail_ft * fy_lb + coeffs[_K1] * fx_lb * fy_lb
    return fx_lb * N_PER_LBF, fy_lb * N_PER_LBF, mz_ftlb * N_PER_LBF * M_PER_FT


@register_jitable(error_model="numpy", inline="always")
def _lane_pass(h: float, den: float, ratio: float, kq: float, c1: float, c2: float,
               c3: float, c4: float) -> tuple[float, float]:
    """:func:`_pass` without branches (both forms of the saturation function computed, one
    taken by the same tests): the same numbers where :func:`_pass` is defined."""
    num = h * ratio * ratio
    f_low = _saturation(num / den, c1, c2, c3, c4)
    f_high = _saturation_beyond(den / num, c1, c2, c3, c4)
    f = 0.0 if not num > 0.0 else (f_low if num <= den else f_high)
    new_ratio = 1.0 - kq * f
    new_ratio = 0.0 if new_ratio < 0.0 else new_ratio
    return f, new_ratio


@register_jitable(error_model="numpy", inline="always")
def forces_lane(fz_n: float, alpha_rad: float, kappa: float, mu: float, c: np.ndarray,
                base: int, lane: int) -> tuple[float, float, float]:
    """:func:`forces` of one lane of the study's batch kernel, without branches, so that a
    loop over lanes compiles to vector instructions (compiled code only: it divides by zero
    where :func:`forces` takes another branch, which IEEE arithmetic allows and plain Python
    does not); coefficient ``k`` of the lane is ``c[(base + k) * LANES + lane]``
    (:mod:`fourws_sim.lanes`; :func:`pack` as a column). Gives :func:`forces`'s numbers bit
    for bit (``test_eightdof_regression.py``) for ``G2 = 1`` (Table C.1; the batch kernel
    takes no other: ``G2 != 1`` needs a power function, which does not vectorize).

    Every phase is computed for every lane, with the tests of :func:`_prepare`,
    :func:`_pass` and :func:`_finish` choosing among the results; a tire that gives no
    force (no load, no friction, no slip) is zero at the end, as ``_NO_FORCE`` makes it."""
    at = base * LANES + lane  # coefficient k of the lane: c[at + k * LANES]
    k_a0 = c[at + _A0 * LANES]
    k_a1 = c[at + _A1 * LANES]
    k_a2 = c[at + _A2 * LANES]
    k_b1 = c[at + _B1 * LANES]
    k_b3 = c[at + _B3 * LANES]
    k_b4 = c[at + _B4 * LANES]
    k_c1 = c[at + _C1 * LANES]
    k_c2 = c[at + _C2 * LANES]
    k_c3 = c[at + _C3 * LANES]
    k_c4 = c[at + _C4 * LANES]
    k_csfz = c[at + _CSFZ * LANES]
    k_fzt = c[at + _FZT * LANES]
    k_g1 = c[at + _G1 * LANES]
    k_k1 = c[at + _K1 * LANES]
    k_ka = c[at + _KA * LANES]
    k_kmu = c[at + _KMU * LANES]
    k_tp = c[at + _TP * LANES]
    k_tw = c[at + _TW * LANES]
    fz = fz_n * _LBF_PER_N
    ap0 = (_AP_CONSTANT * math.sqrt(fz * k_fzt)
           / (k_tw * (k_tp + _AP_PRESSURE_OFFSET_PSI)))
    a1 = k_a1
    a2 = k_a2
    fz_c = fz if fz < 0.5 * a2 else 0.5 * a2
    c_a = k_a0 + a1 * fz_c - a1 / a2 * fz_c * fz_c
    c_a = 0.0 if c_a < 0.0 else c_a
    c_s = k_csfz * fz
    mu0 = mu * (k_b1 * fz + k_b3 + k_b4 * fz * fz)
    sa, ca = sincos(alpha_rad)
    ca = abs(ca)
    s = -kappa
    q = math.sqrt(sa * sa + s * s * ca * ca)
    q = 1.0 if q > 1.0 else q
    c_s_slide = c_s + (c_a - c_s) * q
    mu_slide = mu0 * (1.0 - k_kmu * q)
    mu_slide = 0.0 if mu_slide < 0.0 else mu_slide
    gy = c_a * sa
    gx = c_s_slide * s * ca
    g = math.sqrt(gy * gy + gx * gx)
    valid = fz_n > 0.0 and mu > 0.0 and mu0 > 0.0 and g > 0.0
    hx = c_s * s * ca
    h = 0.25 * math.pi * math.sqrt(gy * gy + hx * hx)
    den = mu0 * fz * ca
    ig = mu_slide / g
    ux = ig * gx
    uy = ig * gy
    kq = k_ka * abs(ux)
    c1 = k_c1
    c2 = k_c2
    c3 = k_c3
    c4 = k_c4
    # forces(): pass 0 at a_p = a_p0, pass 1 with its Fx unless the ratio stayed 1
    f0, ratio1 = _lane_pass(h, den, 1.0, kq, c1, c2, c3, c4)
    f1, ratio2 = _lane_pass(h, den, ratio1, kq, c1, c2, c3, c4)
    again = ratio1 != 1.0
    f = f1 if again else f0
    ratio = ratio2 if again else 1.0
    # _finish() with G2 = 1
    fzf = fz * f
    fx_lb = -fzf * ux
    fy_lb = -fzf * uy
    decay = 1.0 - f
    decay = 0.0 if decay < 0.0 else decay
    trail_ft = k_g1 * _TRAIL_PER_LENGTH * ap0 * ratio * decay
    mz_ftlb = -trail_ft * fy_lb + k_k1 * fx_lb * fy_lb
    fx = fx_lb * N_PER_LBF if valid else 0.0
    fy = fy_lb * N_PER_LBF if valid else 0.0
    mz = mz_ftlb * N_PER_LBF * M_PER_FT if valid else 0.0
    return fx, fy, mz


#: Which coefficient must hold for :func:`forces_lane` (and its value): ``G2 = 1``.
LANE_CONDITION = (int(COEF.G2), 1.0)


def forces(fz_n: float, alpha_rad: float, kappa: float, vx_mps: float, mu: float,
           coeffs: np.ndarray) -> tuple[float, float, float]:
    """Tire-frame forces of the STI composite-slip tire.

    Parameters
    ----------
    fz_n : float
        Normal load in N; ``<= 0`` gives zero force.
    alpha_rad : float
        Slip angle in rad, ``|alpha| <= pi/2`` (``Fy = -C_a alpha`` for small alpha).
    kappa : float
        Slip ratio, positive under drive, -1 locked.
    vx_mps : float
        Wheel forward speed in m/s (not used, see module docstring).
    mu : float
        Road friction relative to the test surface (``SN/SNT``; 1.0 = Table C.1 surface);
        scales the peak and sliding friction.
    coeffs : numpy.ndarray
        Array from :func:`pack`.

    Returns
    -------
    fx_n, fy_n, mz_nm : float
        Longitudinal force (N, positive forward), lateral force (N, positive left),
        aligning moment (N m, positive counter-clockwise seen from above).
    """
    p = _prepare(fz_n, alpha_rad, kappa, mu, coeffs)
    # pass 0 at a_p = a_p0 (Fx = 0); pass 1 with the Fx of pass 0 unless it has none (or
    # KA = 0); the trail takes the ratio that pass 1's Fx gives
    f, ratio1 = _pass(p, 1.0, coeffs)
    ratio = 1.0
    if ratio1 != ratio:
        f, ratio = _pass(p, ratio1, coeffs)
    return _finish(p, f, ratio, coeffs)


def forces4(fz_n: np.ndarray, alpha_rad: np.ndarray, kappa: np.ndarray, vx_mps: np.ndarray,
            mu: float, coeffs_front: np.ndarray, coeffs_rear: np.ndarray, fx_n: np.ndarray,
            fy_n: np.ndarray, mz_nm: np.ndarray) -> None:
    """:func:`forces` of the four wheels (FL, FR, RL, RR; front coefficients for the first
    two) into ``fx_n, fy_n, mz_nm``, phase by phase.

    Gives exactly the numbers of four :func:`forces` calls; the four evaluations of each phase
    are independent, so compiled code overlaps their latency (the 8-DOF kernels use this).
    """
    cf = coeffs_front
    cr = coeffs_rear
    p0 = _prepare(fz_n[0], alpha_rad[0], kappa[0], mu, cf)
    p1 = _prepare(fz_n[1], alpha_rad[1], kappa[1], mu, cf)
    p2 = _prepare(fz_n[2], alpha_rad[2], kappa[2], mu, cr)
    p3 = _prepare(fz_n[3], alpha_rad[3], kappa[3], mu, cr)
    f0, s0 = _pass(p0, 1.0, cf)
    f1, s1 = _pass(p1, 1.0, cf)
    f2, s2 = _pass(p2, 1.0, cr)
    f3, s3 = _pass(p3, 1.0, cr)
    r0 = 1.0
    r1 = 1.0
    r2 = 1.0
    r3 = 1.0
    if s0 != r0:
        f0, r0 = _pass(p0, s0, cf)
    if s1 != r1:
        f1, r1 = _pass(p1, s1, cf)
    if s2 != r2:
        f2, r2 = _pass(p2, s2, cr)
    if s3 != r3:
        f3, r3 = _pass(p3, s3, cr)
    fx_n[0], fy_n[0], mz_nm[0] = _finish(p0, f0, r0, cf)
    fx_n[1], fy_n[1], mz_nm[1] = _finish(p1, f1, r1, cf)
    fx_n[2], fy_n[2], mz_nm[2] = _finish(p2, f2, r2, cr)
    fx_n[3], fy_n[3], mz_nm[3] = _finish(p3, f3, r3, cr)


def cornering_stiffness_analytic(coeffs: np.ndarray, fz_n: float) -> float:
    """Analytic small-slip cornering stiffness of one tire in N/rad.

    ``C_a = A0 + A1 Fz - (A1/A2) Fz^2`` (Fz in lb, C_a in lb/rad), held at its maximum for
    ``Fz > A2/2``.
    """
    if not fz_n > 0.0:
        return 0.0
    fz = min(fz_n / N_PER_LBF, 0.5 * coeffs[_A2])
    c_a = coeffs[_A0] + coeffs[_A1] * fz - coeffs[_A1] / coeffs[_A2] * fz * fz
    return max(c_a, 0.0) * N_PER_LBF


def peak_friction(coeffs: np.ndarray, fz_n: float, mu: float = 1.0) -> float:
    """Peak friction ``mu_0 = mu (B1 Fz + B3 + B4 Fz^2)`` (Fz in lb), dimensionless."""
    fz = fz_n / N_PER_LBF
    return mu * (coeffs[_B1] * fz + coeffs[_B3] + coeffs[_B4] * fz * fz)


def pack_mapping(values: Mapping[str, float], source: str | None = None,
                 prefix: str = "tire.sti.") -> np.ndarray:
    """Coefficient array from a mapping of Table C.1 keys (missing keys take the defaults).

    Raises
    ------
    ParameterError
        On an unknown key or an out-of-range value (named ``tire.sti.<key>``).
    """
    merged = dict(TABLE_C1)
    for key, value in values.items():
        if key not in TABLE_C1:
            raise ParameterError(f"{prefix}{key}",
                                 f"unknown STI coefficient (valid: {', '.join(sorted(TABLE_C1))})",
                                 source)
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise ParameterError(f"{prefix}{key}", f"must be a finite number, got {value!r}",
                                 source)
        merged[key] = float(value)
    for key in _POSITIVE:
        if not merged[key] > 0.0:
            raise ParameterError(f"{prefix}{key}", f"must be > 0, got {merged[key]!r}", source)
    for key in _NONNEG:
        if merged[key] < 0.0:
            raise ParameterError(f"{prefix}{key}", f"must be >= 0, got {merged[key]!r}", source)
    if not merged["tp_psi"] + _AP_PRESSURE_OFFSET_PSI > 0.0:
        raise ParameterError(f"{prefix}tp_psi", "must be > -5 psi", source)
    if not 0.0 <= merged["kmu"] < 1.0:
        raise ParameterError(f"{prefix}kmu", f"must be within [0, 1), got {merged['kmu']!r}",
                             source)
    if not 0.0 <= merged["ka"] < 1.0:
        raise ParameterError(f"{prefix}ka", f"must be within [0, 1), got {merged['ka']!r}",
                             source)
    if not merged["b3"] > 0.0:
        raise ParameterError(f"{prefix}b3", f"must be > 0 (peak friction), got {merged['b3']!r}",
                             source)
    out = np.zeros(N_COEFFS, dtype=np.float64)
    for slot in COEF:
        out[slot] = merged[slot.name.lower()]
    return out


def pack(vehicle: object, axle: str) -> np.ndarray:
    """Coefficient array of one tire on ``axle`` from the vehicle's ``tire.sti`` mapping.

    The paper uses one tire (Table C.1) on both axles, so ``axle`` only is checked.

    Raises
    ------
    ParameterError
        On a bad axle name, an unknown key or a bad value (``tire.sti.<key>``, with the file).
    """
    source = getattr(vehicle, "source", None)
    if axle not in ("front", "rear"):
        raise ParameterError("axle", f"must be 'front' or 'rear', got {axle!r}", source)
    tire = getattr(vehicle, "tire", None)
    values = tire.sti if tire is not None else {}
    return pack_mapping(values, source)
