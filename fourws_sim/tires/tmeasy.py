# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""TMeasy tire (steady state, zero camber): the tire of Chrono::Vehicle and LFDM.

Equations re-derived from W. Hirschberg, G. Rill, H. Weinfurter, "Tire model TMeasy",
Vehicle System Dynamics 45, Suppl. 1 (2007) 101-119, and G. Rill, *Road Vehicle Dynamics:
Fundamentals and Modeling*, CRC Press, 2012, ch. 3 (TMeasy), with the transition between the
maximum and sliding as G. Rill and A. Arrieta Castro, *Road Vehicle Dynamics: Fundamentals and
Modeling with MATLAB*, CRC Press, 2020 give it (the form Chrono::Vehicle's ``ChTMeasyTire``
and LFDM's 18/24-DOF models use; both were read to compare, no code was taken).

Slips. TMeasy divides the slip velocity by the rolling speed ``r_D |Omega|``::

    s_x = -(v_x - r_D Omega) / (r_D |Omega|),    s_y = -v_y / (r_D |Omega|)

fourws gives ``kappa = (Omega R - v_x)/V`` and ``tan(alpha) = v_y/V`` over
``V = max(|v_x|, v_min)`` (``docs/architecture.md``), so ``r_D |Omega| = q V`` with
``q = |sgn(v_x) + kappa|`` and ``s_x = kappa/q``, ``s_y = -tan(alpha)/q``. At free rolling
``s_x = kappa`` and ``s_y = -tan(alpha)``; ``q`` is held at :data:`ROLLING_FLOOR` or more, the
role of TMeasy's small numerical speed ``v_N``: a locked wheel (``q = 0``) slides, it is not
a division by zero.

Load dependence (``x = F_z / F_z^N``, ``F_z`` held at ``F_z^max``, ``Y_1, Y_2`` the values at
``F_z^N`` and ``2 F_z^N``)::

    dF0, F_M, F_S:  Y(F_z) = x (2 Y_1 - Y_2/2 - (Y_1 - Y_2/2) x)     (through 0, Y_1, Y_2)
    s_M, s_S, (n/L)_0, s_y^0, s_y^E:  Y(F_z) = Y_1 + (Y_2 - Y_1)(x - 1)

Friction: with ``mu`` the road friction over the tire's measured one (1.0 = the data's
surface), ``F_M, F_S, s_M, s_S`` (and the trail's ``s_y^0, s_y^E``) are multiplied by ``mu``,
so the initial slopes stay (Rill 2012, "different friction coefficients").

Combined slip (normalized slips, generalized slip ``s`` and its direction ``phi``)::

    s_x^hat = s_x^M/(s_x^M + s_y^M) + (F_x^M/dF_x^0) / (F_x^M/dF_x^0 + F_y^M/dF_y^0)
    s_y^hat = s_y^M/(s_x^M + s_y^M) + (F_y^M/dF_y^0) / (F_x^M/dF_x^0 + F_y^M/dF_y^0)
    s = sqrt((s_x/s_x^hat)^2 + (s_y/s_y^hat)^2),  cos phi = s_x/(s_x^hat s), sin phi = ...
    dF0 = sqrt((dF_x^0 s_x^hat cos phi)^2 + (dF_y^0 s_y^hat sin phi)^2)
    F_M = sqrt((F_x^M cos phi)^2 + (F_y^M sin phi)^2)      (F_S alike)
    s_M = sqrt((s_x^M/s_x^hat cos phi)^2 + (s_y^M/s_y^hat sin phi)^2)   (s_S alike)
    F_x = F(s) cos phi,   F_y = F(s) sin phi

so that pure slip gives back each direction's own curve (``F_y(s_y^M) = F_y^M``).

Generalized characteristic ``F(s)`` (``dF0`` raised to ``2 F_M/s_M`` where it is smaller, as
Chrono and LFDM do, so that the rational part stays concave)::

    0 <= s <= s_M:        F = s_M dF0 sigma / (1 + sigma (sigma + dF0 s_M/F_M - 2)),  sigma = s/s_M
    s_M < s <= s*:        F = F_M - a (s - s_M)^2,     a = (F_M/s_M)^2 / (dF0 s_M)
    s* < s <= s_S:        F = F_S + b (s_S - s)^2,     b = a (s* - s_M)/(s_S - s*)
    s > s_S:              F = F_S
    s* = s_M + (F_M - F_S)/(a (s_S - s_M))

``a`` matches the rational function's curvature at ``s_M`` (its second derivative there is
``-2 F_M^2/(dF0 s_M^3)``) and ``s*, b`` join the two parabolas with equal value and slope.
Where ``s* > s_S`` the parabolas cannot meet in time and the cubic of Hirschberg, Rill and
Weinfurter (2007) joins the maximum and sliding: ``F = F_M - (F_M - F_S) sigma^2 (3 - 2 sigma)``,
``sigma = (s - s_M)/(s_S - s_M)``.

Aligning torque ``M_z = -n F_y`` with the pneumatic trail ``n = L (n/L)(|s_y|)`` (Rill 2012)::

    |s_y| <= s_y^0:  n/L = (n/L)_0 [(1 - w)(1 - t) + w (1 - (3 - 2t) t^2)],  t = |s_y|/s_y^0
    s_y^0 < |s_y| <= s_y^E:  n/L = -(n/L)_0 (1 - w) (|s_y| - s_y^0)/s_y^0 t'^2,
                             t' = (s_y^E - |s_y|)/(s_y^E - s_y^0)
    |s_y| > s_y^E:  n/L = 0,        w = s_y^0/s_y^E

and the contact length ``L = 2 sqrt(r_0 dz)``; the deflection solves the progressive
``F_z = a_1 dz + a_2 dz^2`` with ``a_1 = sqrt(2 c_N^2 - c_2N^2)``, ``a_2 = (c_2N^2 - c_N^2)
/(4 F_z^N)`` from the vertical stiffness at the two loads (Rill 2012).

Not modelled (steady state; fourws has its own parts for them): TMeasy's first-order contact
dynamics (fourws: ``tire.relaxation_length_*``), rolling resistance (``tire.rolling_resistance``),
camber and bore torque (the 8-DOF has no camber), the dynamic rolling radius
(``body.wheel_radius_m``). ``vx_mps`` enters only through its sign.

Parameters: ``tire.tmeasy`` (:class:`fourws_sim.params.TMeasy`), one tire on both axles;
:func:`read_json` reads Chrono::Vehicle and LFDM TMeasy JSON files.
"""

from __future__ import annotations

import json
import math
import re
from enum import IntEnum
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numba.extending import register_jitable

from fourws_sim.errors import ParameterError
from fourws_sim.params import TMEASY_JSON_KEY, TMeasy, tmeasy_from_mapping


class COEF(IntEnum):
    """Slots of the TMeasy coefficient array (SI: N, m, N/m, N/m^2; slips dimensionless)."""

    PN = 0
    PN_MAX = 1
    R0 = 2
    A1 = 3      # F_z = A1 dz + A2 dz^2, N/m
    A2 = 4      # N/m^2
    DFX0_PN = 5
    DFX0_P2N = 6
    FXM_PN = 7
    FXM_P2N = 8
    SXM_PN = 9
    SXM_P2N = 10
    FXS_PN = 11
    FXS_P2N = 12
    SXS_PN = 13
    SXS_P2N = 14
    DFY0_PN = 15
    DFY0_P2N = 16
    FYM_PN = 17
    FYM_P2N = 18
    SYM_PN = 19
    SYM_P2N = 20
    FYS_PN = 21
    FYS_P2N = 22
    SYS_PN = 23
    SYS_P2N = 24
    NTO0_PN = 25
    NTO0_P2N = 26
    SYNTO0_PN = 27
    SYNTO0_P2N = 28
    SYNTOE_PN = 29
    SYNTOE_P2N = 30


N_COEFFS = len(COEF)
#: Smallest rolling speed per slip-reference speed ``q`` (module docstring): TMeasy's
#: numerical speed ``v_N``; a locked wheel's slips become ``kappa/ROLLING_FLOOR`` (sliding).
ROLLING_FLOOR = 1.0e-3

# plain int slots: numba freezes module-level ints as compile-time constants
(_PN, _PN_MAX, _R0, _A1, _A2, _DFX0_PN, _DFX0_P2N, _FXM_PN, _FXM_P2N, _SXM_PN, _SXM_P2N,
 _FXS_PN, _FXS_P2N, _SXS_PN, _SXS_P2N, _DFY0_PN, _DFY0_P2N, _FYM_PN, _FYM_P2N, _SYM_PN,
 _SYM_P2N, _FYS_PN, _FYS_P2N, _SYS_PN, _SYS_P2N, _NTO0_PN, _NTO0_P2N, _SYNTO0_PN, _SYNTO0_P2N,
 _SYNTOE_PN, _SYNTOE_P2N) = range(N_COEFFS)
_HALF_SQRT2 = math.sqrt(0.5)


@register_jitable(error_model="numpy", inline="always")
def _quadratic(x: float, y1: float, y2: float) -> float:
    """TMeasy's load interpolation of forces and slopes through 0, ``y1`` (x = 1), ``y2``
    (x = 2)."""
    return x * (2.0 * y1 - 0.5 * y2 - (y1 - 0.5 * y2) * x)


@register_jitable(error_model="numpy", inline="always")
def _linear(x: float, y1: float, y2: float) -> float:
    """TMeasy's load interpolation of slips: ``y1`` at x = 1, ``y2`` at x = 2."""
    return y1 + (y2 - y1) * (x - 1.0)


@register_jitable(error_model="numpy")
def characteristic(s: float, df0: float, sm: float, fm: float, ss: float, fs: float) -> float:
    """The generalized characteristic ``F(s)`` (module docstring), ``s >= 0``, in N."""
    if not (s > 0.0 and sm > 0.0 and fm > 0.0):
        return 0.0
    if df0 < 2.0 * fm / sm:
        df0 = 2.0 * fm / sm
    if fs > fm:
        fs = fm
    if ss < sm:
        ss = sm
    if s >= ss:
        return fs
    if s <= sm:
        sigma = s / sm
        return sm * df0 * sigma / (1.0 + sigma * (sigma + df0 * sm / fm - 2.0))
    a = (fm / sm) * (fm / sm) / (df0 * sm)
    s_star = sm + (fm - fs) / (a * (ss - sm))
    if s_star <= ss:
        if s <= s_star:
            return fm - a * (s - sm) * (s - sm)
        b = a * (s_star - sm) / (ss - s_star)
        return fs + b * (ss - s) * (ss - s)
    sigma = (s - sm) / (ss - sm)
    return fm - (fm - fs) * sigma * sigma * (3.0 - 2.0 * sigma)


@register_jitable(error_model="numpy")
def trail_per_length(sy_abs: float, nto0: float, sy0: float, sye: float) -> float:
    """``n/L`` at lateral slip ``|s_y|`` (module docstring); 0 where ``(n/L)_0 = 0``."""
    if nto0 == 0.0:
        return 0.0
    if sye < sy0:
        sye = sy0
    if sy_abs >= sye:
        return 0.0
    w = sy0 / sye
    if sy_abs <= sy0:
        t = sy_abs / sy0
        return nto0 * ((1.0 - w) * (1.0 - t) + w * (1.0 - (3.0 - 2.0 * t) * t * t))
    t = (sye - sy_abs) / (sye - sy0)
    return -nto0 * (1.0 - w) * (sy_abs - sy0) / sy0 * t * t


@register_jitable(error_model="numpy")
def contact_length(fz_n: float, r0: float, a1: float, a2: float) -> float:
    """``L = 2 sqrt(r0 dz)``, ``dz`` the root of ``a1 dz + a2 dz^2 = F_z`` (written without the
    cancellation of ``(-a1 + sqrt(a1^2 + 4 a2 F_z))/(2 a2)``; a linear spring when a2 = 0)."""
    dz = 2.0 * fz_n / (a1 + math.sqrt(a1 * a1 + 4.0 * a2 * fz_n))
    return 2.0 * math.sqrt(r0 * dz)


def forces(fz_n: float, alpha_rad: float, kappa: float, vx_mps: float, mu: float,
           coeffs: np.ndarray) -> tuple[float, float, float]:
    """Tire-frame forces of the TMeasy tire.

    Parameters
    ----------
    fz_n : float
        Normal load in N; ``<= 0`` gives zero force.
    alpha_rad : float
        Slip angle in rad, ``|alpha| < pi/2`` (``Fy = -dF_y^0 alpha`` for small alpha).
    kappa : float
        Slip ratio, positive under drive, -1 locked (``Fx = dF_x^0 kappa`` for small kappa).
    vx_mps : float
        Wheel forward speed in m/s (its sign only: the rolling direction).
    mu : float
        Road friction over the tire's measured friction (1.0 = the data's surface).
    coeffs : numpy.ndarray
        Array from :func:`pack`.

    Returns
    -------
    fx_n, fy_n, mz_nm : float
        Longitudinal force (N), lateral force (N), aligning moment (N m).
    """
    q = abs((1.0 if vx_mps >= 0.0 else -1.0) + kappa)
    if q < ROLLING_FLOOR:
        q = ROLLING_FLOOR
    return slip_forces(fz_n, kappa / q, -math.tan(alpha_rad) / q, mu, coeffs)


@register_jitable(error_model="numpy")
def slip_forces(fz_n: float, sx: float, sy: float, mu: float,
                coeffs: np.ndarray) -> tuple[float, float, float]:
    """:func:`forces` at TMeasy's own slips ``s_x, s_y`` (slip velocity over rolling speed,
    module docstring): the curves as Chrono::Vehicle and LFDM tabulate them."""
    if not (fz_n > 0.0 and mu > 0.0):
        return 0.0, 0.0, 0.0
    c = coeffs
    fz = fz_n if fz_n < c[_PN_MAX] else c[_PN_MAX]
    x = fz / c[_PN]
    dfx0 = _quadratic(x, c[_DFX0_PN], c[_DFX0_P2N])
    fxm = mu * _quadratic(x, c[_FXM_PN], c[_FXM_P2N])
    fxs = mu * _quadratic(x, c[_FXS_PN], c[_FXS_P2N])
    sxm = mu * _linear(x, c[_SXM_PN], c[_SXM_P2N])
    sxs = mu * _linear(x, c[_SXS_PN], c[_SXS_P2N])
    dfy0 = _quadratic(x, c[_DFY0_PN], c[_DFY0_P2N])
    fym = mu * _quadratic(x, c[_FYM_PN], c[_FYM_P2N])
    fys = mu * _quadratic(x, c[_FYS_PN], c[_FYS_P2N])
    sym = mu * _linear(x, c[_SYM_PN], c[_SYM_P2N])
    sys = mu * _linear(x, c[_SYS_PN], c[_SYS_P2N])

    kx = fxm / dfx0
    ky = fym / dfy0
    hx = sxm / (sxm + sym) + kx / (kx + ky)
    hy = sym / (sxm + sym) + ky / (kx + ky)
    sxn = sx / hx
    syn = sy / hy
    s = math.hypot(sxn, syn)
    if s > 0.0:
        cphi = sxn / s
        sphi = syn / s
    else:
        cphi = _HALF_SQRT2
        sphi = _HALF_SQRT2
    df0 = math.hypot(dfx0 * hx * cphi, dfy0 * hy * sphi)
    fm = math.hypot(fxm * cphi, fym * sphi)
    sm = math.hypot(sxm / hx * cphi, sym / hy * sphi)
    fs = math.hypot(fxs * cphi, fys * sphi)
    ss = math.hypot(sxs / hx * cphi, sys / hy * sphi)
    f = characteristic(s, df0, sm, fm, ss, fs)
    fx = f * cphi
    fy = f * sphi

    nto0 = _linear(x, c[_NTO0_PN], c[_NTO0_P2N])
    mz = 0.0
    if nto0 != 0.0 and fy != 0.0:
        sy0 = mu * _linear(x, c[_SYNTO0_PN], c[_SYNTO0_P2N])
        sye = mu * _linear(x, c[_SYNTOE_PN], c[_SYNTOE_P2N])
        length = contact_length(fz_n, c[_R0], c[_A1], c[_A2])
        mz = -length * trail_per_length(abs(sy), nto0, sy0, sye) * fy
    return fx, fy, mz


def load_curve(coeffs: np.ndarray, fz_n: float, stem: str) -> float:
    """A load-dependent TMeasy value at ``fz_n`` (``"dfy0"``, ``"fym"``, ``"sym"``, ...: the
    ``COEF`` stem, lower case; friction scale 1), interpolated as :func:`forces` does."""
    x = min(fz_n, coeffs[_PN_MAX]) / coeffs[_PN]
    y1, y2 = coeffs[COEF[f"{stem.upper()}_PN"]], coeffs[COEF[f"{stem.upper()}_P2N"]]
    return float(_quadratic(x, y1, y2) if stem in TMeasy.QUADRATIC else _linear(x, y1, y2))


def cornering_stiffness_analytic(coeffs: np.ndarray, fz_n: float) -> float:
    """``-dFy/dalpha`` at zero slip in N/rad: ``dF_y^0(F_z)`` (raised to ``2 F_y^M/s_y^M`` where
    that is larger, see :func:`characteristic`)."""
    if not fz_n > 0.0:
        return 0.0
    dfy0 = load_curve(coeffs, fz_n, "dfy0")
    return max(dfy0, 2.0 * load_curve(coeffs, fz_n, "fym") / load_curve(coeffs, fz_n, "sym"))


def _field_of(slot: COEF) -> str:
    """The :class:`fourws_sim.params.TMeasy` field of a ``*_PN``/``*_P2N`` slot."""
    stem, load = slot.name.lower().rsplit("_", 1)
    return f"{stem}_{load}_n" if stem in TMeasy.QUADRATIC else f"{stem}_{load}"


#: Array slot -> :class:`fourws_sim.params.TMeasy` field (the slots A1, A2 are computed).
_FIELD_OF_SLOT: dict[int, str] = {
    int(COEF.PN): "nominal_load_n", int(COEF.PN_MAX): "maximum_load_n",
    int(COEF.R0): "unloaded_radius_m",
    **{int(slot): _field_of(slot) for slot in COEF if slot.name.endswith(("_PN", "_P2N"))},
}


def pack_params(p: TMeasy) -> np.ndarray:
    """Coefficient array of a validated :class:`fourws_sim.params.TMeasy`."""
    out = np.zeros(N_COEFFS, dtype=np.float64)
    for slot, name in _FIELD_OF_SLOT.items():
        out[slot] = getattr(p, name)
    c1, c2 = p.vertical_stiffness_pn_n_per_m, p.vertical_stiffness_p2n_n_per_m
    out[COEF.A1] = math.sqrt(2.0 * c1 * c1 - c2 * c2)
    out[COEF.A2] = (c2 * c2 - c1 * c1) / (4.0 * p.nominal_load_n)
    return out


def pack_mapping(values: Mapping[str, Any], source: str | None = None) -> np.ndarray:
    """Coefficient array from a mapping of :class:`fourws_sim.params.TMeasy` fields (missing
    ones take the defaults; no ``json`` key: give :func:`read_json`'s result instead).

    Raises
    ------
    ParameterError
        An unknown field, a bad value or a broken relation.
    """
    return pack_params(tmeasy_from_mapping(values, source))


def pack(vehicle: object, axle: str) -> np.ndarray:
    """Coefficient array of one tire on ``axle`` from the vehicle's ``tire.tmeasy`` (validated
    when the vehicle was loaded; one tire on both axles, so ``axle`` only is checked).

    Raises
    ------
    ParameterError
        On a bad axle name.
    """
    source = getattr(vehicle, "source", None)
    if axle not in ("front", "rear"):
        raise ParameterError("axle", f"must be 'front' or 'rear', got {axle!r}", source)
    tire = getattr(vehicle, "tire", None)
    values = {k: v for k, v in (tire.tmeasy if tire is not None else {}).items()
              if k != TMEASY_JSON_KEY}
    return pack_mapping(values, source)


# ----------------------------------------------------------------------------- JSON files
#: Chrono::Vehicle ``TMeasyTire`` JSON (``"Parameters"`` block, forces in N, slopes in N per
#: unit slip): fourws field -> key path (list index for the values at pn and 2 pn).
CHRONO_KEYS: dict[str, tuple[Any, ...]] = {
    "nominal_load_n": ("Parameters", "Tire Load", "Nominal Vertical Force [N]"),
    "maximum_load_n": ("Parameters", "Tire Load", "Maximum Vertical Force [N]"),
    "unloaded_radius_m": ("Design", "Unloaded Radius [m]"),
    "vertical_stiffness_pn_n_per_m": ("Parameters", "Tire Stiffness", "Vertical [N/m]", 0),
    "vertical_stiffness_p2n_n_per_m": ("Parameters", "Tire Stiffness", "Vertical [N/m]", 1),
    **{f"{stem}_{load}{unit}": ("Parameters", group, key, i)
       for group, axis in (("Longitudinal", "x"), ("Lateral", "y"))
       for stem, key, unit in ((f"df{axis}0", f"Initial Slopes dF{axis}/ds{axis} [N]", "_n"),
                               (f"f{axis}m", f"Maximum F{axis} Load [N]", "_n"),
                               (f"f{axis}s", f"Sliding F{axis} Load [N]", "_n"),
                               (f"s{axis}m", f"Slip s{axis} at Maximum F{axis}", ""),
                               (f"s{axis}s", f"Slip s{axis} where sliding begins", ""))
       for i, load in enumerate(("pn", "p2n"))},
    **{f"{stem}_{load}": ("Parameters", "Aligning", key, i)
       for stem, key in (("nto0", "Normalized Trail at Zero Slip sy"),
                         ("synto0", "Slip sy where Trail Changes Sign"),
                         ("syntoe", "Slip sy where Trail Tends to Zero"))
       for i, load in enumerate(("pn", "p2n"))},
}

#: LFDM (UW-SBEL low-fidelity-dynamic-models, ``data/json/<car>/tmeasy.json``) flat keys, SI
#: (N, m, N/m): fourws field -> key. LFDM's TMeasy has no aligning torque (``(n/L)_0 = 0``)
#: and one linear vertical stiffness ``kt``.
LFDM_KEYS: dict[str, str] = {
    "nominal_load_n": "pn", "maximum_load_n": "pnmax", "unloaded_radius_m": "r0",
    "vertical_stiffness_pn_n_per_m": "kt", "vertical_stiffness_p2n_n_per_m": "kt",
    **{f"{stem}_{load}{unit}": f"{stem}{'Pn' if load == 'pn' else 'P2n'}"
       for axis in ("x", "y")
       for stem, unit in ((f"df{axis}0", "_n"), (f"f{axis}m", "_n"), (f"f{axis}s", "_n"),
                          (f"s{axis}m", ""), (f"s{axis}s", ""))
       for load in ("pn", "p2n")},
}

#: Keys of the two formats that fourws reads but does not use, and why.
IGNORED_KEYS: dict[str, str] = {
    "Coefficient of Friction, mu": "fourws's friction is relative: tire.friction_coefficient "
                                   "= road friction / this value",
    "Rolling Resistance Coefficients, rr": "set tire.rolling_resistance",
    "Tire Stiffness Longitudinal/Lateral, Tire Damping, cx, cy, dx, dy":
        "TMeasy's contact dynamics; fourws lags the side force by tire.relaxation_length_*",
    "Dynamic Radius Weighting Coefficients, rdyncoPn, rdyncoP2n": "body.wheel_radius_m",
    "Design mass, inertia, width, rim radius; jw, step": "not tire-force data",
}

_COMMENT = re.compile(r'"(?:\\.|[^"\\])*"|//[^\n]*|/\*.*?\*/', re.S)


def _strip_comments(text: str) -> str:
    """JSON text without the ``//`` and ``/* */`` comments that Chrono's files carry (and
    that its reader accepts); strings are kept as they are."""
    return _COMMENT.sub(lambda m: m.group(0) if m.group(0).startswith('"') else "", text)


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {key!r}")
        out[key] = value
    return out


def read_json(path: str | Path, field: str = "tire.tmeasy.json",
              source: str | None = None) -> dict[str, float]:
    """The ``tire.tmeasy`` fields of a Chrono::Vehicle or LFDM TMeasy JSON file.

    A file with a ``"Parameters"`` block is read with :data:`CHRONO_KEYS`, one with ``"pn"``
    with :data:`LFDM_KEYS` (no unit conversion: both are SI with forces in N; Chrono's reader
    divides by 1000 and its code works in kN, the same numbers). :data:`IGNORED_KEYS` lists
    what is not used. Files that only name a load index (parameters guessed from the tire's
    size) are refused: fourws has no such guess.

    Raises
    ------
    ParameterError
        Naming ``field``: no such file, not JSON, neither format, a missing key or a
        non-number value.
    """
    where = Path(path)
    try:
        text = where.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(field, f"cannot read TMeasy JSON {str(where)!r}: {exc}",
                             source) from None
    try:
        data = json.loads(_strip_comments(text), object_pairs_hook=_no_duplicates)
    except ValueError as exc:
        raise ParameterError(field, f"{str(where)!r} is not JSON: {exc}", source) from None
    if not isinstance(data, dict):
        raise ParameterError(field, f"{str(where)!r} is not a JSON object", source)
    out: dict[str, float] = {}
    if "Parameters" in data:
        for name, keys in CHRONO_KEYS.items():
            value: Any = data
            for key in keys:
                try:
                    value = value[key]
                except (KeyError, IndexError, TypeError):
                    raise ParameterError(field, f"{str(where)!r} has no "
                                         f"{'/'.join(str(k) for k in keys)} (Chrono TMeasy "
                                         "format)", source) from None
            out[name] = _number(value, field, where, "/".join(str(k) for k in keys), source)
    elif "pn" in data:
        for name, key in LFDM_KEYS.items():
            if key not in data:
                raise ParameterError(field, f"{str(where)!r} has no key {key!r} (LFDM TMeasy "
                                            "format)", source)
            out[name] = _number(data[key], field, where, key, source)
        # no aligning torque in LFDM's TMeasy; the trail slips only keep the block valid
        out.update(nto0_pn=0.0, nto0_p2n=0.0, synto0_pn=out["sym_pn"],
                   synto0_p2n=out["sym_p2n"], syntoe_pn=out["sys_pn"],
                   syntoe_p2n=out["sys_p2n"])
    else:
        raise ParameterError(field, f"{str(where)!r} has neither Chrono's \"Parameters\" nor "
                                    "LFDM's \"pn\" (a file that names a load index only "
                                    "holds no parameters fourws can read)", source)
    return out


def _number(value: Any, field: str, where: Path, key: str, source: str | None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value):
        raise ParameterError(field, f"{str(where)!r}: {key} must be a finite number, got "
                                    f"{value!r}", source)
    return float(value)
