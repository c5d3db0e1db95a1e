r"""ISO 17288 free-steer behaviour: metrics of the steering release (part 1) and the steering
pulse (part 2), from recorded arrays.

Steering release: the car is in a steady turn when the driver lets go of the steering wheel
at :math:`t_r`; the initial values :math:`\dot\psi_0`, :math:`\delta_{H0}`, :math:`a_{y0}` are
the means over the :data:`INITIAL_WINDOW_S` before :math:`t_r`. Of the return (each defined
here, since the standard's text is not at hand; the names follow its list of characteristic
values):

* overshoot of yaw rate and of steering-wheel angle: how far the signal swings past zero in
  the other direction, over its initial value, ``max(-x sign(x_0)) / |x_0|`` after the
  release (0 when it never crosses);
* time of the first zero crossing of the yaw rate after the release (the response time of the
  return);
* time to settle: the time after the release from which the yaw rate stays within
  :data:`SETTLE_BAND` (5 %) of :math:`|\dot\psi_0|` around its final value (the mean over the
  last :data:`FINAL_WINDOW_S` of the record);
* residual yaw rate: the yaw rate :data:`RESIDUAL_TIME_S` (3 s) after the release, and over
  :math:`\dot\psi_0` (a car whose steering friction holds the wheel off centre keeps turning);
* damping ratio and frequency of the yaw-rate oscillation about its final value, from its
  successive extrema from :data:`OSCILLATION_DELAY_S` after the release on (half-cycle
  logarithmic decrement :math:`\Lambda`, :math:`\zeta = \Lambda / \sqrt{\pi^2 + \Lambda^2}`,
  damped frequency from the extrema spacing), when it swings at least twice.

Steering pulse: after the pulse ends the car and its steering swing freely: peak yaw rate and
steering-wheel angle, the damping ratio and frequency of both oscillations, the time to settle
(within 5 % of the peak about the final value) and the residual yaw rate at 3 s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fourws_analysis.bag import MetricUnavailableError

#: Window before the release averaged as the initial steady state, s.
INITIAL_WINDOW_S = 0.5
#: Window at the end of the record averaged as the final value, s.
FINAL_WINDOW_S = 0.5
#: Settling band as a fraction of the initial (release) or peak (pulse) value.
SETTLE_BAND = 0.05
#: Time after the release (or the end of the pulse) of the residual yaw rate, s.
RESIDUAL_TIME_S = 3.0
#: Extrema smaller than this fraction of the first swing are not counted as oscillation.
EXTREMUM_FLOOR = 0.02
#: The oscillation (damping ratio, frequency) is read from this long after the release or the
#: end of the pulse, s: the steering system's fast modes (real parts of -5 1/s and faster in
#: table_8_1's linearized 8dof-free) have decayed to e^-2.5 by then and leave the slowest,
#: least damped mode, which is the one the driver feels.
OSCILLATION_DELAY_S = 0.5


@dataclass(frozen=True)
class Oscillation:
    """Damped oscillation of a signal about its final value, from its extrema.

    Attributes
    ----------
    damping_ratio : float or None
        From the mean half-cycle logarithmic decrement (None with fewer than 2 extrema).
    frequency_hz : float or None
        Damped frequency from the mean spacing of the extrema.
    extrema : int
        Extrema counted.
    """

    damping_ratio: float | None
    frequency_hz: float | None
    extrema: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"damping_ratio": self.damping_ratio, "frequency_hz": self.frequency_hz,
                "extrema": self.extrema}


def _vertex(t: np.ndarray, d: np.ndarray, i: int) -> tuple[float, float]:
    """The extremum at sample ``i`` refined by the parabola through its neighbours (time and
    value between samples: the spacing of the extrema is not quantized by the sample
    period)."""
    a, b, c = d[i - 1], d[i], d[i + 1]
    curv = a - 2.0 * b + c
    if curv == 0.0:
        return float(t[i]), float(b)
    offset = 0.5 * (a - c) / curv
    return float(t[i] + offset * (t[i + 1] - t[i])), float(b - 0.25 * (a - c) * offset)


def oscillation(t: np.ndarray, y: np.ndarray, final: float) -> Oscillation:
    """Damping ratio and damped frequency of ``y`` about ``final`` from its successive
    extrema (module docstring; each refined by a parabola through its samples); extrema below
    :data:`EXTREMUM_FLOOR` of the first are left out (the tail in which numerical noise or
    friction steps dominate)."""
    d = np.asarray(y, dtype=float) - final
    t = np.asarray(t, dtype=float)
    idx = [i for i in range(1, d.size - 1)
           if (d[i] - d[i - 1]) * (d[i + 1] - d[i]) < 0.0 or (d[i] != d[i - 1]
                                                               and d[i + 1] == d[i] == 0.0)]
    peaks = [_vertex(t, d, i) for i in idx if d[i] != 0.0]
    if peaks:
        first = abs(peaks[0][1])
        peaks = [p for p in peaks if abs(p[1]) >= EXTREMUM_FLOOR * first]
    # alternating signs only: a run of same-sign extrema keeps its largest
    swings: list[tuple[float, float]] = []
    for time_, value in peaks:
        if swings and math.copysign(1.0, value) == math.copysign(1.0, swings[-1][1]):
            if abs(value) > abs(swings[-1][1]):
                swings[-1] = (time_, value)
            continue
        swings.append((time_, value))
    if len(swings) < 2:
        return Oscillation(None, None, len(swings))
    logs = [math.log(abs(a[1]) / abs(b[1])) for a, b in zip(swings, swings[1:])]
    lam = float(np.mean(logs))
    zeta = lam / math.sqrt(math.pi ** 2 + lam * lam)
    half = float(np.mean(np.diff([s[0] for s in swings])))
    return Oscillation(zeta, 1.0 / (2.0 * half), len(swings))


def _settling_time(t: np.ndarray, y: np.ndarray, final: float, band: float,
                   t0: float) -> float | None:
    """Time after ``t0`` from which ``|y - final| <= band`` to the end (None if never)."""
    outside = np.nonzero((t >= t0) & (np.abs(y - final) > band))[0]
    if outside.size == 0:
        return 0.0
    k = int(outside[-1])
    if k + 1 >= t.size:
        return None
    return float(t[k + 1] - t0)


def _overshoot(y: np.ndarray, initial: float) -> float:
    """How far ``y`` swings past zero against ``initial``'s sign, over ``|initial|``."""
    if initial == 0.0:
        return math.nan
    return max(0.0, float(np.max(-np.sign(initial) * y))) / abs(initial)


@dataclass(frozen=True)
class ReleaseResult:
    """ISO 17288-1 steering-release metrics (module docstring). Times s, yaw rates rad/s,
    angles rad (steering wheel), fractions 1."""

    release_s: float
    yaw_rate_initial_radps: float
    steering_wheel_initial_rad: float
    lateral_accel_initial_mps2: float | None
    yaw_rate_overshoot: float
    steering_wheel_overshoot: float
    yaw_rate_zero_time_s: float | None
    settling_time_s: float | None
    residual_yaw_rate_radps: float
    residual_fraction: float
    final_yaw_rate_radps: float
    yaw: Oscillation
    steering: Oscillation

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (yaw rates in deg/s, angles in deg)."""
        return {
            "release_s": self.release_s,
            "yaw_rate_initial_degps": math.degrees(self.yaw_rate_initial_radps),
            "steering_wheel_initial_deg": math.degrees(self.steering_wheel_initial_rad),
            "lateral_accel_initial_mps2": self.lateral_accel_initial_mps2,
            "yaw_rate_overshoot": self.yaw_rate_overshoot,
            "steering_wheel_overshoot": self.steering_wheel_overshoot,
            "yaw_rate_zero_time_s": self.yaw_rate_zero_time_s,
            "settling_time_s": self.settling_time_s,
            "residual_time_s": RESIDUAL_TIME_S,
            "residual_yaw_rate_degps": math.degrees(self.residual_yaw_rate_radps),
            "residual_fraction": self.residual_fraction,
            "final_yaw_rate_degps": math.degrees(self.final_yaw_rate_radps),
            "yaw_oscillation": self.yaw.to_dict(), "steering_oscillation": self.steering.to_dict(),
        }


def release_metrics(t: np.ndarray, yaw_rate_radps: np.ndarray, steering_wheel_rad: np.ndarray,
                    release_s: float,
                    lateral_accel_mps2: np.ndarray | None = None) -> ReleaseResult:
    """ISO 17288-1 metrics of a steering-release record (module docstring).

    Raises
    ------
    MetricUnavailableError
        Less than :data:`INITIAL_WINDOW_S` before the release, or less than
        :data:`RESIDUAL_TIME_S` after it, in the record.
    """
    t = np.asarray(t, dtype=float)
    r = np.asarray(yaw_rate_radps, dtype=float)
    d = np.asarray(steering_wheel_rad, dtype=float)
    if t[0] > release_s - INITIAL_WINDOW_S or t[-1] < release_s + RESIDUAL_TIME_S:
        raise MetricUnavailableError(
            f"steering release: the record ({t[0]:.2f}-{t[-1]:.2f} s) must hold "
            f"{INITIAL_WINDOW_S:g} s before the release at {release_s:g} s and "
            f"{RESIDUAL_TIME_S:g} s after it")
    before = (t >= release_s - INITIAL_WINDOW_S) & (t < release_s)
    after = t >= release_s
    free = t >= release_s + OSCILLATION_DELAY_S
    r0, d0 = float(np.mean(r[before])), float(np.mean(d[before]))
    ay0 = None if lateral_accel_mps2 is None else float(np.mean(
        np.asarray(lateral_accel_mps2)[before]))
    final = float(np.mean(r[t >= t[-1] - FINAL_WINDOW_S]))
    ta, ra = t[after], r[after]
    cross = np.nonzero(np.sign(ra) != np.sign(r0))[0] if r0 != 0.0 else np.array([], int)
    zero_time = None
    if cross.size:
        k = int(cross[0])
        zero_time = float(ta[k] - release_s) if k == 0 else float(
            ta[k - 1] - ra[k - 1] * (ta[k] - ta[k - 1]) / (ra[k] - ra[k - 1]) - release_s)
    residual = float(np.interp(release_s + RESIDUAL_TIME_S, t, r))
    return ReleaseResult(
        release_s=float(release_s), yaw_rate_initial_radps=r0, steering_wheel_initial_rad=d0,
        lateral_accel_initial_mps2=ay0, yaw_rate_overshoot=_overshoot(ra, r0),
        steering_wheel_overshoot=_overshoot(d[after], d0), yaw_rate_zero_time_s=zero_time,
        settling_time_s=_settling_time(t, r, final, SETTLE_BAND * abs(r0), release_s),
        residual_yaw_rate_radps=residual,
        residual_fraction=residual / r0 if r0 != 0.0 else math.nan,
        final_yaw_rate_radps=final, yaw=oscillation(t[free], r[free], final),
        steering=oscillation(t[free], d[free], float(np.mean(d[t >= t[-1] - FINAL_WINDOW_S]))))


@dataclass(frozen=True)
class PulseResult:
    """ISO 17288-2 steering-pulse metrics (module docstring)."""

    pulse_end_s: float
    peak_yaw_rate_radps: float
    peak_steering_wheel_rad: float
    settling_time_s: float | None
    residual_yaw_rate_radps: float
    yaw: Oscillation
    steering: Oscillation

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (deg/s, deg)."""
        return {"pulse_end_s": self.pulse_end_s,
                "peak_yaw_rate_degps": math.degrees(self.peak_yaw_rate_radps),
                "peak_steering_wheel_deg": math.degrees(self.peak_steering_wheel_rad),
                "settling_time_s": self.settling_time_s, "residual_time_s": RESIDUAL_TIME_S,
                "residual_yaw_rate_degps": math.degrees(self.residual_yaw_rate_radps),
                "yaw_oscillation": self.yaw.to_dict(),
                "steering_oscillation": self.steering.to_dict()}


def pulse_metrics(t: np.ndarray, yaw_rate_radps: np.ndarray, steering_wheel_rad: np.ndarray,
                  pulse_start_s: float, pulse_end_s: float) -> PulseResult:
    """ISO 17288-2 metrics of a steering-pulse record (module docstring).

    Raises
    ------
    MetricUnavailableError
        Less than :data:`RESIDUAL_TIME_S` of record after the pulse.
    """
    t = np.asarray(t, dtype=float)
    r = np.asarray(yaw_rate_radps, dtype=float)
    d = np.asarray(steering_wheel_rad, dtype=float)
    if t[-1] < pulse_end_s + RESIDUAL_TIME_S:
        raise MetricUnavailableError(f"steering pulse: the record ends {t[-1] - pulse_end_s:.2f}"
                                     f" s after the pulse; needs {RESIDUAL_TIME_S:g} s")
    during = t >= pulse_start_s
    free = t >= pulse_end_s + OSCILLATION_DELAY_S
    k = int(np.argmax(np.abs(r[during])))
    peak_r = float(r[during][k])
    peak_d = float(d[during][int(np.argmax(np.abs(d[during])))])
    final = float(np.mean(r[t >= t[-1] - FINAL_WINDOW_S]))
    final_d = float(np.mean(d[t >= t[-1] - FINAL_WINDOW_S]))
    return PulseResult(
        pulse_end_s=float(pulse_end_s), peak_yaw_rate_radps=peak_r,
        peak_steering_wheel_rad=peak_d,
        settling_time_s=_settling_time(t, r, final, SETTLE_BAND * abs(peak_r), pulse_end_s),
        residual_yaw_rate_radps=float(np.interp(pulse_end_s + RESIDUAL_TIME_S, t, r)),
        yaw=oscillation(t[free], r[free], final),
        steering=oscillation(t[free], d[free], final_d))


__all__ = ["Oscillation", "PulseResult", "ReleaseResult", "oscillation", "pulse_metrics",
           "release_metrics"]
