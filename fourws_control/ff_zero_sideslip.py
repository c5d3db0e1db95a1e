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
"""

from __future__ import annotations

import numpy as np

from fourws_control._vehicle import bicycle
from fourws_control.base import Law, Signal


def zero_sideslip_ratio(m: float, a: float, b: float, cf: float, cr: float,
                        speed_mps: float) -> float:
    """Ksf of eq. 4.13 with Kr = 0 (rad/rad) at ``speed_mps`` (m/s)."""
    L = a + b
    u2 = speed_mps * speed_mps
    return cf * (m * a * u2 - b * L * cr) / (cr * (m * b * u2 + a * L * cf))


class FfZeroSideslipLaw(Law):
    """Feed-forward of the front angle giving zero steady-state sideslip (2-DOF)."""

    name = "ff_zero_sideslip"
    summary = "Sano feed-forward delta_r = Ksf(U) delta_f, zero steady sideslip (eq. 4.13, Kr=0)"
    signals = (Signal.DELTA_F,)

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        p = bicycle(self.vehicle)
        k = np.zeros(len(Signal))
        k[Signal.DELTA_F] = zero_sideslip_ratio(p.m, p.a, p.b, p.cf, p.cr, speed_mps)
        return k
