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

from fourws_control.base import Law, Signal


class Sol2Law(Law):
    """Solution 2 of Table 4.2 (yaw equation driven by sideslip only)."""

    name = "sol2"
    summary = "chapter 4 Solution 2: Ksf = aCf/(bCr), Kr = -(a^2 Cf + b^2 Cr)/(b Cr U^2)"
    signals = (Signal.DELTA_F, Signal.YAW_RATE)

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        p = self.bicycle
        k = np.zeros(len(Signal))
        k[Signal.DELTA_F] = p.a * p.cf / (p.b * p.cr)
        k[Signal.YAW_RATE] = -(p.a * p.a * p.cf + p.b * p.b * p.cr) / (p.b * p.cr * speed_mps)
        return k
