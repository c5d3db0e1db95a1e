# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""ISO 4138 steady-state circular driving from quasi-steady runs.

At steady state a car turning with path curvature :math:`\kappa = r/U` at lateral
acceleration :math:`a_y` needs the front road-wheel angle

.. math::  \delta_f = L\kappa + K_{us} a_y,

(the Ackermann angle plus the understeer term, with wheelbase :math:`L` and understeer
gradient :math:`K_{us}` in rad/(m/s^2)). Fitting :math:`\delta_f - L r/U` against
:math:`a_y` therefore gives :math:`K_{us}` for the constant-speed, constant-radius and
constant-steer methods alike. A slowly ramped steer (or speed) keeps the run quasi-steady;
for a linear vehicle the ramp only shifts the curves by a constant time lag, leaving the slope
exact. Sideslip and roll gradients (:math:`d\beta/da_y`, :math:`d\phi/da_y`) are fitted the
same way over the same linear range. From :math:`K_{us}`: characteristic speed
:math:`\sqrt{L/K_{us}}` (understeer) or critical speed :math:`\sqrt{-L/K_{us}}` (oversteer).

For a four-wheel-steer car :math:`\delta_f` is what the driver commands; the gradient is the
driver's view of the whole vehicle plus controller (the rear steer is inside the plant).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fourws_analysis.bag import MetricUnavailableError

#: Linear range of lateral acceleration used for the gradients, m/s^2 (ISO 4138 reports the
#: gradients at low lateral acceleration; 4 m/s^2 is the usual upper end of the linear range).
LINEAR_RANGE_MPS2 = 4.0
#: Smallest range of |a_y| the fit must cover, m/s^2.
MIN_SPAN_MPS2 = 0.5
#: Speed below which samples are ignored (curvature r/U ill-defined), m/s.
MIN_SPEED_MPS = 1.0


@dataclass
class SteadyStateHandling:
    """Gradients of a steady-state handling run (per m/s^2 of lateral acceleration).

    Attributes
    ----------
    understeer_gradient_rad_per_mps2 : float
        K_us, rad/(m/s^2); > 0 understeer.
    steer_gradient_rad_per_mps2 : float
        d(delta_f)/d(a_y), rad/(m/s^2) (includes the Ackermann part at constant speed).
    steering_wheel_gradient_rad_per_mps2 : float or None
        d(delta_H)/d(a_y), rad/(m/s^2): ISO 4138's steering-wheel angle gradient (N times the
        steer gradient for a steering ratio N), when the steering-wheel angle was given.
    sideslip_gradient_rad_per_mps2, roll_gradient_rad_per_mps2 : float or None
    characteristic_speed_mps, critical_speed_mps : float or None
    ay_range_mps2 : tuple of float
        Range of a_y fitted.
    curves : dict of str to ndarray
        ``ay_mps2``, ``steer_rad``, ``sideslip_rad``, ``roll_rad`` of the fitted samples.
    """

    understeer_gradient_rad_per_mps2: float
    steer_gradient_rad_per_mps2: float
    sideslip_gradient_rad_per_mps2: float | None
    roll_gradient_rad_per_mps2: float | None
    characteristic_speed_mps: float | None
    critical_speed_mps: float | None
    ay_range_mps2: tuple[float, float]
    curves: dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    notes: list[str] = field(default_factory=list)
    steering_wheel_gradient_rad_per_mps2: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (without the curves)."""
        return {k: (list(v) if isinstance(v, tuple) else v)
                for k, v in self.__dict__.items() if k != "curves"}


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    return float(np.polyfit(x, y, 1)[0])


def steady_state_handling(ay_mps2: np.ndarray, delta_f_rad: np.ndarray, yaw_rate_radps: np.ndarray,
                          speed_mps: np.ndarray, wheelbase_m: float,
                          sideslip_rad: np.ndarray | None = None,
                          roll_rad: np.ndarray | None = None,
                          linear_range_mps2: float = LINEAR_RANGE_MPS2,
                          steering_wheel_rad: np.ndarray | None = None
                          ) -> SteadyStateHandling:
    """Understeer gradient and the other ISO 4138 gradients from quasi-steady samples.

    Parameters
    ----------
    ay_mps2, delta_f_rad, yaw_rate_radps, speed_mps : ndarray
        Lateral acceleration (m/s^2), front road-wheel angle (rad), yaw rate (rad/s), forward
        speed (m/s) of the quasi-steady part of the run.
    wheelbase_m : float
        L, m.
    sideslip_rad, roll_rad : ndarray, optional
    linear_range_mps2 : float
        Samples with |a_y| above this are left out of the fits, m/s^2.
    steering_wheel_rad : ndarray, optional
        Steering-wheel angle δH, rad (for the steering-wheel angle gradient).

    Raises
    ------
    MetricUnavailableError
        If the run does not cover at least 0.5 m/s^2 of lateral acceleration within the linear
        range.
    """
    ay = np.asarray(ay_mps2, dtype=float)
    u = np.asarray(speed_mps, dtype=float)
    sel = (np.abs(ay) <= linear_range_mps2) & (u > MIN_SPEED_MPS)
    # only the first pass through the linear range: a run that goes on past the limit (spin,
    # or a ramp that turns back) must not mix post-limit samples into the fit
    over = np.nonzero(~sel)[0]
    first_in = np.nonzero(sel)[0]
    notes: list[str] = []
    if first_in.size:
        later_over = over[over > first_in[0]]
        if later_over.size:
            sel[later_over[0]:] = False
            notes.append(f"fitted up to the first exit from |a_y| <= {linear_range_mps2} m/s^2 "
                         f"(sample {later_over[0]} of {ay.size})")
    if np.count_nonzero(sel) < 10 or np.ptp(ay[sel]) < MIN_SPAN_MPS2:
        span = float(np.ptp(ay[sel])) if np.any(sel) else 0.0
        raise MetricUnavailableError(
            f"steady-state handling: lateral acceleration spans {span:.2f} m/s^2 within "
            f"|a_y| <= {linear_range_mps2} m/s^2; need >= {MIN_SPAN_MPS2} m/s^2 "
            "(a slow ramp steer or constant-radius run)")
    ay_s = ay[sel]
    delta = np.asarray(delta_f_rad, dtype=float)[sel]
    kappa = np.asarray(yaw_rate_radps, dtype=float)[sel] / u[sel]
    kus = _slope(ay_s, delta - wheelbase_m * kappa)
    steer_grad = _slope(ay_s, delta)
    curves = {"ay_mps2": ay_s, "steer_rad": delta}
    beta_g = roll_g = None
    if sideslip_rad is not None:
        curves["sideslip_rad"] = np.asarray(sideslip_rad, dtype=float)[sel]
        beta_g = _slope(ay_s, curves["sideslip_rad"])
    if roll_rad is not None and np.ptp(np.asarray(roll_rad)[sel]) > 0.0:
        curves["roll_rad"] = np.asarray(roll_rad, dtype=float)[sel]
        roll_g = _slope(ay_s, curves["roll_rad"])
    v_char = math.sqrt(wheelbase_m / kus) if kus > 0 else None
    v_crit = math.sqrt(-wheelbase_m / kus) if kus < 0 else None
    if kus == 0.0:
        notes.append("neutral steer: no characteristic or critical speed")
    hand_g = None
    if steering_wheel_rad is not None:
        hand_g = _slope(ay_s, np.asarray(steering_wheel_rad, dtype=float)[sel])
    return SteadyStateHandling(kus, steer_grad, beta_g, roll_g, v_char, v_crit,
                               (float(ay_s.min()), float(ay_s.max())), curves, notes, hand_g)
