# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
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

from fourws_control.base import GainFunction, Law, Signal
from fourws_sim.params import Vehicle


def sol1_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """Solution 1 at ``speed_mps`` (m/s) into ``out`` (:class:`~fourws_control.base.
    GainFunction`); ``params`` = ``m, a, b, Cf, Cr`` (kg, m, m, N/rad, N/rad)."""
    m, a, b, cf, cr = params[0], params[1], params[2], params[3], params[4]
    u = speed_mps
    out[Signal.DELTA_F] = -cf / cr
    # Kr * U, the gain on r in s
    out[Signal.YAW_RATE] = (m * u * u + a * cf - b * cr) / (cr * u)


class Sol1Law(Law):
    """Solution 1 of Table 4.2 (decouples the lateral velocity)."""

    name = "sol1"
    summary = "chapter 4 Solution 1: Ksf = -Cf/Cr, Kr = (mU^2 + aCf - bCr)/(Cr U^2)"
    signals = (Signal.DELTA_F, Signal.YAW_RATE)
    gain_functions = (sol1_gains,)

    def __init__(self, belief_vehicle: Vehicle, **options: float) -> None:
        super().__init__(belief_vehicle, **options)
        p = self.bicycle
        self._gains = GainFunction(sol1_gains, np.array([p.m, p.a, p.b, p.cf, p.cr]))

    def gain_function(self) -> GainFunction:
        """:func:`sol1_gains` of the belief vehicle."""
        return self._gains

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return self._gains.evaluate(speed_mps)
