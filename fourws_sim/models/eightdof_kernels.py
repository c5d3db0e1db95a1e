# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Numba kernels of the 8-DOF model (right-hand side, RK4 and Euler loops) for one tire model.

The equations are those of :mod:`fourws_sim.models.eightdof` (see its docstring). This file is
a template of :mod:`fourws_sim.variants`: :func:`fourws_sim.models.eightdof.kernels_for` loads
it once per tire model (``fourws_sim.models.eightdof_kernels[sti]``, ...), so every tire gets
its own compiled (and disk-cached) variant with the tire function inlined.

The equations, once
-------------------
Each piece of the model is one function of plain numbers, without branches and without any
memory layout: :func:`_wheel_loads` (normal loads), :func:`_corner_slip` (a corner's wheel
kinematics, slips and slip lag), :func:`_corner_spin` (its forces in the body frame, their
moment and the wheel's spin equation), :func:`_differential` (an axle's differential: the
locking torque between its wheels), :func:`_body_rates` (the body's equations of motion,
pose and load-transfer lag). Between a corner's slip and spin comes its tire. Two right-hand
sides call them, differing only in where the numbers are stored:

* :func:`rhs` (scalar: one state, the simulator's, ``Kernels.rhs``/``rk4``/``euler``): arrays
  in :class:`~fourws_sim.models.eightdof.STATE`, ``INPUT`` and ``PARAM`` order; it also has
  the free steering system;
* :func:`rhs_lanes` (the study's batch kernel: ``LANES`` states side by side in the layout of
  :mod:`fourws_sim.lanes`, a loop over lanes that compiles to vector instructions; the
  fixed-control 8-DOF with a tire that has ``forces_lane``).

A branch is a choice between computed values under the same test, so both give the same
numbers bit for bit (``test_eightdof_regression``); numba compiles with IEEE division, where a
value not chosen may be an infinity. The plain-Python reference
:func:`fourws_sim.models.eightdof.evaluate` cannot run these functions for that reason (its
division by a zero friction capacity would raise) and is the test oracle.

Speed (the simulator runs RK4 at 1 ms many times faster than real time): the right-hand side
is inlined into the RK4 loop at one call site, and it evaluates the four tires back to
back (wheel kinematics of all four wheels first, then the four tires, then the wheel and body
equations), so that the CPU overlaps the four independent latency chains of the tire. A tire
module may provide ``forces4(fz, alpha, kappa, vx, mu, coeffs_front, coeffs_rear, fx, fy, mz)``
(arrays of the four wheels FL, FR, RL, RR) that interleaves the four evaluations phase by
phase; it must give exactly the numbers of four ``forces`` calls (``test_eightdof_regression``
checks bit equality). Parameter-only terms are computed once per kernel call, and divisions
by parameters are multiplications by their reciprocals: the results equal the plain scalar
code's to round-off (``test_eightdof_regression`` pins trajectories of the model to 1e-12).

Sub-steps: the right-hand side also reports the rate of the fastest slip mode (aux slot
``_AUX_RATE``); the RK4 and Euler loops read it from their first stage and, where the step is
too long for it (a light or slowly rolling wheel), take the step in ``eightdof.substeps``
equal sub-steps in a separate compiled function. In normal driving the arithmetic is that of a
plain step, bit for bit, and the check costs a comparison per step. The integrators' float
operations over flat arrays are written once (:func:`_advance`, :func:`_rk4_sum`,
:func:`_accept`) for the simulator's loop, its sub-steps and the lanes; each loop keeps only
its own stage sequence (where the right-hand side is inlined or called, where sub-steps are
decided).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fourws_sim.models.eightdof import (_AUX_ALPHA, _AUX_AX, _AUX_AY, _AUX_DELTA_F,
                                        _AUX_DELTA_R, _AUX_DRIVE, _AUX_FX, _AUX_FY, _AUX_FZ,
                                        _AUX_KAPPA, _AUX_MZ, _AUX_RATE, BIAS_BAND_RADPS,
                                        EULER_RATE_BOUND,
                                        HELD_SPIN_FLOOR_RADPS, INPUT, MAX_SUBSTEPS, N_AUX,
                                        N_INPUT, N_STATE, PARAM, RK4_RATE_BOUND, STATE)
from fourws_sim.models import eightdof
from fourws_sim import lanes, trig, variants
from fourws_sim.tires import get_tire
from fourws_sim.lanes import LANES
from fourws_sim.trig import atan, sincos

#: Tire model of this variant (:func:`fourws_sim.variants.tire_of` its module name).
TIRE_NAME: str = variants.tire_of(__name__)

#: numba options: IEEE division semantics (no Python ZeroDivisionError checks: halves the
#: cost of the tire). No fast-math flags: with {contract, reassoc, arcp, nsz} LLVM folds
#: ``x * 0.0`` to 0 in the finiteness test, so a diverging state would go unnoticed.
JIT_OPTIONS: dict[str, Any] = {"error_model": "numpy"}

_TIRE_MODULE = get_tire(TIRE_NAME)
#: What this variant compiles in besides this file: the model module (state, input and
#: parameter slots are frozen in as constants), sin/cos/atan, the lane layout and the tire.
VARIANT = variants.Variant(__file__, TIRE_NAME, (eightdof, trig, lanes, _TIRE_MODULE),
                           JIT_OPTIONS)
_jit = VARIANT.jit
_jit_inline = VARIANT.inline

#: The tire's ``forces`` as compiled into this variant (also callable from Python). Called,
#: not inlined, by ``rhs``: inlining the Magic Formula saves 4 % of the time of a step but
#: adds 4 s to the first compile; the STI tire is inlined through its ``forces4``.
_tire = _jit(_TIRE_MODULE.forces)


# plain int slots: numba freezes module-level ints as compile-time constants
i_u, i_v, i_r, i_phi, i_p = (int(STATE.U), int(STATE.V), int(STATE.R), int(STATE.PHI),
                             int(STATE.P))
i_w0, i_x, i_y, i_psi = int(STATE.OMEGA_FL), int(STATE.X), int(STATE.Y), int(STATE.PSI)
i_ax, i_ay, i_al0 = int(STATE.AX_LT), int(STATE.AY_LT), int(STATE.ALPHA_FL)
i_ds, i_dsr = int(STATE.DELTA_S), int(STATE.DELTA_S_RATE)
j_df, j_dr, j_d0, j_b0 = (int(INPUT.DELTA_F), int(INPUT.DELTA_R), int(INPUT.DRIVE_FL),
                          int(INPUT.BRAKE_FL))
j_tq = int(INPUT.STEER_TORQUE)
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
k_mu, k_frr, k_sigf, k_sigr, k_vmin = (int(PARAM.MU), int(PARAM.F_RR), int(PARAM.SIGMA_F),
                                       int(PARAM.SIGMA_R), int(PARAM.V_MIN))
k_tlt, k_tb, k_g, k_kspin = int(PARAM.TAU_LT), int(PARAM.TAU_B), int(PARAM.G), int(PARAM.K_SPIN)
k_sfree, k_js, k_nus, k_es = (int(PARAM.STEER_FREE), int(PARAM.J_S), int(PARAM.NU_S),
                              int(PARAM.E_S))
k_tcs, k_ns, k_rates = int(PARAM.TC_S), int(PARAM.N_S), int(PARAM.RATE_S)
k_drag, k_liftf, k_liftr = int(PARAM.DRAG), int(PARAM.LIFT_F), int(PARAM.LIFT_R)
k_viscf, k_viscr, k_biasf, k_biasr = (int(PARAM.VISC_F), int(PARAM.VISC_R), int(PARAM.BIAS_F),
                                      int(PARAM.BIAS_R))
a_drive = _AUX_DRIVE
INV_BIAS_BAND = 1.0 / float(BIAS_BAND_RADPS)
a_fz, a_al, a_ka, a_fx, a_fy, a_mz = _AUX_FZ, _AUX_ALPHA, _AUX_KAPPA, _AUX_FX, _AUX_FY, _AUX_MZ
HELD_FLOOR = float(HELD_SPIN_FLOOR_RADPS)
a_df, a_dr, a_ax, a_ay, a_rate = _AUX_DELTA_F, _AUX_DELTA_R, _AUX_AX, _AUX_AY, _AUX_RATE
RK4_BOUND = float(RK4_RATE_BOUND)
EULER_BOUND = float(EULER_RATE_BOUND)
MAX_SUB = int(MAX_SUBSTEPS)


def _forces4_by_wheel(fz, alpha, kappa, vx, mu, cf, cr,  # type: ignore[no-untyped-def]
                      fx, fy, mz):
    """``forces4`` by four ``forces`` calls (tires without their own ``forces4``; ``rhs``
    then calls ``forces`` directly, this only keeps ``_forces4`` defined for typing)."""
    for i in range(4):
        cc = cf if i < 2 else cr
        fx[i], fy[i], mz[i] = _tire(fz[i], alpha[i], kappa[i], vx[i], mu, cc)


#: Whether the tire interleaves the four wheels itself (else ``rhs`` calls ``forces`` four
#: times, which compiles to faster code than the generic ``_forces4_by_wheel``).
HAS_FORCES4 = hasattr(_TIRE_MODULE, "forces4")
_forces4 = _jit_inline(getattr(_TIRE_MODULE, "forces4", _forces4_by_wheel))


def _parameter_terms(q):  # type: ignore[no-untyped-def]
    """Terms of the right-hand side that depend on the parameters only (computed once per
    kernel call), each by the same operations in the same order as written out in ``rhs``
    before, so the results are unchanged."""
    m = q[k_m]
    ms = q[k_ms]
    g = q[k_g]
    a = q[k_a]
    b = q[k_b]
    L = a + b
    mu_ = m - ms
    m_front = m * b / L
    m_rear = m * a / L
    msh = ms * q[k_h]
    return (L,
            0.5 * m,  # d_long = 0.5 m ax h_cg / L
            m_front * (ms / m) * q[k_rcf],  # front roll-centre lateral transfer per ay
            m_front * (mu_ / m) * q[k_hu],  # front unsprung lateral transfer per ay
            m_rear * (ms / m) * q[k_rcr],
            m_rear * (mu_ / m) * q[k_hu],
            m * g * b / (2.0 * L),  # static load of a front tire
            m * g * a / (2.0 * L),  # static load of a rear tire
            msh,
            msh * g,
            q[k_kf] + q[k_kr],
            q[k_cf] + q[k_cr],
            q[k_ixz] * q[k_ixz] / q[k_iz],
            # reciprocals: a division by a parameter is a multiplication (equal to round-off)
            1.0 / L,
            1.0 / q[k_tf],
            1.0 / q[k_tr],
            1.0 / q[k_sigf] if q[k_sigf] > 0.0 else 0.0,
            1.0 / q[k_iw],
            1.0 / m,
            1.0 / q[k_iz],
            1.0 / q[k_tlt],
            1.0 / q[k_sigr] if q[k_sigr] > 0.0 else 0.0)


_P_L, _P_HALF_M, _P_RCF, _P_HUF, _P_RCR, _P_HUR, _P_STF, _P_STR = 0, 1, 2, 3, 4, 5, 6, 7
_P_MSH, _P_MSHG, _P_KPHI, _P_CPHI, _P_IXZ2 = 8, 9, 10, 11, 12
_P_INV_L, _P_INV_TF, _P_INV_TR, _P_INV_SIGMA_F, _P_INV_IW = 13, 14, 15, 16, 17
_P_INV_M, _P_INV_IZ, _P_INV_TLT, _P_INV_SIGMA_R = 18, 19, 20, 21
#: Number of the parameter terms.
N_PT = _P_INV_SIGMA_R + 1


# ------------------------------------------------------------------------------ equations
# Plain numbers in, plain numbers out: no branch, no array (see the module docstring).

def _wheel_loads(phi, pr, U, ax_lt, ay_lt, half_m, h_cg, inv_l,  # type: ignore
                 k_phi_f, c_phi_f, rc_f, hu_f, inv_tf, k_phi_r, c_phi_r, rc_r, hu_r, inv_tr,
                 static_f, static_r, drag, lift_f, lift_r):
    """Normal loads FL, FR, RL, RR (N, before the clamp at 0): static less the aerodynamic
    lift (``lift_f``, ``lift_r`` per wheel and U^2, kg/m), longitudinal transfer of the
    forces at the ground (``m ax + drag``, ``drag`` per U|U| in kg/m) and lateral transfer
    (Figures 8.3, 8.4) from the roll state and the lagged accelerations. With ``drag``,
    ``lift_f``, ``lift_r`` zero the numbers are those without them, bit for bit."""
    d_long = (half_m * ax_lt + 0.5 * drag * (U * abs(U))) * h_cg * inv_l
    d_lat_f = (k_phi_f * phi + c_phi_f * pr + rc_f * ay_lt + hu_f * ay_lt) * inv_tf
    d_lat_r = (k_phi_r * phi + c_phi_r * pr + rc_r * ay_lt + hu_r * ay_lt) * inv_tr
    uu = U * U
    load_f = static_f - lift_f * uu
    load_r = static_r - lift_r * uu
    return ((load_f - d_long) - d_lat_f, (load_f - d_long) + d_lat_f,
            (load_r + d_long) - d_lat_r, (load_r + d_long) + d_lat_r)


def _corner_slip(fz, U, V, r, xw, yw, cd, sd, omega, alpha_lag,  # type: ignore
                 inv_sigma, rw, vmin, k_spin, rate):
    """One corner's wheel kinematics (eqs. 8.34-8.46): the wheel at ``(xw, yw)`` (m) steered
    by the angle of cosine ``cd`` and sine ``sd``, spinning at ``omega`` (rad/s), with the
    lagged slip angle ``alpha_lag`` (rad) of its relaxation length (``inv_sigma`` 1/m, 0 for
    none). Returns its load clamped at 0 (N), the slip angle its tire sees (rad), the slip
    ratio, the wheel's forward speed |v_x| (m/s), the slip lag's derivative (rad/s) and the
    larger of ``rate`` and its slip modes' rates (1/s, the sub-steps')."""
    fz = 0.0 if fz < 0.0 else fz
    vxb = U - r * yw
    vyb = V + r * xw
    vx = vxb * cd + vyb * sd
    vy = -vxb * sd + vyb * cd
    avx = abs(vx)
    den = avx if avx > vmin else vmin
    inv_den = 1.0 / den  # den >= v_min > 0
    alpha = atan(vy * inv_den)  # atan2(vy, den) without the quadrant logic
    kappa = (omega * rw - vx) * inv_den
    lagged = inv_sigma > 0.0
    lag_rate = den * inv_sigma
    d_alpha = lag_rate * (alpha - alpha_lag) if lagged else 0.0
    alpha_t = alpha_lag if lagged else alpha
    rate = lag_rate if (lagged and lag_rate > rate) else rate
    spin_rate = k_spin * inv_den
    rate = spin_rate if spin_rate > rate else rate
    return fz, alpha_t, kappa, avx, d_alpha, rate


def _corner_spin(fx, fy, mz, fz, omega, xw, yw, cd, sd, drive, brake,  # type: ignore
                 rw, iw, inv_iw, tau_b, f_rr):
    """One corner's tire forces ``fx, fy`` (N, tire frame) and aligning moment ``mz`` (N m)
    in the body frame (eqs. 8.9-8.13) and the wheel's spin acceleration (eqs. 8.5-8.8, the
    stick-slip friction of brake ``brake`` and rolling resistance of the eightdof docstring).
    Returns ``(fx_body, fy_body, moment about the CG, d omega/dt)``."""
    fxb = fx * cd - fy * sd
    fyb = fx * sd + fy * cd
    moment = xw * fyb - yw * fxb + mz
    brake = 0.0 if brake < 0.0 else brake
    cap = brake + f_rr * fz * rw
    t_other = drive - rw * fx
    sliding = iw * abs(omega) >= cap * tau_b  # Coulomb friction opposes the spin
    t_slide = (t_other - cap if omega > 0.0 else
               (t_other + cap if omega < 0.0 else t_other))
    held = -omega / tau_b * (1.0 - abs(t_other) / cap)  # stuck band: decays to zero
    d_omega = (t_slide * inv_iw if sliding else
               ((t_other - cap) * inv_iw if t_other > cap else  # breaking loose
                ((t_other + cap) * inv_iw if t_other < -cap else
                 (held if abs(omega) > HELD_FLOOR else 0.0))))
    return fxb, fyb, moment, d_omega


def _differential(drive_l, drive_r, omega_l, omega_r, visc, bias,  # type: ignore
                  inv_iw, rate):
    """An axle's differential (eightdof docstring): the drive torques ``drive_l, drive_r``
    (N m, the open split) less and plus the locking torque of the viscous coupling ``visc``
    (N m s/rad) and the torque bias ``bias`` ((TBR - 1)/(TBR + 1)) at the wheel speeds
    ``omega_l, omega_r`` (rad/s). Returns the two wheels' torques and the larger of ``rate``
    and the coupling's rate (1/s). With ``visc`` and ``bias`` 0 the torques are unchanged."""
    dw = omega_l - omega_r
    s = dw * INV_BIAS_BAND
    s = 1.0 if s > 1.0 else (-1.0 if s < -1.0 else s)
    t_axle = abs(drive_l + drive_r)
    lock = visc * dw + 0.5 * bias * t_axle * s
    coupling = (2.0 * visc + bias * t_axle * INV_BIAS_BAND) * inv_iw
    rate = coupling if coupling > rate else rate
    return drive_l - lock, drive_r + lock, rate


def _body_rates(sum_fx, sum_fy, sum_n, U, V, r, phi, pr, psi,  # type: ignore
                ax_lt, ay_lt, m, ix, ixz, msh, msh_g, k_phi, c_phi, ixz2, inv_m, inv_iz,
                inv_tlt, drag):
    """The body's equations of motion (eqs. 8.1-8.4, 8.14: the 3x3 system in V', r', p'
    solved in closed form, then U'), the pose rates (8.15-8.17) and the lag of the
    load-transfer accelerations, from the summed tire forces ``sum_fx, sum_fy`` (N) and yaw
    moment ``sum_n`` (N m) and the aerodynamic drag ``drag`` U|U| (``drag`` in kg/m, along
    -x at the CG). Returns ``(U', V', r', p', ax, ay, X', Y', ax_lt', ay_lt')``."""
    s, c = sincos(phi)
    mshc = msh * c
    rhs_y = sum_fy - m * U * r - msh * s * (pr * pr + r * r)
    rhs_l = mshc * U * r + msh_g * s - k_phi * phi - c_phi * pr
    det = ix - mshc * mshc * inv_m - ixz2
    pd = (rhs_l + mshc * rhs_y * inv_m + ixz * sum_n * inv_iz) / det
    vd = (rhs_y + mshc * pd) * inv_m
    rd = (sum_n + ixz * pd) * inv_iz
    ud = (sum_fx - drag * (U * abs(U)) + m * V * r - msh * (s * rd + 2.0 * r * pr * c)) * inv_m
    ax = ud - V * r
    ay = vd + U * r
    sps, cps = sincos(psi)
    return (ud, vd, rd, pd, ax, ay, U * cps - V * sps, U * sps + V * cps,
            (ax - ax_lt) * inv_tlt, (ay - ay_lt) * inv_tlt)


_wheel_loads = _jit_inline(_wheel_loads)
_corner_slip = _jit_inline(_corner_slip)
_corner_spin = _jit_inline(_corner_spin)
_body_rates = _jit_inline(_body_rates)
_differential = _jit_inline(_differential)


# ------------------------------------------------------------------------------ scalar

def _corner_geometry(i, a, b, tf, tr, cdf, sdf, cdr, sdr):  # type: ignore[no-untyped-def]
    """Position (m) and steer cosine and sine of corner ``i`` (FL, FR, RL, RR)."""
    front = i < 2
    xw = a if front else -b
    half_track = 0.5 * tf if front else 0.5 * tr
    yw = half_track if (i == 0 or i == 2) else -half_track
    return xw, yw, (cdf if front else cdr), (sdf if front else sdr)


_corner_geometry = _jit_inline(_corner_geometry)


def _steering_rates(x, u, q, aux):  # type: ignore[no-untyped-def]
    """``(d delta_s/dt, d^2 delta_s/dt^2)`` of the free steering system (eightdof docstring),
    stick-slip as the wheels."""
    rate_s = x[i_dsr]
    e_s = q[k_es]
    t_s = (q[k_ns] * u[j_tq] + ((aux[a_mz] - e_s * aux[a_fy])
                                + (aux[a_mz + 1] - e_s * aux[a_fy + 1]))
           - q[k_nus] * rate_s)
    cap_s = q[k_tcs]
    j_s = q[k_js]
    if j_s * abs(rate_s) >= cap_s * q[k_tb]:
        if rate_s > 0.0:
            t_s -= cap_s
        elif rate_s < 0.0:
            t_s += cap_s
        acc_s = t_s / j_s
    elif t_s > cap_s:
        acc_s = (t_s - cap_s) / j_s
    elif t_s < -cap_s:
        acc_s = (t_s + cap_s) / j_s
    elif abs(rate_s) > HELD_FLOOR:
        acc_s = -rate_s / q[k_tb] * (1.0 - abs(t_s) / cap_s)
    else:
        acc_s = 0.0
    return rate_s, acc_s


_steering_rates = _jit_inline(_steering_rates)


def _rhs_terms(x, u, q, pt, cf, cr, dx, aux):  # type: ignore[no-untyped-def]
    """``rhs`` with the parameter-only terms ``pt = _parameter_terms(q)`` given."""
    U = x[i_u]
    V = x[i_v]
    r = x[i_r]
    phi = x[i_phi]
    pr = x[i_p]
    a = q[k_a]
    b = q[k_b]
    tf = q[k_tf]
    tr = q[k_tr]
    rw = q[k_rw]
    free = q[k_sfree] > 0.0  # free steering system: its angle replaces the command
    delta_f = (x[i_ds] if free else u[j_df]) + q[k_ef] * phi
    delta_r = u[j_dr] + q[k_er] * phi
    ax_lt = x[i_ax]
    ay_lt = x[i_ay]
    aux[a_fz], aux[a_fz + 1], aux[a_fz + 2], aux[a_fz + 3] = _wheel_loads(
        phi, pr, U, ax_lt, ay_lt, pt[_P_HALF_M], q[k_hcg], pt[_P_INV_L], q[k_kf], q[k_cf],
        pt[_P_RCF], pt[_P_HUF], pt[_P_INV_TF], q[k_kr], q[k_cr], pt[_P_RCR], pt[_P_HUR],
        pt[_P_INV_TR], pt[_P_STF], pt[_P_STR], q[k_drag], q[k_liftf], q[k_liftr])
    sdf, cdf = sincos(delta_f)
    sdr, cdr = sincos(delta_r)
    rate = 0.0  # fastest slip mode, 1/s (sets the integrators' sub-steps)
    # wheel kinematics of the four wheels, then the four tires back to back (independent:
    # their latency chains overlap), then the wheel spin equations and the force sums (in
    # wheel order)
    for i in range(4):
        xw, yw, cd, sd = _corner_geometry(i, a, b, tf, tr, cdf, sdf, cdr, sdr)
        (aux[a_fz + i], aux[a_al + i], aux[a_ka + i], avx, dx[i_al0 + i],
         rate) = _corner_slip(aux[a_fz + i], U, V, r, xw, yw, cd, sd, x[i_w0 + i],
                              x[i_al0 + i], pt[_P_INV_SIGMA_F] if i < 2 else pt[_P_INV_SIGMA_R],
                              rw, q[k_vmin], q[k_kspin], rate)
        dx[i_w0 + i] = avx  # scratch until the spin equations below overwrite it
    inv_iw = pt[_P_INV_IW]
    aux[a_drive], aux[a_drive + 1], rate = _differential(
        u[j_d0], u[j_d0 + 1], x[i_w0], x[i_w0 + 1], q[k_viscf], q[k_biasf], inv_iw, rate)
    aux[a_drive + 2], aux[a_drive + 3], rate = _differential(
        u[j_d0 + 2], u[j_d0 + 3], x[i_w0 + 2], x[i_w0 + 3], q[k_viscr], q[k_biasr], inv_iw, rate)
    mu = q[k_mu]
    if HAS_FORCES4:
        _forces4(aux[a_fz:a_fz + 4], aux[a_al:a_al + 4], aux[a_ka:a_ka + 4],
                 dx[i_w0:i_w0 + 4], mu, cf, cr, aux[a_fx:a_fx + 4], aux[a_fy:a_fy + 4],
                 aux[a_mz:a_mz + 4])
    else:
        for i in range(4):
            cc = cf if i < 2 else cr
            fx, fy, mz = _tire(aux[a_fz + i], aux[a_al + i], aux[a_ka + i], dx[i_w0 + i],
                               mu, cc)
            aux[a_fx + i] = fx
            aux[a_fy + i] = fy
            aux[a_mz + i] = mz
    sum_fx = 0.0
    sum_fy = 0.0
    sum_n = 0.0
    for i in range(4):
        xw, yw, cd, sd = _corner_geometry(i, a, b, tf, tr, cdf, sdf, cdr, sdr)
        fxb, fyb, moment, dx[i_w0 + i] = _corner_spin(
            aux[a_fx + i], aux[a_fy + i], aux[a_mz + i], aux[a_fz + i], x[i_w0 + i], xw, yw,
            cd, sd, aux[a_drive + i], u[j_b0 + i], rw, q[k_iw], inv_iw, q[k_tb], q[k_frr])
        sum_fx += fxb
        sum_fy += fyb
        sum_n += moment
    if free:
        dx[i_ds], dx[i_dsr] = _steering_rates(x, u, q, aux)
        if q[k_rates] > rate:
            rate = q[k_rates]
    else:
        dx[i_ds] = 0.0
        dx[i_dsr] = 0.0
    (dx[i_u], dx[i_v], dx[i_r], dx[i_p], ax, ay, dx[i_x], dx[i_y], dx[i_ax],
     dx[i_ay]) = _body_rates(sum_fx, sum_fy, sum_n, U, V, r, phi, pr, x[i_psi], ax_lt, ay_lt,
                             q[k_m], q[k_ix], q[k_ixz], pt[_P_MSH], pt[_P_MSHG], pt[_P_KPHI],
                             pt[_P_CPHI], pt[_P_IXZ2], pt[_P_INV_M], pt[_P_INV_IZ],
                             pt[_P_INV_TLT], q[k_drag])
    dx[i_phi] = pr
    dx[i_psi] = r
    aux[a_df] = delta_f
    aux[a_dr] = delta_r
    aux[a_ax] = ax
    aux[a_ay] = ay
    aux[a_rate] = rate


def _rhs(x, u, q, cf, cr, dx, aux):  # type: ignore[no-untyped-def]
    """dx/dt into ``dx`` and per-wheel quantities into ``aux`` (see ``eightdof.Kernels``)."""
    _rhs_called(x, u, q, _parameter_terms_inline(q), cf, cr, dx, aux)


_parameter_terms_inline = _jit_inline(_parameter_terms)
# RK4 (the real-time path) gets the right-hand side inlined, ~7 % faster; ``rhs`` and Euler
# call one compiled copy (numba's inlining is what makes the first compile slow)
_rhs_inline = _jit_inline(_rhs_terms)
_rhs_called = _jit(_rhs_terms)
rhs = _jit(_rhs)


# ------------------------------------------------------------------------------ integrators
# Over flat arrays of ``n`` numbers: one state (n = N_STATE) or the lanes' states
# (n = N_STATE * LANES), the same operations in the same order for each number.

def _advance(x, k, h, out, n):  # type: ignore[no-untyped-def]
    """``out = x + h k``."""
    for j in range(n):
        out[j] = x[j] + h * k[j]


def _rk4_sum(x, k1, k2, k3, k4, sixth, out, n):  # type: ignore[no-untyped-def]
    """``out = x + (h/6)(k1 + 2 k2 + 2 k3 + k4)`` with ``sixth = h/6``."""
    for j in range(n):
        out[j] = x[j] + sixth * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])


def _accept(x, xt, n):  # type: ignore[no-untyped-def]
    """Copy ``xt`` into ``x`` if every number is finite; whether it was."""
    ok = True
    for j in range(n):
        if not math.isfinite(xt[j]):
            ok = False
    if ok:
        for j in range(n):
            x[j] = xt[j]
    return ok


def _substeps(rate, dt_over_bound):  # type: ignore[no-untyped-def]
    """Sub-steps for the slip rate ``rate`` (1/s): ``eightdof.substeps`` (1 when
    ``rate dt <= bound``; a NaN rate gives 1 and the step's finiteness check reports it)."""
    ratio = rate * dt_over_bound
    if not ratio > 1.0:
        return 1
    if not ratio < MAX_SUB:
        return MAX_SUB
    return int(math.ceil(ratio))


_advance = _jit_inline(_advance)
_rk4_sum = _jit_inline(_rk4_sum)
_accept = _jit_inline(_accept)
_substeps_inline = _jit_inline(_substeps)

#: Rows of the integrators' work array: the four RK4 stage derivatives, the stage state, the
#: state at the start of a step taken in sub-steps.
_K1, _K2, _K3, _K4, _XT, _X0 = 0, 1, 2, 3, 4, 5


def _take_input(u, u_held):  # type: ignore[no-untyped-def]
    """Check ``u`` as ``Simulator.input_vector`` does (every component finite, brake torques
    >= 0) and copy it into ``u_held``; False (nothing copied) if it fails."""
    for j in range(N_INPUT):
        if not math.isfinite(u[j]):
            return False
    for i in range(4):
        if u[j_b0 + i] < 0.0:
            return False
    for j in range(N_INPUT):
        u_held[j] = u[j]
    return True


_take_input_inline = _jit_inline(_take_input)


def _rk4_substeps(x, u, q, pt, cf, cr, dt, n_sub, work, aux):  # type: ignore[no-untyped-def]
    """One RK4 step of ``dt`` in ``n_sub`` equal sub-steps, in place (the rare path: a light or
    slowly rolling wheel); False, with ``x`` restored to the step's start, if a state became
    non-finite. Calls the compiled right-hand side (not inlined: the first compile stays as
    fast as before)."""
    xt = work[_XT]
    x0 = work[_X0]
    for j in range(N_STATE):
        x0[j] = x[j]
    h = dt / n_sub
    half = 0.5 * h
    sixth = h / 6.0
    for _ in range(n_sub):
        # the stages of rk4's step (stage s starts from x + h_s k_{s-1}, h_s = h/2, h/2, h)
        _rhs_called(x, u, q, pt, cf, cr, work[_K1], aux)
        for stage in range(1, 4):
            _advance(x, work[stage - 1], h if stage == 3 else half, xt, N_STATE)
            _rhs_called(xt, u, q, pt, cf, cr, work[stage], aux)
        _rk4_sum(x, work[_K1], work[_K2], work[_K3], work[_K4], sixth, xt, N_STATE)
        if not _accept(x, xt, N_STATE):
            for j in range(N_STATE):
                x[j] = x0[j]
            return False
    return True


def rk4(x, u, q, cf, cr, dt, n, u_held=None):  # type: ignore[no-untyped-def]
    """``n`` RK4 steps in place; returns the number of finite steps done.

    A step whose starting state has a slip mode too fast for ``dt`` (``_substeps`` > 1) is
    taken in that many equal sub-steps (:func:`_rk4_substeps`); otherwise (normal driving)
    the arithmetic is that of a plain RK4 step. With ``u_held`` (the simulator's fast path:
    one compiled call per tick), ``u`` is first checked and copied into ``u_held``
    (:func:`_take_input`); -1 and no step if it fails.
    """
    if u_held is not None:
        if not _take_input_inline(u, u_held):
            return -1
    work = np.empty((6, N_STATE))
    aux = np.empty(N_AUX)
    xt = work[_XT]
    pt = _parameter_terms_inline(q)
    half = 0.5 * dt
    sixth = dt / 6.0
    dt_over_bound = dt / RK4_BOUND
    for step in range(n):
        # one inlined right-hand side for the four stages (stage s starts from
        # x + h_s k_{s-1} with h_s = dt/2, dt/2, dt); a loop over the four, as LLVM does not
        # unroll it into four copies of the right-hand side (first compile time). Written
        # here and not as a function shared with _rk4_substeps: a step inlined from a
        # function of its own ran 10 % slower (measured)
        n_sub = 1
        for stage in range(4):
            if stage == 0:
                _rhs_inline(x, u, q, pt, cf, cr, work[_K1], aux)
                n_sub = _substeps_inline(aux[a_rate], dt_over_bound)
                if n_sub > 1:
                    break
            else:
                _advance(x, work[stage - 1], dt if stage == 3 else half, xt, N_STATE)
                _rhs_inline(xt, u, q, pt, cf, cr, work[stage], aux)
        if n_sub > 1:
            if not _rk4_substeps_called(x, u, q, pt, cf, cr, dt, n_sub, work, aux):
                return step
            continue
        _rk4_sum(x, work[_K1], work[_K2], work[_K3], work[_K4], sixth, xt, N_STATE)
        if not _accept(x, xt, N_STATE):
            return step
    return n


def _pose_from_new_rates(x, xt, h):  # type: ignore[no-untyped-def]
    """Semi-implicit Euler's second half: the pose states of ``xt`` (an explicit-Euler step
    from ``x``) taken again with the step's *new* rates, ``q_{n+1} = q_n + h g(v_{n+1}, q_n)``
    -- roll angle with the new roll rate, heading with the new yaw rate, the earth-frame
    position with the new body velocities (at the old heading), the free steering angle with
    its new rate. Every other state (velocities, wheel spins, lags) keeps its explicit step."""
    xt[i_phi] = x[i_phi] + h * xt[i_p]
    xt[i_psi] = x[i_psi] + h * xt[i_r]
    sps, cps = sincos(x[i_psi])
    xt[i_x] = x[i_x] + h * (xt[i_u] * cps - xt[i_v] * sps)
    xt[i_y] = x[i_y] + h * (xt[i_u] * sps + xt[i_v] * cps)
    xt[i_ds] = x[i_ds] + h * xt[i_dsr]


_pose_from_new_rates = _jit_inline(_pose_from_new_rates)


def _euler_substeps(x, u, q, pt, cf, cr, dt, n_sub, work, aux,  # type: ignore
                    semi=False):
    """One explicit-Euler step of ``dt`` in ``n_sub`` equal sub-steps (as
    :func:`_rk4_substeps`); with ``semi`` semi-implicit Euler's sub-steps
    (:func:`_pose_from_new_rates`)."""
    xt = work[_XT]
    x0 = work[_X0]
    for j in range(N_STATE):
        x0[j] = x[j]
    h = dt / n_sub
    for _ in range(n_sub):
        _rhs_called(x, u, q, pt, cf, cr, work[_K1], aux)
        _advance(x, work[_K1], h, xt, N_STATE)
        if semi:
            _pose_from_new_rates(x, xt, h)
        if not _accept(x, xt, N_STATE):
            for j in range(N_STATE):
                x[j] = x0[j]
            return False
    return True


def _first_order(x, u, q, cf, cr, dt, n, u_held, semi):  # type: ignore[no-untyped-def]
    """``n`` explicit-Euler steps in place, or with ``semi`` semi-implicit Euler steps (the
    rates explicitly, then the pose with the new rates, :func:`_pose_from_new_rates`), in
    sub-steps where the state needs them (bound ``EULER_RATE_BOUND``,
    :func:`_euler_substeps`); returns the number of finite steps done (the same ``u_held``
    option as :func:`rk4`)."""
    if u_held is not None:
        if not _take_input_inline(u, u_held):
            return -1
    work = np.empty((6, N_STATE))
    aux = np.empty(N_AUX)
    xt = work[_XT]
    pt = _parameter_terms_inline(q)
    dt_over_bound = dt / EULER_BOUND
    for step in range(n):
        _rhs_called(x, u, q, pt, cf, cr, work[_K1], aux)
        n_sub = _substeps_inline(aux[a_rate], dt_over_bound)
        if n_sub > 1:
            if not _euler_substeps_called(x, u, q, pt, cf, cr, dt, n_sub, work, aux, semi):
                return step
            continue
        _advance(x, work[_K1], dt, xt, N_STATE)
        if semi:
            _pose_from_new_rates(x, xt, dt)
        if not _accept(x, xt, N_STATE):
            return step
    return n


def euler(x, u, q, cf, cr, dt, n, u_held=None):  # type: ignore[no-untyped-def]
    """``n`` explicit-Euler steps in place (:func:`_first_order`)."""
    return _first_order(x, u, q, cf, cr, dt, n, u_held, False)


def semi_implicit_euler(x, u, q, cf, cr, dt, n, u_held=None):  # type: ignore
    """``n`` semi-implicit (symplectic) Euler steps in place: the rates (velocities, roll and
    yaw rate, wheel spins, lags) by an explicit step from the forces at the step's start, then
    the pose by the new rates (:func:`_pose_from_new_rates`), as the half-implicit Euler of
    multibody codes. First order, one right-hand side per step (:func:`_first_order`)."""
    return _first_order(x, u, q, cf, cr, dt, n, u_held, True)


_rk4_substeps_called = _jit(_rk4_substeps)
_euler_substeps_called = _jit(_euler_substeps)
_first_order = _jit_inline(_first_order)
rk4 = _jit(rk4)
euler = _jit(euler)
semi_implicit_euler = _jit(semi_implicit_euler)


# ------------------------------------------------------------------------------ lanes
# The study's batch kernel advances LANES points ("lanes") at once (:mod:`fourws_sim.lanes`:
# quantity ``row`` of lane ``l`` is element ``row * LANES + l`` of a flat array), in loops
# over lanes whose body has no branch and no call, so the compiler turns them into vector
# instructions: the equations above (all branch-free) with the tire's ``forces_lane``. It
# covers the fixed-control 8-DOF (no free steering system) with a tire that has
# ``forces_lane``.

#: The tire's branch-free lane function, if it has one (else the batch kernel calls the
#: scalar kernel point by point).
HAS_LANES = hasattr(_TIRE_MODULE, "forces_lane")
N_COEF = int(getattr(_TIRE_MODULE, "N_COEFFS", 0))
#: Rows of the lanes' input array: state, input, parameters, parameter terms, front and
#: rear tire coefficients.
R_X = 0
R_U = R_X + N_STATE
R_Q = R_U + N_INPUT
R_PT = R_Q + len(PARAM)
R_CF = R_PT + N_PT
R_CR = R_CF + N_COEF
N_IN = R_CR + N_COEF
#: Rows of the lanes' output array: dx/dt, the fastest slip rate, and what a tick's
#: outputs take from the right-hand side (accelerations, applied road-wheel angles).
R_DX = 0
R_RATE = N_STATE
R_AX = R_RATE + 1
R_AY = R_AX + 1
R_DF = R_AY + 1
R_DR = R_DF + 1
N_OUT = R_DR + 1


def _lanes_unavailable(*args):  # type: ignore[no-untyped-def]
    return 0.0, 0.0, 0.0


_forces_lane = _jit_inline(getattr(_TIRE_MODULE, "forces_lane", _lanes_unavailable))


def _lane_corner(IN, OUT, cbase, ln, i, xw, yw, cd, sd, fz, inv_sigma,  # type: ignore
                 U_, V, r, rw, iw, inv_iw, vmin, k_spin, mu, tb, frr, drive, rate):
    """Corner ``i`` of lane ``ln`` in :func:`_rhs_lanes`: :func:`_corner_slip`, the tire's
    ``forces_lane``, :func:`_corner_spin` with the drive torque ``drive`` its differential
    gives it; writes its slip-lag and spin derivatives and returns
    ``(fxb, fyb, moment about the CG, rate)``."""
    om = IN[(R_X + i_w0 + i) * LANES + ln]
    fz, alpha_t, kappa, _avx, d_alpha, rate = _corner_slip(
        fz, U_, V, r, xw, yw, cd, sd, om, IN[(R_X + i_al0 + i) * LANES + ln], inv_sigma, rw,
        vmin, k_spin, rate)
    OUT[(R_DX + i_al0 + i) * LANES + ln] = d_alpha
    fx, fy, mz = _forces_lane(fz, alpha_t, kappa, mu, IN, cbase, ln)
    fxb, fyb, moment, OUT[(R_DX + i_w0 + i) * LANES + ln] = _corner_spin(
        fx, fy, mz, fz, om, xw, yw, cd, sd, drive, IN[(R_U + j_b0 + i) * LANES + ln], rw, iw,
        inv_iw, tb, frr)
    return fxb, fyb, moment, rate


_lane_corner = _jit_inline(_lane_corner)


def _rhs_lanes(IN, OUT):  # type: ignore[no-untyped-def]
    """The right-hand side of the LANES lanes of ``IN`` (rows ``R_*``) into ``OUT`` (dx/dt,
    the fastest slip rate, the accelerations and applied road-wheel angles: ``rhs``'s ``aux``
    slots of the same names). Lanes have the steering system off."""
    for ln in range(LANES):
        U_ = IN[(R_X + i_u) * LANES + ln]
        V = IN[(R_X + i_v) * LANES + ln]
        r = IN[(R_X + i_r) * LANES + ln]
        phi = IN[(R_X + i_phi) * LANES + ln]
        pr = IN[(R_X + i_p) * LANES + ln]
        ax_lt = IN[(R_X + i_ax) * LANES + ln]
        ay_lt = IN[(R_X + i_ay) * LANES + ln]
        a = IN[(R_Q + k_a) * LANES + ln]
        b = IN[(R_Q + k_b) * LANES + ln]
        rw = IN[(R_Q + k_rw) * LANES + ln]
        iw = IN[(R_Q + k_iw) * LANES + ln]
        vmin = IN[(R_Q + k_vmin) * LANES + ln]
        k_spin = IN[(R_Q + k_kspin) * LANES + ln]
        mu = IN[(R_Q + k_mu) * LANES + ln]
        tb = IN[(R_Q + k_tb) * LANES + ln]
        frr = IN[(R_Q + k_frr) * LANES + ln]
        inv_iw = IN[(R_PT + _P_INV_IW) * LANES + ln]
        delta_f = IN[(R_U + j_df) * LANES + ln] + IN[(R_Q + k_ef) * LANES + ln] * phi
        delta_r = IN[(R_U + j_dr) * LANES + ln] + IN[(R_Q + k_er) * LANES + ln] * phi
        fz_fl, fz_fr, fz_rl, fz_rr = _wheel_loads(
            phi, pr, U_, ax_lt, ay_lt, IN[(R_PT + _P_HALF_M) * LANES + ln],
            IN[(R_Q + k_hcg) * LANES + ln], IN[(R_PT + _P_INV_L) * LANES + ln],
            IN[(R_Q + k_kf) * LANES + ln], IN[(R_Q + k_cf) * LANES + ln],
            IN[(R_PT + _P_RCF) * LANES + ln], IN[(R_PT + _P_HUF) * LANES + ln],
            IN[(R_PT + _P_INV_TF) * LANES + ln], IN[(R_Q + k_kr) * LANES + ln],
            IN[(R_Q + k_cr) * LANES + ln], IN[(R_PT + _P_RCR) * LANES + ln],
            IN[(R_PT + _P_HUR) * LANES + ln], IN[(R_PT + _P_INV_TR) * LANES + ln],
            IN[(R_PT + _P_STF) * LANES + ln], IN[(R_PT + _P_STR) * LANES + ln],
            IN[(R_Q + k_drag) * LANES + ln], IN[(R_Q + k_liftf) * LANES + ln],
            IN[(R_Q + k_liftr) * LANES + ln])
        sdf, cdf = sincos(delta_f)
        sdr, cdr = sincos(delta_r)
        sig_f = IN[(R_PT + _P_INV_SIGMA_F) * LANES + ln]
        sig_r = IN[(R_PT + _P_INV_SIGMA_R) * LANES + ln]
        ywf = 0.5 * IN[(R_Q + k_tf) * LANES + ln]
        ywr = 0.5 * IN[(R_Q + k_tr) * LANES + ln]
        dr_fl, dr_fr, rate = _differential(
            IN[(R_U + j_d0) * LANES + ln], IN[(R_U + j_d0 + 1) * LANES + ln],
            IN[(R_X + i_w0) * LANES + ln], IN[(R_X + i_w0 + 1) * LANES + ln],
            IN[(R_Q + k_viscf) * LANES + ln], IN[(R_Q + k_biasf) * LANES + ln], inv_iw, 0.0)
        dr_rl, dr_rr, rate = _differential(
            IN[(R_U + j_d0 + 2) * LANES + ln], IN[(R_U + j_d0 + 3) * LANES + ln],
            IN[(R_X + i_w0 + 2) * LANES + ln], IN[(R_X + i_w0 + 3) * LANES + ln],
            IN[(R_Q + k_viscr) * LANES + ln], IN[(R_Q + k_biasr) * LANES + ln], inv_iw, rate)
        # the four corners in order (FL, FR, RL, RR), summed in wheel order as ``rhs``
        fxb, fyb, mom, rate = _lane_corner(
            IN, OUT, R_CF, ln, 0, a, ywf, cdf, sdf, fz_fl, sig_f,
            U_, V, r, rw, iw, inv_iw, vmin, k_spin, mu, tb, frr, dr_fl, rate)
        sum_fx = 0.0 + fxb
        sum_fy = 0.0 + fyb
        sum_n = 0.0 + mom
        fxb, fyb, mom, rate = _lane_corner(
            IN, OUT, R_CF, ln, 1, a, -ywf, cdf, sdf, fz_fr, sig_f,
            U_, V, r, rw, iw, inv_iw, vmin, k_spin, mu, tb, frr, dr_fr, rate)
        sum_fx += fxb
        sum_fy += fyb
        sum_n += mom
        fxb, fyb, mom, rate = _lane_corner(
            IN, OUT, R_CR, ln, 2, -b, ywr, cdr, sdr, fz_rl, sig_r,
            U_, V, r, rw, iw, inv_iw, vmin, k_spin, mu, tb, frr, dr_rl, rate)
        sum_fx += fxb
        sum_fy += fyb
        sum_n += mom
        fxb, fyb, mom, rate = _lane_corner(
            IN, OUT, R_CR, ln, 3, -b, -ywr, cdr, sdr, fz_rr, sig_r,
            U_, V, r, rw, iw, inv_iw, vmin, k_spin, mu, tb, frr, dr_rr, rate)
        sum_fx += fxb
        sum_fy += fyb
        sum_n += mom
        OUT[(R_DX + i_ds) * LANES + ln] = 0.0
        OUT[(R_DX + i_dsr) * LANES + ln] = 0.0
        ud, vd, rd, pd, ax, ay, dX, dY, dax, day = _body_rates(
            sum_fx, sum_fy, sum_n, U_, V, r, phi, pr, IN[(R_X + i_psi) * LANES + ln], ax_lt,
            ay_lt, IN[(R_Q + k_m) * LANES + ln], IN[(R_Q + k_ix) * LANES + ln],
            IN[(R_Q + k_ixz) * LANES + ln], IN[(R_PT + _P_MSH) * LANES + ln],
            IN[(R_PT + _P_MSHG) * LANES + ln], IN[(R_PT + _P_KPHI) * LANES + ln],
            IN[(R_PT + _P_CPHI) * LANES + ln], IN[(R_PT + _P_IXZ2) * LANES + ln],
            IN[(R_PT + _P_INV_M) * LANES + ln], IN[(R_PT + _P_INV_IZ) * LANES + ln],
            IN[(R_PT + _P_INV_TLT) * LANES + ln], IN[(R_Q + k_drag) * LANES + ln])
        OUT[(R_DX + i_u) * LANES + ln] = ud
        OUT[(R_DX + i_v) * LANES + ln] = vd
        OUT[(R_DX + i_r) * LANES + ln] = rd
        OUT[(R_DX + i_phi) * LANES + ln] = pr
        OUT[(R_DX + i_p) * LANES + ln] = pd
        OUT[(R_DX + i_x) * LANES + ln] = dX
        OUT[(R_DX + i_y) * LANES + ln] = dY
        OUT[(R_DX + i_psi) * LANES + ln] = r
        OUT[(R_DX + i_ax) * LANES + ln] = dax
        OUT[(R_DX + i_ay) * LANES + ln] = day
        OUT[R_RATE * LANES + ln] = rate
        OUT[R_AX * LANES + ln] = ax
        OUT[R_AY * LANES + ln] = ay
        OUT[R_DF * LANES + ln] = delta_f
        OUT[R_DR * LANES + ln] = delta_r


#: One compiled copy, called (the loop over lanes inside makes the call's cost nothing).
rhs_lanes = _jit(_rhs_lanes)


def pack_lane(IN, ln, x, u, q, cf, cr):  # type: ignore[no-untyped-def]
    """Put one point's state, input, parameters (and their terms) and tire coefficients
    into lane ``l`` of ``IN``."""
    for j in range(N_STATE):
        IN[(R_X + j) * LANES + ln] = x[j]
    for j in range(N_INPUT):
        IN[(R_U + j) * LANES + ln] = u[j]
    for j in range(len(q)):
        IN[(R_Q + j) * LANES + ln] = q[j]
    terms = _parameter_terms_inline(q)
    for j in range(N_PT):
        IN[(R_PT + j) * LANES + ln] = terms[j]
    for j in range(N_COEF):
        IN[(R_CF + j) * LANES + ln] = cf[j]
        IN[(R_CR + j) * LANES + ln] = cr[j]


def _unpack_lane(IN, X, ln, xs, us, qs, cfs, crs):  # type: ignore[no-untyped-def]
    """Lane ``ln``'s state (from ``X``), input, parameters and tire coefficients (from
    ``IN``) into the scalar kernel's arrays."""
    for j in range(N_STATE):
        xs[j] = X[j * LANES + ln]
    for j in range(N_INPUT):
        us[j] = IN[(R_U + j) * LANES + ln]
    for j in range(qs.size):
        qs[j] = IN[(R_Q + j) * LANES + ln]
    for j in range(N_COEF):
        cfs[j] = IN[(R_CF + j) * LANES + ln]
        crs[j] = IN[(R_CR + j) * LANES + ln]


_unpack_lane = _jit_inline(_unpack_lane)


def rk4_lanes(X, IN, OUT, K, XT, RATE, active, dt, n_steps,  # type: ignore[no-untyped-def]
              xs, us, qs, cfs, crs, work, aux):
    """``n_steps`` RK4 steps of the active lanes (``active[ln] != 0``) of the states ``X``
    (flat, rows ``0..N_STATE``), with the inputs, parameters and coefficients in ``IN``: each
    lane gets exactly what ``rk4`` gives its state. A lane whose state needs sub-steps takes
    that step through the scalar ``_rk4_substeps`` (its column copied to ``xs``, ``us``,
    ``qs``, ``cfs``, ``crs``); a lane whose state becomes non-finite keeps its state at the
    start of that step and gets ``active[ln] = 0``. ``OUT``: the right-hand side's output;
    ``K``: (4, N_STATE * LANES) stage derivatives; ``XT``, ``RATE``: work (N_STATE * LANES),
    (LANES,); ``work``, ``aux``: the scalar path's. Returns the lanes still active."""
    n_x = N_STATE * LANES
    half = 0.5 * dt
    dt_over_bound = dt / RK4_BOUND
    for _step in range(n_steps):
        # the stages of rk4's step, of every lane at once
        for stage in range(4):
            if stage == 0:
                for i in range(n_x):
                    IN[i] = X[i]
            else:
                _advance(X, K[stage - 1], dt if stage == 3 else half, IN, n_x)
            rhs_lanes(IN, OUT)
            ks = K[stage]
            for i in range(n_x):
                ks[i] = OUT[i]
            if stage == 0:
                for ln in range(LANES):
                    RATE[ln] = OUT[R_RATE * LANES + ln]
        _rk4_sum(X, K[0], K[1], K[2], K[3], dt / 6.0, XT, n_x)
        for ln in range(LANES):
            if active[ln] == 0:
                continue
            n_sub = _substeps_inline(RATE[ln], dt_over_bound)
            if n_sub > 1:
                _unpack_lane(IN, X, ln, xs, us, qs, cfs, crs)
                pt = _parameter_terms_inline(qs)
                if _rk4_substeps_called(xs, us, qs, pt, cfs, crs, dt, n_sub, work, aux):
                    for j in range(N_STATE):
                        X[j * LANES + ln] = xs[j]
                else:
                    active[ln] = 0
                continue
            ok = True
            for j in range(N_STATE):
                if not math.isfinite(XT[j * LANES + ln]):
                    ok = False
            if ok:
                for j in range(N_STATE):
                    X[j * LANES + ln] = XT[j * LANES + ln]
            else:
                active[ln] = 0
    count = 0
    for ln in range(LANES):
        if active[ln] != 0:
            count += 1
    return count


pack_lane = _jit(pack_lane)
rk4_lanes = _jit(rk4_lanes)
