"""Numba kernels of the 8-DOF model (right-hand side, RK4 and Euler loops) for one tire model.

The equations are those of :mod:`fourws_sim.models.eightdof` (see its docstring), written as
scalar loops without allocation. Do not import this module directly: use
:func:`fourws_sim.models.eightdof.kernels_for`, which loads this file once per tire model
under its own module name with ``TIRE_NAME`` set, so every tire gets its own compiled (and
disk-cached) variant with the tire function inlined.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path
from typing import Any

import numba
import numpy as np

from fourws_sim.models.eightdof import (_AUX_ALPHA, _AUX_AX, _AUX_AY, _AUX_DELTA_F,
                                        _AUX_DELTA_R, _AUX_FX, _AUX_FY, _AUX_FZ, _AUX_KAPPA,
                                        _AUX_MZ, HELD_SPIN_FLOOR_RADPS, INPUT, N_AUX,
                                        N_STATE, PARAM, STATE)
from fourws_sim.tires import get_tire

#: Tire model of this variant (set by ``kernels_for`` before the module body runs).
TIRE_NAME: str = globals().get("TIRE_NAME", "linear")

#: numba options: IEEE division semantics (no Python ZeroDivisionError checks: halves the
#: cost of the tire). No fast-math flags: with {contract, reassoc, arcp, nsz} LLVM folds
#: ``x * 0.0`` to 0 in the finiteness test, so a diverging state would go unnoticed.
JIT_OPTIONS: dict[str, Any] = {"error_model": "numpy"}

_TIRE_MODULE = get_tire(TIRE_NAME)
_tire = numba.njit(cache=True, **JIT_OPTIONS)(_TIRE_MODULE.forces)


def _source_digest() -> str:
    """Short hash of the sources this variant's compiled code depends on besides this file:
    the model module (state/input/parameter slots are frozen in as constants) and the tire
    module (its code is linked in). numba only checks the stamp of the function's own file,
    so without this an edited tire or model would silently run from a stale cache."""
    from fourws_sim.models import eightdof

    digest = hashlib.sha1()
    for module in (eightdof, _TIRE_MODULE):
        digest.update(Path(module.__file__).read_bytes())  # type: ignore[arg-type]
    return digest.hexdigest()[:12]


_VARIANT = f"{TIRE_NAME}_{_source_digest()}"


def _jit(func: Any) -> Any:
    """Compile ``func`` for this tire variant.

    numba names its cache files after the source file and the function's qualified name and
    does not key them on globals, so each variant gets its own qualified name
    (``rhs_sti_<digest>``, ...) -- otherwise the variants would share (and load) one cache
    entry, and an edit of the tire or model module would not invalidate it.
    """
    func.__qualname__ = f"{func.__name__}_{_VARIANT}"
    return numba.njit(cache=True, **JIT_OPTIONS)(func)


# plain int slots: numba freezes module-level ints as compile-time constants
i_u, i_v, i_r, i_phi, i_p = (int(STATE.U), int(STATE.V), int(STATE.R), int(STATE.PHI),
                             int(STATE.P))
i_w0, i_x, i_y, i_psi = int(STATE.OMEGA_FL), int(STATE.X), int(STATE.Y), int(STATE.PSI)
i_ax, i_ay, i_al0 = int(STATE.AX_LT), int(STATE.AY_LT), int(STATE.ALPHA_FL)
j_df, j_dr, j_d0, j_b0 = (int(INPUT.DELTA_F), int(INPUT.DELTA_R), int(INPUT.DRIVE_FL),
                          int(INPUT.BRAKE_FL))
k_m, k_ms, k_iz, k_ix, k_ixz = (int(PARAM.M), int(PARAM.MS), int(PARAM.IZ), int(PARAM.IX),
                                int(PARAM.IXZ))
k_a, k_b, k_tf, k_tr, k_hcg = (int(PARAM.A), int(PARAM.B), int(PARAM.TF), int(PARAM.TR),
                               int(PARAM.H_CG))
k_h, k_rcf, k_rcr, k_hu = (int(PARAM.H_ROLL), int(PARAM.H_RC_F), int(PARAM.H_RC_R),
                           int(PARAM.H_U))
k_rw, k_iw, k_kf, k_kr = (int(PARAM.R_W), int(PARAM.I_W), int(PARAM.K_PHI_F),
                          int(PARAM.K_PHI_R))
k_cf, k_cr, k_ef, k_er = (int(PARAM.C_PHI_F), int(PARAM.C_PHI_R), int(PARAM.EPS_F),
                          int(PARAM.EPS_R))
k_mu, k_frr, k_sig, k_vmin = (int(PARAM.MU), int(PARAM.F_RR), int(PARAM.SIGMA),
                              int(PARAM.V_MIN))
k_tlt, k_tb, k_g = int(PARAM.TAU_LT), int(PARAM.TAU_B), int(PARAM.G)
a_fz, a_al, a_ka, a_fx, a_fy, a_mz = _AUX_FZ, _AUX_ALPHA, _AUX_KAPPA, _AUX_FX, _AUX_FY, _AUX_MZ
HELD_FLOOR = float(HELD_SPIN_FLOOR_RADPS)
a_df, a_dr, a_ax, a_ay = _AUX_DELTA_F, _AUX_DELTA_R, _AUX_AX, _AUX_AY


@_jit
def rhs(x, u, q, cf, cr, dx, aux):  # type: ignore[no-untyped-def]
    """dx/dt into ``dx`` and per-wheel quantities into ``aux`` (see ``eightdof.Kernels``)."""
    U = x[i_u]
    V = x[i_v]
    r = x[i_r]
    phi = x[i_phi]
    pr = x[i_p]
    psi = x[i_psi]
    m = q[k_m]
    ms = q[k_ms]
    g = q[k_g]
    a = q[k_a]
    b = q[k_b]
    L = a + b
    tf = q[k_tf]
    tr = q[k_tr]
    rw = q[k_rw]
    iw = q[k_iw]
    vmin = q[k_vmin]
    sigma = q[k_sig]
    mu = q[k_mu]
    mu_ = m - ms
    delta_f = u[j_df] + q[k_ef] * phi
    delta_r = u[j_dr] + q[k_er] * phi
    ax_lt = x[i_ax]
    ay_lt = x[i_ay]
    d_long = 0.5 * m * ax_lt * q[k_hcg] / L
    m_front = m * b / L
    m_rear = m * a / L
    d_lat_f = (q[k_kf] * phi + q[k_cf] * pr + m_front * (ms / m) * q[k_rcf] * ay_lt
               + m_front * (mu_ / m) * q[k_hu] * ay_lt) / tf
    d_lat_r = (q[k_kr] * phi + q[k_cr] * pr + m_rear * (ms / m) * q[k_rcr] * ay_lt
               + m_rear * (mu_ / m) * q[k_hu] * ay_lt) / tr
    st_f = m * g * b / (2.0 * L)
    st_r = m * g * a / (2.0 * L)
    cdf = math.cos(delta_f)
    sdf = math.sin(delta_f)
    cdr = math.cos(delta_r)
    sdr = math.sin(delta_r)
    sum_fx = 0.0
    sum_fy = 0.0
    sum_n = 0.0
    for i in range(4):
        if i < 2:
            xw = a
            cd = cdf
            sd = sdf
            fz = st_f - d_long
            dl = d_lat_f
            yw = 0.5 * tf
        else:
            xw = -b
            cd = cdr
            sd = sdr
            fz = st_r + d_long
            dl = d_lat_r
            yw = 0.5 * tr
        if i == 0 or i == 2:
            fz -= dl
        else:
            fz += dl
            yw = -yw
        if fz < 0.0:
            fz = 0.0
        vxb = U - r * yw
        vyb = V + r * xw
        vx = vxb * cd + vyb * sd
        vy = -vxb * sd + vyb * cd
        avx = abs(vx)
        den = avx if avx > vmin else vmin
        alpha = math.atan(vy / den)  # den > 0: atan2(vy, den) without the quadrant logic
        om = x[i_w0 + i]
        kappa = (om * rw - vx) / den
        if sigma > 0.0:
            al_lag = x[i_al0 + i]
            dx[i_al0 + i] = den / sigma * (alpha - al_lag)
            alpha_t = al_lag
        else:
            dx[i_al0 + i] = 0.0
            alpha_t = alpha
        if i < 2:
            fx, fy, mz = _tire(fz, alpha_t, kappa, avx, mu, cf)
        else:
            fx, fy, mz = _tire(fz, alpha_t, kappa, avx, mu, cr)
        fxb = fx * cd - fy * sd
        fyb = fx * sd + fy * cd
        sum_fx += fxb
        sum_fy += fyb
        sum_n += xw * fyb - yw * fxb + mz
        brake = u[j_b0 + i]
        if brake < 0.0:
            brake = 0.0
        cap = brake + q[k_frr] * fz * rw
        t_other = u[j_d0 + i] - rw * fx
        if iw * abs(om) >= cap * q[k_tb]:  # sliding: Coulomb friction
            if om > 0.0:
                t_other -= cap
            elif om < 0.0:
                t_other += cap
            dx[i_w0 + i] = t_other / iw
        elif t_other > cap:  # stuck band, breaking loose forwards
            dx[i_w0 + i] = (t_other - cap) / iw
        elif t_other < -cap:  # stuck band, breaking loose backwards
            dx[i_w0 + i] = (t_other + cap) / iw
        elif abs(om) > HELD_FLOOR:  # stuck band, held: the spin decays to zero
            dx[i_w0 + i] = -om / q[k_tb] * (1.0 - abs(t_other) / cap)
        else:
            dx[i_w0 + i] = 0.0
        aux[a_fz + i] = fz
        aux[a_al + i] = alpha_t
        aux[a_ka + i] = kappa
        aux[a_fx + i] = fx
        aux[a_fy + i] = fy
        aux[a_mz + i] = mz
    c = math.cos(phi)
    s = math.sin(phi)
    msh = ms * q[k_h]
    mshc = msh * c
    iz = q[k_iz]
    ixz = q[k_ixz]
    rhs_y = sum_fy - m * U * r - msh * s * (pr * pr + r * r)
    rhs_l = (mshc * U * r + msh * g * s - (q[k_kf] + q[k_kr]) * phi
             - (q[k_cf] + q[k_cr]) * pr)
    det = q[k_ix] - mshc * mshc / m - ixz * ixz / iz
    pd = (rhs_l + mshc * rhs_y / m + ixz * sum_n / iz) / det
    vd = (rhs_y + mshc * pd) / m
    rd = (sum_n + ixz * pd) / iz
    ud = (sum_fx + m * V * r - msh * (s * rd + 2.0 * r * pr * c)) / m
    ax = ud - V * r
    ay = vd + U * r
    dx[i_u] = ud
    dx[i_v] = vd
    dx[i_r] = rd
    dx[i_phi] = pr
    dx[i_p] = pd
    cps = math.cos(psi)
    sps = math.sin(psi)
    dx[i_x] = U * cps - V * sps
    dx[i_y] = U * sps + V * cps
    dx[i_psi] = r
    dx[i_ax] = (ax - ax_lt) / q[k_tlt]
    dx[i_ay] = (ay - ay_lt) / q[k_tlt]
    aux[a_df] = delta_f
    aux[a_dr] = delta_r
    aux[a_ax] = ax
    aux[a_ay] = ay


@_jit
def rk4(x, u, q, cf, cr, dt, n):  # type: ignore[no-untyped-def]
    """``n`` RK4 steps in place; returns the number of finite steps done."""
    k1 = np.empty(N_STATE)
    k2 = np.empty(N_STATE)
    k3 = np.empty(N_STATE)
    k4 = np.empty(N_STATE)
    xt = np.empty(N_STATE)
    aux = np.empty(N_AUX)
    half = 0.5 * dt
    sixth = dt / 6.0
    for step in range(n):
        rhs(x, u, q, cf, cr, k1, aux)
        for j in range(N_STATE):
            xt[j] = x[j] + half * k1[j]
        rhs(xt, u, q, cf, cr, k2, aux)
        for j in range(N_STATE):
            xt[j] = x[j] + half * k2[j]
        rhs(xt, u, q, cf, cr, k3, aux)
        for j in range(N_STATE):
            xt[j] = x[j] + dt * k3[j]
        rhs(xt, u, q, cf, cr, k4, aux)
        ok = True
        for j in range(N_STATE):
            xt[j] = x[j] + sixth * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            if not math.isfinite(xt[j]):
                ok = False
        if not ok:
            return step
        for j in range(N_STATE):
            x[j] = xt[j]
    return n


@_jit
def euler(x, u, q, cf, cr, dt, n):  # type: ignore[no-untyped-def]
    """``n`` explicit-Euler steps in place; returns the number of finite steps done."""
    k1 = np.empty(N_STATE)
    xt = np.empty(N_STATE)
    aux = np.empty(N_AUX)
    for step in range(n):
        rhs(x, u, q, cf, cr, k1, aux)
        ok = True
        for j in range(N_STATE):
            xt[j] = x[j] + dt * k1[j]
            if not math.isfinite(xt[j]):
                ok = False
        if not ok:
            return step
        for j in range(N_STATE):
            x[j] = xt[j]
    return n
