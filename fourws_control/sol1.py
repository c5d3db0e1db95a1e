r"""``sol1``: chapter 4 Solution 1 (Table 4.2), zero yaw-rate/lateral-acceleration phase lag.

:math:`\delta_r = K_{sf}\,\delta_f + K_r U r` with

.. math::

    K_{sf} = -\frac{C_f}{C_r}, \qquad K_r = \frac{m U^2 + a C_f - b C_r}{C_r U^2}.

Derivation (re-done, the OCR of Table 4.2 is damaged): in
:math:`m\dot V = -\frac{C_f+C_r}{U} V + \left(-\frac{aC_f - bC_r}{U} - mU + C_r K_r U\right) r
+ (C_f + C_r K_{sf})\,\delta_f` the :math:`r` and :math:`\delta_f` terms vanish, so the lateral
velocity is decoupled, :math:`\dot V = -\frac{C_f + C_r}{mU} V` (eq. 4.49, time constant
:math:`mU/(C_f+C_r)`), and the closed loop has the real eigenvalues
:math:`-\frac{C_f+C_r}{mU}` and :math:`-\frac{a L C_f + b m U^2}{I_z U}` (eq. 4.31/4.33).
This is also RWC 3 of chapter 6 and RWC 1 of chapter 8.
"""

from __future__ import annotations

import numpy as np

from fourws_control.base import Law, Signal


class Sol1Law(Law):
    """Solution 1 of Table 4.2 (decouples the lateral velocity)."""

    name = "sol1"
    summary = "chapter 4 Solution 1: Ksf = -Cf/Cr, Kr = (mU^2 + aCf - bCr)/(Cr U^2)"
    signals = (Signal.DELTA_F, Signal.YAW_RATE)

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        p = self.bicycle
        u = speed_mps
        k = np.zeros(len(Signal))
        k[Signal.DELTA_F] = -p.cf / p.cr
        # Kr * U, the gain on r in s
        k[Signal.YAW_RATE] = (p.m * u * u + p.a * p.cf - p.b * p.cr) / (p.cr * u)
        return k
