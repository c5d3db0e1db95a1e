r"""FMVSS No. 126 (UN R13-H annex 9, UN GTR 8) metrics of the sine with dwell and the slowly
increasing steer, from recorded arrays, as the regulation defines them (S5.2, S7.11).

Data processing (S7.11): the steering-wheel angle (the road-wheel angle through the steering
ratio when only that is recorded) is filtered with a 12-pole phaseless Butterworth low-pass at
10 Hz, yaw rate and lateral acceleration at 6 Hz
(:func:`fourws_sim.maneuvers.esc.phaseless_lowpass`: 6th order forward and backward), each
zeroed with the data before the maneuver. The simulated lateral acceleration is that of the
CG in the body's yaw frame (:math:`\dot V + U r`): no roll or sensor-position correction is
needed.

Timing points:

* BOS, beginning of steer (S7.11.6): the first time the zeroed steering-wheel angle reaches
  5 deg in the direction of the first half wave, interpolated.
* COS, completion of steer (S7.11.7): the time the steering-wheel angle returns to zero after
  the second half wave (its zero crossing after the dwell), interpolated.

Metrics (S5.2): the second peak yaw rate :math:`\dot\psi_{peak}` is the first local yaw-rate
peak of the second half wave's sign after the steering wheel reverses (S7.11.8);

* lateral stability: :math:`\dot\psi(t_{COS} + 1.00)/\dot\psi_{peak} \le 35\,\%` and
  :math:`\dot\psi(t_{COS} + 1.75)/\dot\psi_{peak} \le 20\,\%` (S5.2.1, S5.2.2);
* responsiveness (runs with an amplitude of 5 A or more): the lateral displacement of the CG
  1.07 s after BOS, the double integral of the lateral acceleration from BOS (velocity and
  displacement zeroed there, S7.11.9), at least 1.83 m for a vehicle of 3500 kg or less
  (1.52 m above; S5.2.3). The vehicle's gross vehicle weight rating is not in a vehicle file:
  its mass stands for it.

A run that passes all that apply passes; a law passes when every run of its series does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import scipy.integrate

from fourws_analysis.bag import MetricUnavailableError
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers.esc import (MOTION_FILTER_HZ, STEERING_FILTER_HZ, phaseless_lowpass,
                                      reference_amplitude_rad, zeroed)

#: BOS threshold, rad (5 deg of steering-wheel angle, S7.11.6).
BOS_THRESHOLD_RAD = math.radians(5.0)
#: Yaw-rate-ratio times after COS, s, and their limits (S5.2.1, S5.2.2).
YAW_RATIO_TIMES_S = (1.00, 1.75)
YAW_RATIO_LIMITS = (0.35, 0.20)
#: Lateral displacement: time after BOS (s), the amplitude it applies from (multiples of A),
#: the limits (m) and the mass that separates them (kg), S5.2.3.
DISPLACEMENT_TIME_S = 1.07
DISPLACEMENT_FROM_FACTOR = 5.0
DISPLACEMENT_LIMIT_M = 1.83
DISPLACEMENT_LIMIT_HEAVY_M = 1.52
HEAVY_MASS_KG = 3500.0
#: A local yaw-rate peak after the reversal counts as the second peak from this fraction of
#: the largest yaw rate of that sign on (a choice: the regulation's "first local peak" read
#: so that a ripple of the filter near zero is not taken for it).
SECOND_PEAK_FLOOR = 0.1
#: Samples of the settle window zeroing needs before BOS, when the start time is unknown, s.
DEFAULT_ZERO_WINDOW_S = 0.5


def _crossing(t: np.ndarray, y: np.ndarray, level: float, start: int = 0) -> tuple[float, int]:
    """First time from index ``start`` at which ``y`` reaches ``level`` from below (linear
    interpolation) and the index at or after it; ``(nan, -1)`` if it never does."""
    above = np.nonzero(y[start:] >= level)[0]
    if above.size == 0:
        return math.nan, -1
    k = start + int(above[0])
    if k == 0 or y[k] == level:
        return float(t[k]), k
    y0, y1 = y[k - 1], y[k]
    return float(t[k - 1] + (level - y0) * (t[k] - t[k - 1]) / (y1 - y0)), k


def timing_points(t: np.ndarray, steering_wheel_rad: np.ndarray) -> tuple[float, float, float,
                                                                           float]:
    """BOS and COS of a zeroed, filtered steering-wheel angle (module docstring).

    Returns
    -------
    bos_s, cos_s : float
        Interpolated times, s.
    direction : float
        +1 when the first half wave steers left, -1 right.
    reversal_s : float
        The steering wheel's zero crossing between the half waves, s.

    Raises
    ------
    MetricUnavailableError
        The angle never reaches 5 deg, or does not come back to zero after the second half
        wave within the record.
    """
    t = np.asarray(t, dtype=float)
    swa = np.asarray(steering_wheel_rad, dtype=float)
    big = np.nonzero(np.abs(swa) >= BOS_THRESHOLD_RAD)[0]
    if big.size == 0:
        raise MetricUnavailableError("sine with dwell: the steering-wheel angle never reaches "
                                     "5 deg (no beginning of steer)")
    direction = math.copysign(1.0, float(swa[big[0]]))
    s = direction * swa  # first half wave positive
    bos, k_bos = _crossing(t, s, BOS_THRESHOLD_RAD)
    # reversal: the first crossing of zero after BOS
    rev, k_rev = _crossing(t, -s, 0.0, k_bos)
    if k_rev < 0:
        raise MetricUnavailableError("sine with dwell: the steering wheel never reverses")
    # second half wave: its extreme, then the return to zero
    k_min = k_rev + int(np.argmin(s[k_rev:]))
    cos_, k_cos = _crossing(t, s, 0.0, k_min)
    if k_cos < 0:
        raise MetricUnavailableError("sine with dwell: the steering wheel does not return to "
                                     "zero after the second half wave within the record")
    return bos, cos_, direction, rev


def second_peak_yaw_rate(t: np.ndarray, yaw_rate: np.ndarray, reversal_s: float,
                         direction: float) -> tuple[float, float]:
    """The first local yaw-rate peak of the second half wave's sign after the steering
    reversal (S7.11.8): ``(value rad/s, signed; time s)``. Only a peak above
    :data:`SECOND_PEAK_FLOOR` of the largest such yaw rate counts (the ripple of a filter or of
    noise near zero is no peak). A yaw rate that keeps growing to the end of the record (the
    car spins on) peaks at its largest value."""
    t = np.asarray(t, dtype=float)
    y = -direction * np.asarray(yaw_rate, dtype=float)  # the second half wave's sign: +
    k0 = int(np.searchsorted(t, reversal_s))
    seg = y[k0:]
    if seg.size == 0:
        raise MetricUnavailableError("sine with dwell: no record after the steering reversal")
    floor = SECOND_PEAK_FLOOR * float(np.max(seg))
    for i in range(1, seg.size - 1):
        if seg[i] > floor and seg[i] >= seg[i - 1] and seg[i] > seg[i + 1]:
            return float(-direction * seg[i]), float(t[k0 + i])
    i = int(np.argmax(seg))
    return float(-direction * seg[i]), float(t[k0 + i])


def lateral_displacement(t: np.ndarray, lateral_accel_mps2: np.ndarray,
                         bos_s: float) -> np.ndarray:
    """The regulation's lateral displacement (m) on the grid ``t``: the lateral acceleration
    integrated twice from BOS by the trapezoidal rule, velocity and displacement 0 at BOS
    (S7.11.9); NaN before BOS."""
    t = np.asarray(t, dtype=float)
    a = np.asarray(lateral_accel_mps2, dtype=float)
    k = int(np.searchsorted(t, bos_s))
    tt = np.concatenate(([bos_s], t[k:]))
    aa = np.concatenate(([float(np.interp(bos_s, t, a))], a[k:]))
    v = scipy.integrate.cumulative_trapezoid(aa, tt, initial=0.0)
    y = scipy.integrate.cumulative_trapezoid(v, tt, initial=0.0)
    out = np.full(t.size, np.nan)
    out[k:] = y[1:]
    return out


@dataclass(frozen=True)
class SineWithDwellResult:
    """FMVSS No. 126 metrics of one sine-with-dwell run (module docstring). Times are of the
    record (s); yaw rates rad/s; angles rad (steering wheel).

    Attributes
    ----------
    direction : float
        +1 first half wave left, -1 right.
    amplitude_rad : float
        The largest filtered steering-wheel angle of the run (the commanded amplitude).
    amplitude_factor, reference_amplitude_rad : float or None
        The run's amplitude as a multiple of A, and A (from the run configuration).
    bos_s, cos_s : float
    peak_yaw_rate_radps, peak_time_s : float
        The second peak yaw rate (signed) and its time.
    yaw_rate_at_radps : tuple of float
        Yaw rate at COS + 1.00 s and COS + 1.75 s.
    yaw_ratios : tuple of float
        Those over the peak.
    lateral_displacement_m : float
        At BOS + 1.07 s, in the direction of the first half wave.
    path_displacement_m : float or None
        The CG's distance from its straight path at BOS (earth-frame track, when recorded):
        what the regulation's integral approximates.
    displacement_applies : bool
        The amplitude is at least 5 A (the responsiveness criterion applies).
    displacement_limit_m : float
    yaw_ratio_pass : tuple of bool
    displacement_pass : bool or None
        None where it does not apply.
    t_rel_bos_s, yaw_rate_filtered_radps, displacement_curve_m : numpy.ndarray
        Curves for the graders' plots (time from BOS).
    """

    direction: float
    amplitude_rad: float
    amplitude_factor: float | None
    reference_amplitude_rad: float | None
    bos_s: float
    cos_s: float
    peak_yaw_rate_radps: float
    peak_time_s: float
    yaw_rate_at_radps: tuple[float, float]
    yaw_ratios: tuple[float, float]
    lateral_displacement_m: float
    path_displacement_m: float | None
    displacement_applies: bool
    displacement_limit_m: float
    yaw_ratio_pass: tuple[bool, bool]
    displacement_pass: bool | None
    t_rel_bos_s: np.ndarray = field(repr=False)
    yaw_rate_filtered_radps: np.ndarray = field(repr=False)
    displacement_curve_m: np.ndarray = field(repr=False)

    @property
    def passed(self) -> bool:
        """Every criterion that applies is met."""
        return all(self.yaw_ratio_pass) and self.displacement_pass is not False

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (no curves)."""
        return {
            "direction": "left" if self.direction > 0 else "right",
            "amplitude_deg": math.degrees(self.amplitude_rad),
            "amplitude_factor": self.amplitude_factor,
            "reference_amplitude_deg": (None if self.reference_amplitude_rad is None
                                        else math.degrees(self.reference_amplitude_rad)),
            "bos_s": self.bos_s, "cos_s": self.cos_s,
            "peak_yaw_rate_degps": math.degrees(self.peak_yaw_rate_radps),
            "peak_time_s": self.peak_time_s,
            "yaw_rate_cos_plus_1_00_degps": math.degrees(self.yaw_rate_at_radps[0]),
            "yaw_rate_cos_plus_1_75_degps": math.degrees(self.yaw_rate_at_radps[1]),
            "yaw_ratio_1_00": self.yaw_ratios[0], "yaw_ratio_1_75": self.yaw_ratios[1],
            "yaw_ratio_limits": list(YAW_RATIO_LIMITS),
            "lateral_displacement_m": self.lateral_displacement_m,
            "path_displacement_m": self.path_displacement_m,
            "displacement_applies": self.displacement_applies,
            "displacement_limit_m": self.displacement_limit_m,
            "yaw_ratio_pass": list(self.yaw_ratio_pass),
            "displacement_pass": self.displacement_pass, "passed": self.passed,
        }


def sine_with_dwell_metrics(t: np.ndarray, steering_wheel_rad: np.ndarray,
                            yaw_rate_radps: np.ndarray, lateral_accel_mps2: np.ndarray, *,
                            zero_before_s: float | None = None,
                            amplitude_factor: float | None = None,
                            reference_amplitude_rad: float | None = None,
                            vehicle_mass_kg: float | None = None,
                            x_m: np.ndarray | None = None, y_m: np.ndarray | None = None,
                            heading_rad: np.ndarray | None = None) -> SineWithDwellResult:
    """The FMVSS No. 126 metrics of one sine-with-dwell record (module docstring).

    Parameters
    ----------
    t : array
        Uniform time grid, s.
    steering_wheel_rad, yaw_rate_radps, lateral_accel_mps2 : array
        Raw channels on ``t`` (filtered and zeroed here).
    zero_before_s : float, optional
        Zero every channel with its mean before this time (the maneuver's start); default
        the first 0.5 s of the record.
    amplitude_factor, reference_amplitude_rad : float, optional
        The run's amplitude in multiples of A and A; the displacement criterion applies when
        the factor is 5 or more (with A alone: amplitude / A).
    vehicle_mass_kg : float, optional
        Selects the displacement limit (1.83 m up to 3500 kg); default the light vehicle's.
    x_m, y_m, heading_rad : array, optional
        The earth-frame track, for the geometric displacement beside the regulation's.

    Raises
    ------
    MetricUnavailableError
        No beginning or completion of steer, or the record ends before COS + 1.75 s.
    """
    t = np.asarray(t, dtype=float)
    dt = float(np.median(np.diff(t)))
    zero_s = t[0] + DEFAULT_ZERO_WINDOW_S if zero_before_s is None else zero_before_s
    swa = zeroed(phaseless_lowpass(steering_wheel_rad, dt, STEERING_FILTER_HZ), t, zero_s)
    yaw = zeroed(phaseless_lowpass(yaw_rate_radps, dt, MOTION_FILTER_HZ), t, zero_s)
    ay = zeroed(phaseless_lowpass(lateral_accel_mps2, dt, MOTION_FILTER_HZ), t, zero_s)
    bos, cos_, direction, reversal = timing_points(t, swa)
    last = cos_ + YAW_RATIO_TIMES_S[-1]
    if t[-1] < last:
        raise MetricUnavailableError(f"sine with dwell: the record ends at {t[-1]:.3f} s, "
                                     f"before COS + {YAW_RATIO_TIMES_S[-1]:g} s = {last:.3f} s")
    peak, peak_t = second_peak_yaw_rate(t, yaw, reversal, direction)
    at = tuple(float(np.interp(cos_ + dt_, t, yaw)) for dt_ in YAW_RATIO_TIMES_S)
    ratios = tuple(v / peak if peak != 0.0 else math.inf for v in at)
    curve = lateral_displacement(t, ay, bos)
    disp = direction * float(np.interp(bos + DISPLACEMENT_TIME_S, t, np.nan_to_num(curve)))
    amplitude = float(np.max(np.abs(swa)))
    factor = amplitude_factor
    if factor is None and reference_amplitude_rad:
        factor = amplitude / abs(reference_amplitude_rad)
    applies = factor is not None and factor >= DISPLACEMENT_FROM_FACTOR - 1e-9
    limit = (DISPLACEMENT_LIMIT_HEAVY_M if vehicle_mass_kg is not None
             and vehicle_mass_kg > HEAVY_MASS_KG else DISPLACEMENT_LIMIT_M)
    path = None
    if x_m is not None and y_m is not None and heading_rad is not None:
        x0, y0 = float(np.interp(bos, t, x_m)), float(np.interp(bos, t, y_m))
        psi0 = float(np.interp(bos, t, heading_rad))
        xe = float(np.interp(bos + DISPLACEMENT_TIME_S, t, x_m))
        ye = float(np.interp(bos + DISPLACEMENT_TIME_S, t, y_m))
        path = direction * (-(xe - x0) * math.sin(psi0) + (ye - y0) * math.cos(psi0))
    yaw_pass = tuple(bool(r <= lim) for r, lim in zip(ratios, YAW_RATIO_LIMITS))
    return SineWithDwellResult(
        direction=direction, amplitude_rad=amplitude, amplitude_factor=amplitude_factor,
        reference_amplitude_rad=reference_amplitude_rad, bos_s=bos, cos_s=cos_,
        peak_yaw_rate_radps=peak, peak_time_s=peak_t, yaw_rate_at_radps=at,  # type: ignore
        yaw_ratios=ratios, lateral_displacement_m=disp,  # type: ignore[arg-type]
        path_displacement_m=path, displacement_applies=applies, displacement_limit_m=limit,
        yaw_ratio_pass=yaw_pass,  # type: ignore[arg-type]
        displacement_pass=bool(disp >= limit) if applies else None,
        t_rel_bos_s=t - bos, yaw_rate_filtered_radps=yaw, displacement_curve_m=direction * curve)


@dataclass(frozen=True)
class ReferenceAmplitudeResult:
    """A of one slowly-increasing-steer record: the steering-wheel angle of 0.3 g from the
    regulation's regression (:func:`fourws_sim.maneuvers.esc.reference_amplitude_rad`), rad
    (signed: the run's direction)."""

    steering_wheel_at_reference_rad: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"steering_wheel_angle_at_0_3g_deg":
                math.degrees(self.steering_wheel_at_reference_rad)}


def reference_amplitude_metrics(t: np.ndarray, steering_wheel_rad: np.ndarray,
                                lateral_accel_mps2: np.ndarray,
                                start_s: float) -> ReferenceAmplitudeResult:
    """A of one slowly-increasing-steer record (zeroed before ``start_s``).

    Raises
    ------
    MetricUnavailableError
        The run did not reach the regression's range (0.1 g to 0.375 g).
    """
    try:
        value = reference_amplitude_rad(t, steering_wheel_rad, lateral_accel_mps2, start_s)
    except ParameterError as exc:
        raise MetricUnavailableError(f"slowly increasing steer: {exc.problem}") from None
    return ReferenceAmplitudeResult(value)


@dataclass(frozen=True)
class LawVerdict:
    """Pass/fail of one law over its sine-with-dwell runs.

    Attributes
    ----------
    law : str
    runs : int
    failed : tuple of str
        Names of the runs that fail.
    """

    law: str
    runs: int
    failed: tuple[str, ...]

    @property
    def passed(self) -> bool:
        """Every run passes (and there is at least one)."""
        return self.runs > 0 and not self.failed

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"law": self.law, "runs": self.runs, "failed": list(self.failed),
                "passed": self.passed}


def law_verdicts(results: Sequence[tuple[str, str, SineWithDwellResult]]) -> list[LawVerdict]:
    """One verdict per law from ``(law, run name, result)`` triples, in first-seen order."""
    order: list[str] = []
    runs: dict[str, int] = {}
    failed: dict[str, list[str]] = {}
    for law, name, result in results:
        if law not in runs:
            order.append(law)
            runs[law], failed[law] = 0, []
        runs[law] += 1
        if not result.passed:
            failed[law].append(name)
    return [LawVerdict(law, runs[law], tuple(failed[law])) for law in order]


__all__ = ["BOS_THRESHOLD_RAD", "DISPLACEMENT_LIMIT_M", "DISPLACEMENT_TIME_S", "LawVerdict",
           "ReferenceAmplitudeResult", "SineWithDwellResult", "YAW_RATIO_LIMITS",
           "YAW_RATIO_TIMES_S", "law_verdicts", "lateral_displacement",
           "reference_amplitude_metrics", "second_peak_yaw_rate", "sine_with_dwell_metrics",
           "timing_points"]
