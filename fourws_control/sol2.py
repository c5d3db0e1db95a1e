# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""``sol2``: chapter 4 Solution 2 (Table 4.2), the second root of the zero phase-lag condition.

:math:`\delta_r = K_{sf}\,\delta_f + K_r U r` with

.. math::

    K_{sf} = \frac{a C_f}{b C_r}, \qquad K_r = -\frac{a^2 C_f + b^2 C_r}{b C_r U^2}.

Re-derived: these gains cancel the :math:`\delta_f` and :math:`r` terms of the yaw equation,
leaving :math:`I_z \dot r = \frac{b C_r - a C_f}{U} V` (the paper's eq. 4.52: the yaw rate is
driven by the sideslip only). The closed loop is oscillatory and, for an oversteer vehicle
(:math:`a C_f > b C_r`, Table 4.1 data set 2), unstable at every speed - Table 4.3 lists a
positive eigenvalue for data set 2. Kept for the comparison the paper makes; not a law to drive.
"""

from __future__ import annotations

import numpy as np

from fourws_control.base import GainFunction, Law, Signal
from fourws_sim.params import Vehicle


def sol2_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """Solution 2 at ``speed_mps`` (m/s) into ``out`` (:class:`~fourws_control.base.
    GainFunction`); ``params`` = ``a, b, Cf, Cr`` (m, m, N/rad, N/rad)."""
    a, b, cf, cr = params[0], params[1], params[2], params[3]
    out[Signal.DELTA_F] = a * cf / (b * cr)
    out[Signal.YAW_RATE] = -(a * a * cf + b * b * cr) / (b * cr * speed_mps)


class Sol2Law(Law):
    """Solution 2 of Table 4.2 (yaw equation driven by sideslip only)."""

    name = "sol2"
    summary = "chapter 4 Solution 2: Ksf = aCf/(bCr), Kr = -(a^2 Cf + b^2 Cr)/(b Cr U^2)"
    signals = (Signal.DELTA_F, Signal.YAW_RATE)
    gain_functions = (sol2_gains,)

    def __init__(self, belief_vehicle: Vehicle, **options: float) -> None:
        super().__init__(belief_vehicle, **options)
        p = self.bicycle
        self._gains = GainFunction(sol2_gains, np.array([p.a, p.b, p.cf, p.cr]))

    def gain_function(self) -> GainFunction:
        """:func:`sol2_gains` of the belief vehicle."""
        return self._gains

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return self._gains.evaluate(speed_mps)
