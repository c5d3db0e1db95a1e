# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""``ff_zero_sideslip``: Sano-style feed-forward, zero steady-state sideslip (eq. 4.13, Kr = 0).

:math:`\delta_r = K_{sf}(U)\,\delta_f` with the ratio that makes the steady-state lateral
velocity of the 2-DOF model zero. From the steady state of the bicycle model with
:math:`V = 0` the two axle equations give
:math:`\delta_f = r\,(a/U + m U b/(L C_f))` and :math:`\delta_r = r\,(-b/U + m U a/(L C_r))`,
hence

.. math::

    K_{sf}(U) = \frac{C_f\,(m a U^2 - b L C_r)}{C_r\,(m b U^2 + a L C_f)},

which is the paper's eq. 4.13 with :math:`K_r = 0` (and Sano et al.'s ratio): counter-steer
(:math:`K_{sf} \to -b/a`) at low speed, same-direction steer above
:math:`U = \sqrt{b L C_r/(m a)}`, tending to :math:`C_f a / (C_r b)` at high speed.

Option ``ksf``: hold the feed-forward ratio at a given constant and add the yaw-rate feedback
:math:`\delta_r = K_{sf}\delta_f + K_r U r` that restores zero steady sideslip (eq. 4.14),

.. math::

    K_r(U) = \frac{m a}{L C_r} - \frac{b}{U^2}
             - K_{sf}\left(\frac{a}{U^2} + \frac{m b}{L C_f}\right).

This is the family whose stability section 4.1.2 analyses: the closed loop is stable only for
:math:`K_{sf} < 1` (eq. 4.17) and below the speed-dependent bound of eq. 4.16
(:func:`fourws_analysis.handling.zero_sideslip_ksf_limits`).
"""

from __future__ import annotations

import math

import numpy as np

from fourws_control.base import (DEFAULT_CONTROL_PERIOD_S, DEFAULT_MIN_SPEED_MPS,
                                 GainFunction, Law, Signal)
from fourws_sim.errors import ParameterError
from fourws_sim.params import Vehicle


def zero_sideslip_ratio(m: float, a: float, b: float, cf: float, cr: float,
                        speed_mps: float) -> float:
    """Ksf of eq. 4.13 with Kr = 0 (rad/rad) at ``speed_mps`` (m/s)."""
    L = a + b
    u2 = speed_mps * speed_mps
    return cf * (m * a * u2 - b * L * cr) / (cr * (m * b * u2 + a * L * cf))


def zero_sideslip_yaw_gain(m: float, a: float, b: float, cf: float, cr: float, ksf: float,
                           speed_mps: float) -> float:
    """Kr of eq. 4.14 (s/m, applied as Kr U r) giving zero steady sideslip for a given Ksf."""
    L = a + b
    u2 = speed_mps * speed_mps
    return m * a / (L * cr) - b / u2 - ksf * (a / u2 + m * b / (L * cf))


def zero_sideslip_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """The feed-forward ratio of eq. 4.13 at ``speed_mps`` (m/s) into ``out``
    (:class:`~fourws_control.base.GainFunction`); ``params`` = ``m, a, b, Cf, Cr``."""
    out[Signal.DELTA_F] = zero_sideslip_ratio(params[0], params[1], params[2], params[3],
                                              params[4], speed_mps)


def fixed_ratio_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """A constant ratio ``Ksf`` with the yaw-rate gain ``Kr U`` of eq. 4.14 into ``out``;
    ``params`` = ``m, a, b, Cf, Cr, Ksf``."""
    ksf = params[5]
    out[Signal.DELTA_F] = ksf
    out[Signal.YAW_RATE] = speed_mps * zero_sideslip_yaw_gain(
        params[0], params[1], params[2], params[3], params[4], ksf, speed_mps)


class FfZeroSideslipLaw(Law):
    """Feed-forward of the front angle giving zero steady-state sideslip (2-DOF).

    Parameters
    ----------
    belief_vehicle : Vehicle
        Design vehicle.
    ksf : float, optional
        Constant feed-forward ratio; then Kr(U) of eq. 4.14 is added (see module docstring).
    min_speed_mps : float
        Low-speed fade (:mod:`fourws_control.base`).
    control_period_s : float
        Loop period, s (not used: a continuous-time closed form).
    """

    name = "ff_zero_sideslip"
    summary = "Sano feed-forward delta_r = Ksf(U) delta_f, zero steady sideslip (eq. 4.13, Kr=0)"
    signals: tuple[Signal, ...] = (Signal.DELTA_F,)
    gain_functions = (zero_sideslip_gains, fixed_ratio_gains)
    gain_helpers = (zero_sideslip_ratio, zero_sideslip_yaw_gain)

    def __init__(self, belief_vehicle: Vehicle, *, ksf: float | None = None,
                 min_speed_mps: float = DEFAULT_MIN_SPEED_MPS,
                 control_period_s: float = DEFAULT_CONTROL_PERIOD_S) -> None:
        super().__init__(belief_vehicle, min_speed_mps=min_speed_mps,
                         control_period_s=control_period_s)
        self.ksf = None
        if ksf is not None:
            if isinstance(ksf, bool) or not isinstance(ksf, (int, float)) \
                    or not math.isfinite(ksf):
                raise ParameterError("ksf", f"must be a finite number, got {ksf!r}")
            self.ksf = float(ksf)
            self.signals = (Signal.DELTA_F, Signal.YAW_RATE)
        p = self.bicycle
        self._gains = (GainFunction(zero_sideslip_gains, np.array([p.m, p.a, p.b, p.cf, p.cr]))
                       if self.ksf is None else
                       GainFunction(fixed_ratio_gains,
                                    np.array([p.m, p.a, p.b, p.cf, p.cr, self.ksf])))

    def gain_function(self) -> GainFunction:
        """:func:`zero_sideslip_gains`, or :func:`fixed_ratio_gains` with option ``ksf``."""
        return self._gains

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return self._gains.evaluate(speed_mps)
