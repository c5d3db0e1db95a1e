# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""ISO 7401 step-steer (lateral transient response) metrics from a recorded run.

Time reference ``t0``: the instant the steering input passes 50 % of its step (ISO 7401).
For a response ``y`` (yaw rate or lateral acceleration) with steady-state value ``y_ss``:

* response time -- from ``t0`` to the first time ``y`` reaches 90 % of ``y_ss``;
* peak response time -- from ``t0`` to the peak of ``y``;
* overshoot -- ``(y_peak - y_ss) / y_ss``;
* steady-state gain -- ``y_ss / delta_ss``;
* TB factor -- yaw-rate peak response time times the steady-state sideslip angle, s deg.

For a second-order response ``y = K(1 - e^{-\zeta\omega_n t}(\cos\omega_d t +
\zeta/\sqrt{1-\zeta^2}\sin\omega_d t))`` these give a peak time ``pi/omega_d`` and an overshoot
``exp(-zeta pi / sqrt(1 - zeta^2))`` (tested in ``test/test_analysis_iso.py``).

ISO 7401's step test is run at a steady lateral acceleration of
:data:`ISO_LATERAL_ACCEL_MPS2` (4 m/s^2); a step of any other size gives the same metrics at
another point of the tires' curves, not the ISO condition.

Spike rule (lateral acceleration). A car's own lateral acceleration builds up with its yaw
and sideslip, on the time scale of the yaw rate's rise (its peak response time). An
overshoot of ``a_y`` whose peak comes earlier than half that rise, and whose excursion above
the steady state is narrower (full width at half the overshoot) than half that rise, is
driven by something faster than the car's response: a steer input acting on the tires
directly (a rear-steer law's command through its actuator, or the front steer ramp). It is
flagged (:attr:`StepMetrics.spike`, with the rear-wheel motion in that window when the rear
angle is given) instead of being read as the car's damping.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fourws_analysis import units
from fourws_analysis.bag import MetricUnavailableError

#: Fraction of the steady-state response that defines the response time (ISO 7401).
RESPONSE_FRACTION = 0.9
#: Fraction of the steering step that defines the time reference t0 (ISO 7401).
STEER_REFERENCE_FRACTION = 0.5
#: Length of the window, at the end of the hold, averaged for the steady state, s.
STEADY_WINDOW_S = 1.0
#: A step smaller than this fraction of the largest |steer| in the run is not a step.
MIN_STEP_FRACTION = 0.5
#: The straight-running baseline is taken before the steer leaves its initial value by this
#: fraction of the step (noise on a recorded steer stays well below it).
BASELINE_STEER_FRACTION = 0.01
#: ISO 7401's steady lateral acceleration of the step-steer test, m/s^2.
ISO_LATERAL_ACCEL_MPS2 = 4.0
#: Spike rule (module docstring): the a_y peak time and the width of its excursion, each as a
#: fraction of the yaw rate's peak response time, below which the overshoot is a spike.
SPIKE_FRACTION_OF_YAW_RISE = 0.5
#: Rear-wheel motion within the spike, as a fraction of the front step, from which the rear
#: steer is named as its cause.
SPIKE_REAR_FRACTION = 0.1


@dataclass
class StepMetrics:
    """ISO 7401 step metrics of one response channel.

    Attributes
    ----------
    channel : str
    steady_state : float
        Steady-state response (channel unit).
    steady_state_gain : float
        Steady-state response per steady-state steer (channel unit per rad of the steer
        given to :func:`step_metrics`, the front road-wheel angle δf).
    response_time_s, peak_response_time_s : float or None
        Times from t0 in s (None if never reached).
    overshoot : float or None
        (peak - steady) / steady, fraction.
    settled : bool
        Whether the response varies less than 2 % over the steady window.
    steady_state_gain_steering_wheel : float or None
        Steady-state response per steady-state steering-wheel angle δH (channel unit per
        rad), when the steering-wheel angle was given.
    spike : str
        Non-empty when the overshoot is a spike (lateral acceleration, module docstring):
        what the spike is and its cause.
    """

    channel: str
    steady_state: float
    steady_state_gain: float
    response_time_s: float | None
    peak_response_time_s: float | None
    overshoot: float | None
    settled: bool
    notes: list[str] = field(default_factory=list)
    steady_state_gain_steering_wheel: float | None = None
    spike: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping; keys name their units (:mod:`fourws_analysis.units`)."""
        return {
            units.steady_key(self.channel): self.steady_state,
            units.gain_key(self.channel, units.ROAD_WHEEL.channel): self.steady_state_gain,
            units.gain_key(self.channel, units.STEERING_WHEEL.channel):
                self.steady_state_gain_steering_wheel,
            "response_time_s": self.response_time_s,
            "peak_response_time_s": self.peak_response_time_s,
            "overshoot_fraction": self.overshoot, "settled": self.settled,
            "overshoot_is_spike": bool(self.spike), "spike": self.spike,
            "notes": list(self.notes)}


@dataclass
class StepResult:
    """All ISO 7401 step metrics of a run.

    Attributes
    ----------
    t0_s : float
        Time reference (50 % of the steer step), s.
    steer_step : float
        Size of the steer step, rad (front road-wheel angle).
    responses : dict of str to StepMetrics
    tb_factor_s_deg : float or None
    notes : list of str
    hold_end_s : float
        End of the hold (the steady window ends here), s.
    """

    t0_s: float
    steer_step: float
    responses: dict[str, StepMetrics]
    tb_factor_s_deg: float | None
    notes: list[str] = field(default_factory=list)
    hold_end_s: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"t0_s": self.t0_s, "steer_step_rad": self.steer_step,
                "hold_end_s": self.hold_end_s,
                "tb_factor_s_deg": self.tb_factor_s_deg, "notes": list(self.notes),
                **{k: v.to_dict() for k, v in self.responses.items()}}


def find_step(time_s: np.ndarray, steer: np.ndarray) -> tuple[int, int, float, float]:
    """Locate the steering step: (start index, index where the hold ends, t0 in s, step size).

    The hold ends where the steer leaves the band of +-5 % of the step around its held value
    (or at the end of the record).

    Raises
    ------
    MetricUnavailableError
        If the steer never moves.
    """
    steer = np.asarray(steer, dtype=float)
    base = float(steer[0])
    dev = steer - base
    peak = float(np.max(np.abs(dev)))
    if peak <= 1e-9:
        raise MetricUnavailableError("step metrics: the steering input never changes")
    k_peak = int(np.argmax(np.abs(dev) >= 0.98 * peak))
    step = float(dev[k_peak:][np.argmax(np.abs(dev[k_peak:]) >= 0.98 * peak)])
    # hold: contiguous samples after reaching the step that stay within 5 % of it
    held = np.abs(dev[k_peak:] - step) <= 0.05 * abs(step)
    end = k_peak + (int(np.argmin(held)) if not np.all(held) else held.size)
    half = np.nonzero(np.abs(dev[:k_peak + 1]) >= STEER_REFERENCE_FRACTION * abs(step))[0][0]
    if half == 0:
        t0 = float(time_s[0])
    else:
        d0, d1 = abs(dev[half - 1]), abs(dev[half])
        frac = (STEER_REFERENCE_FRACTION * abs(step) - d0) / (d1 - d0)
        t0 = float(time_s[half - 1] + frac * (time_s[half] - time_s[half - 1]))
    return half, end, t0, step


def step_metrics(time_s: np.ndarray, steer: np.ndarray, responses: dict[str, np.ndarray],
                 sideslip_rad: np.ndarray | None = None,
                 steady_window_s: float = STEADY_WINDOW_S,
                 steering_wheel_rad: np.ndarray | None = None,
                 rear_wheel_rad: np.ndarray | None = None) -> StepResult:
    """ISO 7401 metrics of a step-steer run.

    Parameters
    ----------
    time_s : ndarray
        Uniform time grid, s.
    steer : ndarray
        Steering input (front road-wheel or steering-wheel angle), rad.
    responses : dict of str to ndarray
        Response channels (e.g. ``yaw_rate_radps``, ``lateral_accel_mps2``).
    sideslip_rad : ndarray, optional
        Sideslip for the TB factor.
    steady_window_s : float
        Window at the end of the hold averaged for the steady state, s.
    steering_wheel_rad : ndarray, optional
        Steering-wheel angle δH, rad: the gains per δH are computed over the same window.
    rear_wheel_rad : ndarray, optional
        Rear road-wheel angle, rad: names the rear steer as a spike's cause when it moves
        within the spike.

    Raises
    ------
    MetricUnavailableError
        If the steer has no step or the hold is shorter than twice the steady window.
    """
    t = np.asarray(time_s, dtype=float)
    _, end, t0, step = find_step(t, steer)
    hold_s = t[end - 1] - t0
    if hold_s < 2.0 * steady_window_s:
        raise MetricUnavailableError(
            f"step metrics: steer held {hold_s:.2f} s after the step; need "
            f">= {2 * steady_window_s:.1f} s to reach a steady state")
    win = (t >= t[end - 1] - steady_window_s) & (t <= t[end - 1])
    # the straight-running baseline ends where the steer starts to move, not at t0: a law
    # with a quick a_y response (direct feedthrough of the steer) has moved a_y by then, and
    # averaging the first half of the ramp into the baseline shifted its steady state by 1 %
    steer_dev = np.abs(np.asarray(steer, dtype=float) - float(np.asarray(steer)[0]))
    moving = np.nonzero(steer_dev > BASELINE_STEER_FRACTION * abs(step))[0]
    base_idx = np.arange(t.size) < (moving[0] if moving.size else 0)
    steer_ss = float(np.mean(np.asarray(steer)[win])) - float(np.asarray(steer)[0])
    hand_ss = None
    if steering_wheel_rad is not None:
        hand = np.asarray(steering_wheel_rad, dtype=float)
        hand_ss = float(np.mean(hand[win])) - float(hand[0])
    out: dict[str, StepMetrics] = {}
    curves: dict[str, tuple[np.ndarray, np.ndarray, float]] = {}
    notes: list[str] = []
    for name, y in responses.items():
        y = np.asarray(y, dtype=float)
        y0 = float(np.mean(y[base_idx])) if np.any(base_idx) else float(y[0])
        yw = y[win] - y0
        yss = float(np.mean(yw))
        settled = bool(np.ptp(yw) <= 0.02 * abs(yss)) if yss != 0.0 else False
        seg = (t >= t0) & (np.arange(t.size) < end)
        ts, ys = t[seg] - t0, (y[seg] - y0) * math.copysign(1.0, yss)
        a = abs(yss)
        m_notes: list[str] = []
        rt = _first_crossing(ts, ys, RESPONSE_FRACTION * a)
        if rt is None:
            m_notes.append(f"never reaches {RESPONSE_FRACTION:.0%} of its steady state")
        k = int(np.argmax(ys))
        if 0 < k < ys.size - 1:
            peak_t = _parabolic_peak(ts, ys, k)
            pt, over = peak_t[0], (peak_t[1] - a) / a
        else:
            pt, over = None, None
            m_notes.append("no peak before the end of the hold (overdamped)")
        if not settled:
            m_notes.append("not settled over the steady window (varies by more than 2 %)")
        out[name] = StepMetrics(name, yss, yss / steer_ss, rt, pt, over, settled, m_notes,
                                None if not hand_ss else yss / hand_ss)
        curves[name] = (ts, ys, a)
    ay, yaw_m = out.get("lateral_accel_mps2"), out.get("yaw_rate_radps")
    if ay is not None and yaw_m is not None:
        rise = yaw_m.peak_response_time_s or yaw_m.response_time_s
        ts, ys, a = curves["lateral_accel_mps2"]
        ay.spike = spike_of(ts, ys, a, ay.peak_response_time_s, ay.overshoot, rise, t0, step,
                            t, rear_wheel_rad)
    tb = None
    yaw = out.get("yaw_rate_radps")
    if sideslip_rad is not None and yaw is not None and yaw.peak_response_time_s is not None:
        beta = np.asarray(sideslip_rad, dtype=float)
        beta_0 = float(np.mean(beta[base_idx])) if np.any(base_idx) else float(beta[0])
        beta_ss = float(np.mean(beta[win])) - beta_0
        tb = yaw.peak_response_time_s * abs(math.degrees(beta_ss))
    elif sideslip_rad is not None:
        notes.append("TB factor needs a yaw-rate peak response time")
    return StepResult(t0, step, out, tb, notes, float(t[end - 1]))


def spike_of(ts: np.ndarray, ys: np.ndarray, steady: float, peak_time_s: float | None,
             overshoot: float | None, yaw_rise_s: float | None, t0_s: float, step: float,
             time_s: np.ndarray | None = None, rear_wheel_rad: np.ndarray | None = None
             ) -> str:
    """The spike rule of the module docstring for one response: ``ts`` (s from t0) and
    ``ys`` (the response less its baseline, sign of its steady state ``steady > 0``), its peak
    time and overshoot, the yaw rate's rise ``yaw_rise_s`` (s). Returns what the spike is and
    its cause, or ``""`` when the overshoot is the car's own.
    """
    if None in (peak_time_s, overshoot, yaw_rise_s) or not overshoot > 0.0 \
            or not steady > 0.0:
        return ""
    assert peak_time_s is not None and overshoot is not None and yaw_rise_s is not None
    limit = SPIKE_FRACTION_OF_YAW_RISE * yaw_rise_s
    if not peak_time_s < limit:
        return ""
    half = steady * (1.0 + 0.5 * overshoot)
    k = int(np.argmin(np.abs(ts - peak_time_s)))
    above = ys >= half
    lo = k
    while lo > 0 and above[lo - 1]:
        lo -= 1
    hi = k
    while hi < ys.size - 1 and above[hi + 1]:
        hi += 1
    width = float(ts[min(hi + 1, ts.size - 1)] - ts[max(lo - 1, 0)])
    if not width < limit:
        return ""
    text = (f"one spike {peak_time_s:.2f} s after the step, {width:.2f} s wide, both within "
            f"half the yaw rate's rise ({yaw_rise_s:.2f} s): not the car's yaw-sideslip "
            "response")
    if rear_wheel_rad is not None and time_s is not None:
        rear = np.asarray(rear_wheel_rad, dtype=float)
        window = (time_s >= t0_s - 0.5 * peak_time_s) & (time_s <= t0_s + peak_time_s + width)
        seg = rear[window] - float(rear[0])
        if seg.size and float(np.ptp(seg)) > SPIKE_REAR_FRACTION * abs(step):
            return (text + f"; cause: the rear-steer command, the rear wheels move between "
                    f"{math.degrees(float(seg.min())):+.2f} and "
                    f"{math.degrees(float(seg.max())):+.2f} deg in that time (the law's "
                    f"response to the steer step through its actuator)")
    return text + "; cause: the steer ramp itself (the tires' force follows the steer input " \
        "before the car yaws)"


def _first_crossing(t: np.ndarray, y: np.ndarray, level: float) -> float | None:
    idx = np.nonzero(y >= level)[0]
    if idx.size == 0:
        return None
    k = int(idx[0])
    if k == 0:
        return float(t[0])
    return float(t[k - 1] + (level - y[k - 1]) / (y[k] - y[k - 1]) * (t[k] - t[k - 1]))


def _parabolic_peak(t: np.ndarray, y: np.ndarray, k: int) -> tuple[float, float]:
    """Sub-sample peak (time, value) from a parabola through the three samples around k."""
    y0, y1, y2 = y[k - 1], y[k], y[k + 1]
    den = y0 - 2.0 * y1 + y2
    if den >= 0.0:
        return float(t[k]), float(y1)
    off = 0.5 * (y0 - y2) / den
    h = t[k + 1] - t[k]
    return float(t[k] + off * h), float(y1 - 0.25 * (y0 - y2) * off)
