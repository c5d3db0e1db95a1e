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

from fourws_control.base import DEFAULT_CONTROL_PERIOD_S, DEFAULT_MIN_SPEED_MPS, Law, Signal
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

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        p = self.bicycle
        k = np.zeros(len(Signal))
        if self.ksf is None:
            k[Signal.DELTA_F] = zero_sideslip_ratio(p.m, p.a, p.b, p.cf, p.cr, speed_mps)
        else:
            k[Signal.DELTA_F] = self.ksf
            k[Signal.YAW_RATE] = speed_mps * zero_sideslip_yaw_gain(
                p.m, p.a, p.b, p.cf, p.cr, self.ksf, speed_mps)
        return k
