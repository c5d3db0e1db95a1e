"""``fws``: front-wheel steering only, the rear wheels stay straight (delta_r = 0)."""

from __future__ import annotations

import numpy as np

from fourws_control.base import Law, Signal


class FwsLaw(Law):
    """No rear steer: every gain is zero."""

    name = "fws"
    summary = "front-wheel steering only (delta_r = 0)"
    signals: tuple[Signal, ...] = ()

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return np.zeros(len(Signal))
