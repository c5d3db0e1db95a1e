# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Chapter 6 laws designed on the linear 3-DOF roll model (``fourws_sim.models.roll3dof``).

Signs are fourws': roll :math:`\phi` positive right side down (a left turn rolls to positive
:math:`\phi`), roll steer adds :math:`\varepsilon_i\phi` to road-wheel angle ``i``.

Zero steady-state sideslip (RWC 1, RWC 2)
-----------------------------------------
In a steady turn (:math:`\dot V = \dot r = \dot\phi = \ddot\phi = 0`) the roll equation gives
:math:`\phi = p\,U r` with :math:`p = m_s h/(K_\phi - m_s g h)`, the axle forces are
:math:`F_{yf} = m U r\,b/L`, :math:`F_{yr} = m U r\,a/L`, and with :math:`V = 0` the axle
slip equations give

.. math::

    \delta_f = r\left(\frac{a}{U} + \frac{m U b}{L C_f} - \varepsilon_f p U\right),\qquad
    \delta_r = r\left(-\frac{b}{U} + \frac{m U a}{L C_r} - \varepsilon_r p U\right).

RWC 1 (``rwc1_3dof``, eq. 6.26/6.32) is the feed-forward ratio
:math:`\delta_r = K_{sf1}\delta_f`,

.. math::

    K_{sf1}(U) = \frac{-b + (m a/(L C_r) - \varepsilon_r p)\,U^2}
                      {a + (m b/(L C_f) - \varepsilon_f p)\,U^2};

RWC 2 (``rwc2_3dof``, eq. 6.27/6.33) is yaw-rate feedback :math:`\delta_r = K_{r1} U r`,

.. math::

    K_{r1}(U) = \frac{m a}{L C_r} - \varepsilon_r p - \frac{b}{U^2}.

These are the paper's eqs. 6.32/6.33 with its roll-steer sign turned into fourws' (the paper's
roll angle is positive the other way, so its :math:`+\varepsilon_{rr}` term reads
:math:`-\varepsilon_r` here). Both gains are negative (counter-steer) at low speed and change
sign at the same speed :math:`U_0 = \sqrt{b/(m a/(L C_r) - \varepsilon_r p)}` (Figure 6.3).
Without roll (:math:`m_s h = 0`) RWC 1 is ``ff_zero_sideslip``.

RWC 4 (``rwc4_3dof``, eq. 6.35-6.39)
------------------------------------
:math:`\delta_r = K_{sf4}\delta_f + K_{r4} U r + K_\phi\phi + K_{\dot\phi}\dot\phi`, chosen so
that the lateral-velocity equation of the 3-DOF model keeps only its :math:`V` term
(:math:`\dot V = A_{VV} V`): with :math:`A_{V\cdot}`, :math:`B_{V\cdot}` the V rows of the
model's first-order matrices, each gain is :math:`-A_{Vj}/B_{V\delta_r}` (and
:math:`-B_{V\delta_f}/B_{V\delta_r}` for the feed-forward). The paper prints these as closed
forms (6.36-6.39, badly damaged in the OCR); fourws takes them from the model matrices of the
belief vehicle. The V row is exactly :math:`c_0 + c_1/U + c_2 U` per entry (the mass matrix
does not depend on U), so the law fits it once from three speeds at construction, checks it
at a fourth, and evaluates the closed form per call (no matrix algebra at 100 Hz).
"""

from __future__ import annotations

import numpy as np

from fourws_control.base import GainFunction, Law, Signal
from fourws_control.bicycle import bicycle
from fourws_sim.errors import IncompatibleError
from fourws_sim.models import roll3dof
from fourws_sim.params import GRAVITY_MPS2, Vehicle

#: Speeds (m/s) at which RWC 4 samples the model's V row to fit c0 + c1/U + c2 U, and the
#: speed at which the fit is verified.
_FIT_SPEEDS_MPS = (5.0, 20.0, 60.0)
_CHECK_SPEED_MPS = 33.0
#: Relative tolerance of that verification.
_FIT_RTOL = 1e-9


def roll_compliance(vehicle: Vehicle) -> float:
    """p = m_s h / (K_phi - m_s g h): steady roll per unit lateral acceleration, rad/(m/s^2).

    Raises
    ------
    ParameterError
        Missing ``roll`` subsystem.
    IncompatibleError
        ``K_phi <= m_s g h``: the roll mode is statically unstable (eq. 6.63), no steady turn.
    """
    vehicle.require("roll", user="the chapter-6 laws")
    rl = vehicle.roll
    msh = rl.sprung_mass_kg * rl.roll_arm_m
    net = rl.roll_stiffness_nm_per_rad - msh * GRAVITY_MPS2
    if net <= 0.0:
        raise IncompatibleError(
            f"roll.roll_stiffness_*: total roll stiffness {rl.roll_stiffness_nm_per_rad} N m/rad "
            f"does not exceed m_s g h = {msh * GRAVITY_MPS2:.1f} N m/rad; the roll mode is "
            f"unstable (eq. 6.63) in {vehicle.source or vehicle.name}")
    return msh / net


def _coefficients(vehicle: Vehicle) -> tuple[float, float, float, float]:
    """(a, b, front, rear): delta_f = r (a/U + front U), delta_r = r (-b/U + rear U) at V = 0."""
    p = bicycle(vehicle)
    pr = roll_compliance(vehicle)
    ef, er = vehicle.roll.roll_steer_front, vehicle.roll.roll_steer_rear
    return p.a, p.b, p.m * p.b / (p.L * p.cf) - ef * pr, p.m * p.a / (p.L * p.cr) - er * pr


def rwc_gains_3dof(a: float, b: float, front: float, rear: float,
                   speed_mps: float) -> tuple[float, float]:
    """(Ksf1 in rad/rad, Kr1 in s/m) of RWC 1 and RWC 2 at ``speed_mps`` (m/s) from the
    coefficients ``a, b, front, rear`` of the steady turn (module docstring)."""
    u2 = speed_mps * speed_mps
    return (-b + rear * u2) / (a + front * u2), rear - b / u2


def zero_sideslip_gains_3dof(vehicle: Vehicle, speed_mps: float) -> tuple[float, float]:
    """(Ksf1 in rad/rad, Kr1 in s/m, applied as Kr1 U r) of RWC 1 and RWC 2 at ``speed_mps``."""
    return rwc_gains_3dof(*_coefficients(vehicle), speed_mps)


def rwc1_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """RWC 1 at ``speed_mps`` (m/s) into ``out`` (:class:`~fourws_control.base.GainFunction`);
    ``params`` = ``a, b, front, rear`` (:func:`rwc_gains_3dof`)."""
    out[Signal.DELTA_F] = rwc_gains_3dof(params[0], params[1], params[2], params[3],
                                         speed_mps)[0]


def rwc2_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """RWC 2 (``Kr1 U`` on the yaw rate) at ``speed_mps`` (m/s) into ``out``; ``params`` as
    :func:`rwc1_gains`."""
    out[Signal.YAW_RATE] = rwc_gains_3dof(params[0], params[1], params[2], params[3],
                                          speed_mps)[1] * speed_mps


def rwc4_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """RWC 4 at ``speed_mps`` (m/s) into ``out``; ``params`` = ``Ksf4``, the rear-steer entry
    ``B_V,delta_r`` of the V row, then ``c0, c1, c2`` of the V-row entries of ``r``, ``phi``
    and ``phi_dot`` (each ``c0 + c1/U + c2 U``)."""
    u = speed_mps
    b_rear = params[1]
    out[Signal.DELTA_F] = params[0]
    out[Signal.YAW_RATE] = -(params[2] + params[3] / u + params[4] * u) / b_rear
    out[Signal.ROLL] = -(params[5] + params[6] / u + params[7] * u) / b_rear
    out[Signal.ROLL_RATE] = -(params[8] + params[9] / u + params[10] * u) / b_rear


def sign_change_speed_mps(vehicle: Vehicle) -> float:
    """Speed (m/s) where RWC 1 and RWC 2 gains change sign (Figure 6.3); inf if never."""
    p = bicycle(vehicle)
    rear = p.m * p.a / (p.L * p.cr) - vehicle.roll.roll_steer_rear * roll_compliance(vehicle)
    return float(np.sqrt(p.b / rear)) if rear > 0.0 else float("inf")


class Rwc1Law(Law):
    """RWC 1 of chapter 6: feed-forward giving zero steady sideslip on the 3-DOF model."""

    name = "rwc1_3dof"
    summary = "chapter 6 RWC 1: delta_r = Ksf1(U) delta_f, zero steady sideslip with roll"
    signals = (Signal.DELTA_F,)
    gain_functions = (rwc1_gains,)
    gain_helpers = (rwc_gains_3dof,)

    def __init__(self, belief_vehicle: Vehicle, **options: float) -> None:
        super().__init__(belief_vehicle, **options)
        # fails here, not at 100 Hz
        self._gains = GainFunction(rwc1_gains, np.array(_coefficients(belief_vehicle)))

    def gain_function(self) -> GainFunction:
        """:func:`rwc1_gains` of the belief vehicle."""
        return self._gains

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return self._gains.evaluate(speed_mps)


class Rwc2Law(Law):
    """RWC 2 of chapter 6: yaw-rate feedback giving zero steady sideslip on the 3-DOF model."""

    name = "rwc2_3dof"
    summary = "chapter 6 RWC 2: delta_r = Kr1(U) U r, zero steady sideslip with roll"
    signals = (Signal.YAW_RATE,)
    gain_functions = (rwc2_gains,)
    gain_helpers = (rwc_gains_3dof,)

    def __init__(self, belief_vehicle: Vehicle, **options: float) -> None:
        super().__init__(belief_vehicle, **options)
        self._gains = GainFunction(rwc2_gains, np.array(_coefficients(belief_vehicle)))

    def gain_function(self) -> GainFunction:
        """:func:`rwc2_gains` of the belief vehicle."""
        return self._gains

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return self._gains.evaluate(speed_mps)


class Rwc4Law(Law):
    """RWC 4 of chapter 6: decouples the lateral velocity of the 3-DOF model."""

    name = "rwc4_3dof"
    summary = ("chapter 6 RWC 4: delta_r = Ksf4 delta_f + Kr4 U r + Kphi phi + Kphidot phidot, "
               "V decoupled")
    signals = (Signal.DELTA_F, Signal.YAW_RATE, Signal.ROLL, Signal.ROLL_RATE)
    gain_functions = (rwc4_gains,)

    def __init__(self, belief_vehicle: Vehicle, **options: float) -> None:
        super().__init__(belief_vehicle, **options)
        S, IN = roll3dof.STATE, roll3dof.INPUT
        rows = []
        b_rows = []
        for u in _FIT_SPEEDS_MPS:
            A, B = roll3dof.matrices(belief_vehicle, u)
            rows.append(A[S.V])
            b_rows.append(B[S.V])
        # A_V(U) = c0 + c1/U + c2 U, solved entry-wise from the three samples
        basis = np.array([[1.0, 1.0 / u, u] for u in _FIT_SPEEDS_MPS])
        self._coef = np.linalg.solve(basis, np.array(rows))  # (3, n_states)
        A, B = roll3dof.matrices(belief_vehicle, _CHECK_SPEED_MPS)
        fit = self._row(_CHECK_SPEED_MPS)
        if not np.allclose(fit, A[S.V], rtol=_FIT_RTOL, atol=1e-12 * np.abs(A).max()):
            raise IncompatibleError("rwc4_3dof: the 3dof model's V row is not of the form "
                                    "c0 + c1/U + c2 U; the law's closed form does not apply")
        b_v = b_rows[0]
        if abs(b_v[IN.DELTA_R]) == 0.0:
            raise IncompatibleError("rwc4_3dof: rear steer has no direct effect on dV/dt")
        self._b_rear = float(b_v[IN.DELTA_R])
        self._ksf = -float(b_v[IN.DELTA_F]) / self._b_rear
        c = self._coef
        self._gains = GainFunction(rwc4_gains, np.array(
            [self._ksf, self._b_rear, *c[:, S.R], *c[:, S.PHI], *c[:, S.PHI_DOT]]))

    def _row(self, speed_mps: float) -> np.ndarray:
        c = self._coef
        return c[0] + c[1] / speed_mps + c[2] * speed_mps

    def gain_function(self) -> GainFunction:
        """:func:`rwc4_gains` of the belief vehicle."""
        return self._gains

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return self._gains.evaluate(speed_mps)
