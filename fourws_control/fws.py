# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fws``: front-wheel steering only, the rear wheels stay straight (delta_r = 0)."""

from __future__ import annotations

import numpy as np

from fourws_control.base import GainFunction, Law, Signal


def fws_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """No gain at any speed (:class:`~fourws_control.base.GainFunction`; ``out`` stays
    zero)."""


class FwsLaw(Law):
    """No rear steer: every gain is zero."""

    name = "fws"
    summary = "front-wheel steering only (delta_r = 0)"
    signals: tuple[Signal, ...] = ()
    gain_functions = (fws_gains,)
    _GAINS = GainFunction(fws_gains, np.zeros(0))

    def gain_function(self) -> GainFunction:
        """:func:`fws_gains` (no parameters)."""
        return self._GAINS

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return self._GAINS.evaluate(speed_mps)
