# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Validation of a simulated run against a reference: tolerance bands (``fourws validate``).

A band surrounds the reference curve :math:`(x_j, y_j)`: at each of its points an ellipse of
semi-axes

.. math::

    \varepsilon_x = a_x + b_x |x_j|, \qquad \varepsilon_y = a_y + b_y |y_j|,

and the band is the region those ellipses sweep along the curve (drawn as its edges
:math:`(x_j \mp \Delta y\, \varepsilon_x^2/D,\; y_j \pm \Delta x\, \varepsilon_y^2/D)`,
:math:`D = \sqrt{(\Delta x\, \varepsilon_y)^2 + (\Delta y\, \varepsilon_x)^2}`, with
:math:`(\Delta x, \Delta y)` the curve's direction at the point: the ellipse's points normal to
the curve). A simulated point :math:`(x, y)` is inside when its band distance

.. math::

    d = \min_j \sqrt{\left(\frac{x - x_j}{\varepsilon_{x,j}}\right)^2
                     + \left(\frac{y - y_j}{\varepsilon_{y,j}}\right)^2} \le 1,

the minimum taken over the reference polyline (densified so that its points lie a small
fraction of an ellipse apart). Each curve's result is the share of its points inside and
pass/fail against the required share.

Standards (:data:`STANDARDS`):

* ``iso19364`` -- steady-state circular driving (ISO 4138 constant-radius or slowly
  increasing steer runs): the cross-plots of ISO 19364 against lateral acceleration,
  steering-wheel angle, sideslip, roll and yaw-rate gain (yaw rate over steering-wheel angle).
  Each log's quasi-steady samples (``|da_y/dt|`` below :data:`STEADY_JERK_MPS3`, up to the
  largest ``|a_y|``, turned to the positive direction) are averaged in bins of
  :data:`BIN_WIDTH_MPS2` of ``|a_y|``; the simulation's bins are tested against the
  reference's curve, and a reference bin the simulation does not reach counts as outside.
* ``iso19365`` -- sine with dwell (FMVSS 126): the time histories of steering-wheel angle, yaw
  rate and lateral acceleration from each run's beginning of steer to 1.75 s after its
  completion, in time bands, and the regulation's metrics side by side, each within a
  tolerance (:data:`SWD_METRIC_TOLERANCES`).
* ``band`` -- any maneuver: the time histories of every channel both logs have, from the
  start of each record, in time bands.

The band numbers are parameters (:class:`Band`); their defaults and sources are in
:data:`CROSS_PLOTS`, :data:`SWD_HISTORIES` and :data:`HISTORY_BANDS`: ISO 19364 and 19365 are
not public, and the one published implementation of the ISO 19364 band (TUM FTM's
VVUQ-Python_Framework, ``src/blocks/DecisionMaking.py``, Riedmaier et al.) gives
:math:`0.1 + 0.06|a_y|` m/s^2 and :math:`5 + 0.03|\delta_H|` deg for the steering-wheel angle
cross-plot; fourws uses those for it, and states its own choice for the others.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Mapping

import numpy as np

from fourws_analysis import fmvss126
from fourws_analysis.bag import MetricUnavailableError
from fourws_analysis.measured import COLUMN_BY_NAME, MeasuredLog, json_ready
from fourws_sim.errors import FourwsError, ParameterError
from fourws_sim.maneuvers.esc import phaseless_lowpass

_DEG = 180.0 / math.pi

#: The standards ``fourws validate --standard`` takes (``auto`` picks by maneuver).
STANDARDS = ("iso19364", "iso19365", "band")
#: Maneuvers ``auto`` validates by a standard other than ``band``.
AUTO_STANDARD = {"slow_ramp_steer": "iso19364", "constant_radius": "iso19364",
                 "sine_with_dwell": "iso19365"}
#: Share of a curve that must lie inside its band (ISO 19364 asks the whole simulated curve
#: to lie in the band).
DEFAULT_REQUIRED_SHARE = 1.0


@dataclass(frozen=True)
class Band:
    """Tolerance of a curve y(x), in the curve's display units.

    Attributes
    ----------
    x_offset, x_gain, y_offset, y_gain : float
        :math:`\\varepsilon_x = a_x + b_x |x|`, :math:`\\varepsilon_y = a_y + b_y |y|`.
    source : str
        Where the numbers come from.
    """

    x_offset: float
    x_gain: float
    y_offset: float
    y_gain: float
    source: str = ""

    def eps(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Semi-axes at the points ``(x, y)``."""
        return (self.x_offset + self.x_gain * np.abs(x), self.y_offset + self.y_gain * np.abs(y))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return dict(self.__dict__)


_VVUQ = ("TUM FTM VVUQ-Python_Framework src/blocks/DecisionMaking.py (Riedmaier et al.), "
         "given there as ISO 19364's")
_X_AY = (0.1, 0.06)  # lateral acceleration tolerance of every ISO 19364 cross-plot, m/s^2


@dataclass(frozen=True)
class CrossPlot:
    """One ISO 19364 cross-plot: a channel (or the yaw-rate gain) against ``|a_y|``.

    Attributes
    ----------
    key, label, unit : str
        JSON key, words, display unit of y.
    band : Band
    channels : tuple of str
        Log channels it needs.
    value : callable
        ``(channels) -> y`` in display units, sign as the channels (turned with a_y).
    min_ay : float
        Only bins from this |a_y| on, m/s^2 (the gain is a quotient of two small numbers
        near straight running).
    """

    key: str
    label: str
    unit: str
    band: Band
    channels: tuple[str, ...]
    value: Callable[[Mapping[str, np.ndarray]], np.ndarray]
    min_ay: float = 0.0


def _gain(ch: Mapping[str, np.ndarray]) -> np.ndarray:
    swa = ch["steering_wheel_angle_rad"]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(swa) > 1e-6, ch["yaw_rate_radps"] / swa, np.nan)


#: The ISO 19364 cross-plots and their default bands.
CROSS_PLOTS: tuple[CrossPlot, ...] = (
    CrossPlot("steering_wheel_angle", "steering-wheel angle δH", "deg",
              Band(*_X_AY, 5.0, 0.03, _VVUQ), ("steering_wheel_angle_rad",),
              lambda ch: ch["steering_wheel_angle_rad"] * _DEG),
    CrossPlot("sideslip", "sideslip β", "deg",
              Band(*_X_AY, 0.3, 0.10, "fourws: twice the 0.15 deg accuracy of a GNSS/INS or "
                   "optical sideslip sensor, plus 10 % of the value"), ("sideslip_rad",),
              lambda ch: ch["sideslip_rad"] * _DEG),
    CrossPlot("roll", "roll φ", "deg",
              Band(*_X_AY, 0.2, 0.10, "fourws: four times a 0.05 deg inertial platform's "
                   "resolution, plus 10 % of the value"), ("roll_rad",),
              lambda ch: ch["roll_rad"] * _DEG),
    CrossPlot("yaw_rate_gain", "yaw-rate gain r/δH", "1/s",
              Band(*_X_AY, 0.02, 0.05, "fourws: a quotient of two measured signals: the "
                   "steering-wheel angle band's 3 % plus 2 %, and 0.02 1/s (0.02 deg/s per "
                   "deg)"), ("yaw_rate_radps", "steering_wheel_angle_rad"), _gain,
              min_ay=1.0),
)
#: Width of the |a_y| bins of the steady-state curves, m/s^2.
BIN_WIDTH_MPS2 = 0.25
#: Fewest samples of a bin.
MIN_BIN_SAMPLES = 5
#: Samples whose lateral acceleration changes faster than this (1 Hz low-pass) are not
#: quasi-steady, m/s^3: the start of steer and the speed steps of a constant-radius run are
#: left out, an ISO 4138 ramp of 5 deg/s hand-wheel (1-2 m/s^3) stays in.
STEADY_JERK_MPS3 = 3.0

#: Time bands of the generic ``band`` standard: channel -> (time tolerance s, value offset in
#: the channel's display unit, value gain). Source: fourws (50 ms: the timing of a steering
#: robot's start; an offset of a few instrument floors; 10 % of the value; the steering-wheel
#: angle's as ISO 19364's cross-plot).
HISTORY_BANDS: dict[str, tuple[float, float, float]] = {
    "steering_wheel_angle_rad": (0.05, 5.0, 0.03),
    "yaw_rate_radps": (0.05, 1.0, 0.10),
    "lateral_accel_mps2": (0.05, 0.3, 0.10),
    "sideslip_rad": (0.05, 0.3, 0.10),
    "roll_rad": (0.05, 0.2, 0.10),
    "roll_rate_radps": (0.05, 1.0, 0.10),
}
_HISTORY_SOURCE = ("fourws: 50 ms (a steering robot's timing), a few instrument floors and 10 % "
                   "of the value")
#: Sine-with-dwell time histories (ISO 19365 style), from BOS to COS + 1.75 s.
SWD_HISTORIES = ("steering_wheel_angle_rad", "yaw_rate_radps", "lateral_accel_mps2")
#: Tolerances of the FMVSS 126 metrics (fourws: a tenth of the criterion for the ratios, 10 %
#: of the peak yaw rate, 0.15 m of the 1.83 m displacement): key -> (absolute, relative).
SWD_METRIC_TOLERANCES: dict[str, tuple[float, float]] = {
    "peak_yaw_rate_degps": (1.0, 0.10),
    "yaw_ratio_1_00": (0.035, 0.0),
    "yaw_ratio_1_75": (0.02, 0.0),
    "lateral_displacement_m": (0.15, 0.0),
}


# ------------------------------------------------------------------------------ bands

def band_edges(x: np.ndarray, y: np.ndarray, band: Band) -> dict[str, np.ndarray]:
    """The band's edges at each reference point (module docstring): ``upper_x``, ``upper_y``,
    ``lower_x``, ``lower_y`` and the semi-axes ``eps_x``, ``eps_y``. The curve's direction at
    a point is the central difference of its neighbours (one-sided at the ends)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    ex, ey = band.eps(x, y)
    if x.size < 2:
        dx, dy = np.ones_like(x), np.zeros_like(y)
    else:
        dx, dy = np.gradient(x), np.gradient(y)
    d = np.sqrt((dx * ey) ** 2 + (dy * ex) ** 2)
    d = np.where(d > 0.0, d, 1.0)
    return {"eps_x": ex, "eps_y": ey,
            "upper_x": x - dy * ex ** 2 / d, "upper_y": y + dx * ey ** 2 / d,
            "lower_x": x + dy * ex ** 2 / d, "lower_y": y - dx * ey ** 2 / d}


def _densify(x: np.ndarray, y: np.ndarray, band: Band,
             spacing: float = 0.05, most: int = 64) -> tuple[np.ndarray, ...]:
    """Reference points every ``spacing`` of an ellipse along the polyline (semi-axes
    interpolated linearly between the points)."""
    ex, ey = band.eps(x, y)
    if x.size < 2:
        return x, y, ex, ey
    steps = np.maximum(np.abs(np.diff(x)) / np.minimum(ex[:-1], ex[1:]),
                       np.abs(np.diff(y)) / np.minimum(ey[:-1], ey[1:]))
    pieces = np.clip(np.ceil(steps / spacing), 1, most).astype(int)
    out: list[list[np.ndarray]] = [[], [], [], []]
    for i, k in enumerate(pieces):
        s = np.arange(k) / k
        for j, arr in enumerate((x, y, ex, ey)):
            out[j].append(arr[i] + s * (arr[i + 1] - arr[i]))
    for j, arr in enumerate((x, y, ex, ey)):
        out[j].append(arr[-1:])
    return tuple(np.concatenate(o) for o in out)


def band_distance(ref_x: np.ndarray, ref_y: np.ndarray, x: np.ndarray, y: np.ndarray,
                  band: Band) -> np.ndarray:
    """Band distance of each point ``(x, y)`` to the reference curve (module docstring):
    inside where it is at most 1; NaN for a NaN point."""
    rx, ry, ex, ey = _densify(np.asarray(ref_x, float), np.asarray(ref_y, float), band)
    order = np.argsort(rx, kind="stable")
    rx, ry, ex, ey = rx[order], ry[order], ex[order], ey[order]
    reach = float(np.max(ex)) if ex.size else 0.0
    out = np.full(np.size(x), np.nan)
    for i, (xi, yi) in enumerate(zip(np.asarray(x, float), np.asarray(y, float))):
        if not (math.isfinite(xi) and math.isfinite(yi)):
            continue
        lo = int(np.searchsorted(rx, xi - reach, side="left"))
        hi = int(np.searchsorted(rx, xi + reach, side="right"))
        if hi == lo:  # no ellipse reaches this far in x
            out[i] = math.inf
            continue
        sl = slice(lo, hi)
        d2 = ((xi - rx[sl]) / ex[sl]) ** 2 + ((yi - ry[sl]) / ey[sl]) ** 2
        out[i] = float(np.sqrt(np.min(d2)))
    return out


@dataclass
class CurveResult:
    """One curve against its band.

    Attributes
    ----------
    key, label, x_label, x_unit, y_unit : str
    band : Band
    reference_x, reference_y : ndarray
        The reference curve (display units).
    x, y : ndarray
        The simulated curve; NaN where it has no point (a reference bin it does not reach).
    distance : ndarray
        Band distance of each simulated point (inf or NaN: outside).
    required_share : float
    """

    key: str
    label: str
    x_label: str
    x_unit: str
    y_unit: str
    band: Band
    reference_x: np.ndarray
    reference_y: np.ndarray
    x: np.ndarray
    y: np.ndarray
    distance: np.ndarray
    required_share: float = DEFAULT_REQUIRED_SHARE

    @property
    def inside(self) -> np.ndarray:
        """Points inside the band."""
        return np.nan_to_num(self.distance, nan=math.inf) <= 1.0

    @property
    def share_inside(self) -> float:
        """Share of the simulated points inside the band."""
        return float(np.mean(self.inside)) if self.distance.size else 0.0

    @property
    def passed(self) -> bool:
        """At least the required share inside."""
        return self.share_inside >= self.required_share - 1e-12

    def edges(self) -> dict[str, np.ndarray]:
        """:func:`band_edges` of the reference curve."""
        return band_edges(self.reference_x, self.reference_y, self.band)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping: the band, the reference with its edges, the simulated points
        with their distances, the share and the verdict."""
        edges = self.edges()
        return {
            "label": self.label, "x": self.x_label, "x_unit": self.x_unit,
            "y_unit": self.y_unit, "band": self.band.to_dict(),
            "reference": {"x": self.reference_x.tolist(), "y": self.reference_y.tolist(),
                          **{k: v.tolist() for k, v in edges.items()}},
            "simulation": {"x": self.x.tolist(), "y": self.y.tolist(),
                           "distance": self.distance.tolist(),
                           "inside": self.inside.tolist()},
            "share_inside": self.share_inside, "required_share": self.required_share,
            "passed": self.passed}


@dataclass
class MetricComparison:
    """One scalar metric of both runs (sine with dwell).

    Attributes
    ----------
    key, unit : str
    simulation, reference : float
    tolerance : float
        Allowed |simulation - reference| (absolute + relative of the reference).
    """

    key: str
    unit: str
    simulation: float
    reference: float
    tolerance: float

    @property
    def passed(self) -> bool:
        """Within the tolerance."""
        return abs(self.simulation - self.reference) <= self.tolerance

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"unit": self.unit, "simulation": self.simulation, "reference": self.reference,
                "difference": self.simulation - self.reference, "tolerance": self.tolerance,
                "passed": self.passed}


@dataclass
class ValidationResult:
    """``fourws validate``'s answer.

    Attributes
    ----------
    standard : str
    simulation, reference : MeasuredLog
    curves : list of CurveResult
    metrics : list of MetricComparison
        Sine with dwell: FMVSS 126 metrics side by side.
    verdicts : dict of str to bool or None
        FMVSS 126 pass/fail of each run (sine with dwell).
    skipped : dict of str to str
        Curves that could not be drawn and why.
    notes : list of str
    """

    standard: str
    simulation: MeasuredLog
    reference: MeasuredLog
    curves: list[CurveResult] = field(default_factory=list)
    metrics: list[MetricComparison] = field(default_factory=list)
    verdicts: dict[str, bool | None] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        """Every curve and metric passes (and there is at least one curve)."""
        return bool(self.curves) and all(c.passed for c in self.curves) \
            and all(m.passed for m in self.metrics)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (``validation.json``)."""
        return json_ready({
            "standard": self.standard, "passed": self.passed,
            "simulation": {"name": self.simulation.name, "source": self.simulation.source},
            "reference": {"name": self.reference.name, "source": self.reference.source},
            "curves": {c.key: c.to_dict() for c in self.curves},
            "metrics": {m.key: m.to_dict() for m in self.metrics},
            "fmvss126_passed": dict(self.verdicts),
            "skipped": dict(self.skipped), "notes": list(self.notes)})


# ------------------------------------------------------------------------------ iso19364

def steady_samples(log: MeasuredLog) -> np.ndarray:
    """Indices of the quasi-steady samples up to the largest |a_y| (module docstring)."""
    ay = phaseless_lowpass(log.channels["lateral_accel_mps2"], log.dt_s, 1.0)
    jerk = np.gradient(ay, log.dt_s)
    peak = int(np.argmax(np.abs(ay)))
    idx = np.arange(peak + 1)
    return idx[np.abs(jerk[:peak + 1]) <= STEADY_JERK_MPS3]


def binned_curve(log: MeasuredLog, plot: CrossPlot, width: float = BIN_WIDTH_MPS2
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bin indices, mean |a_y| and mean y per bin of ``log``'s quasi-steady samples (turned to
    the positive direction of its turn)."""
    idx = steady_samples(log)
    ay = log.channels["lateral_accel_mps2"][idx]
    sign = 1.0 if float(np.mean(ay)) >= 0.0 else -1.0
    ch = {k: v[idx] for k, v in log.channels.items()}
    value = plot.value(ch)
    # the gain is a quotient: its sign does not turn with the direction
    y = value if plot.key == "yaw_rate_gain" else sign * value
    x = sign * ay
    k = np.floor(x / width).astype(int)
    keep = (x >= plot.min_ay) & np.isfinite(y)
    bins, xs, ys = [], [], []
    for b in np.unique(k[keep]):
        sel = keep & (k == b)
        if np.count_nonzero(sel) >= MIN_BIN_SAMPLES:
            bins.append(int(b))
            xs.append(float(np.mean(x[sel])))
            ys.append(float(np.mean(y[sel])))
    return np.array(bins, dtype=int), np.array(xs), np.array(ys)


def cross_plot(sim: MeasuredLog, ref: MeasuredLog, plot: CrossPlot,
               required_share: float = DEFAULT_REQUIRED_SHARE,
               width: float = BIN_WIDTH_MPS2) -> CurveResult:
    """One ISO 19364 cross-plot of ``sim`` against ``ref`` (module docstring).

    Raises
    ------
    MetricUnavailableError
        A log lacks a channel, or the reference has no quasi-steady bin.
    """
    for log in (sim, ref):
        missing = [c for c in plot.channels if not log.has(c)]
        if missing:
            raise MetricUnavailableError(f"{log.name} has no {', '.join(missing)}")
    rb, rx, ry = binned_curve(ref, plot, width)
    if rb.size == 0:
        raise MetricUnavailableError(f"{ref.name}: no quasi-steady lateral acceleration "
                                     f"above {plot.min_ay:g} m/s^2 (a steady-state circular "
                                     "run is needed)")
    sb, sx, sy = binned_curve(sim, plot, width)
    pos = {b: i for i, b in enumerate(sb)}
    x = np.array([sx[pos[b]] if b in pos else math.nan for b in rb])
    y = np.array([sy[pos[b]] if b in pos else math.nan for b in rb])
    return CurveResult(plot.key, plot.label, "lateral acceleration |a_y|", "m/s²", plot.unit,
                       plot.band, rx, ry, x, y, band_distance(rx, ry, x, y, plot.band),
                       required_share)


# ------------------------------------------------------------------------------ histories

def history_curve(sim: MeasuredLog, ref: MeasuredLog, channel: str, start_sim: float,
                  start_ref: float, span_s: float, band: Band, label: str, scale: float,
                  unit: str, required_share: float, x_label: str = "time") -> CurveResult:
    """A channel's time history of ``sim`` against ``ref`` over ``span_s`` from their start
    times (the simulation resampled onto the reference's samples); ``x_label`` says from
    what the time counts."""
    tr = ref.time_s - start_ref
    ts = sim.time_s - start_sim
    sel = (tr >= 0.0) & (tr <= span_s)
    rx = tr[sel]
    ry = ref.channels[channel][sel] * scale
    inside = (rx >= ts[0]) & (rx <= ts[-1])
    y = np.where(inside, np.interp(rx, ts, sim.channels[channel] * scale), math.nan)
    return CurveResult(channel, label, x_label, "s", unit, band, rx, ry, rx.copy(), y,
                       band_distance(rx, ry, rx, y, band), required_share)


def _history_band(channel: str) -> tuple[str, float, str, Band]:
    t_tol, offset, gain = HISTORY_BANDS[channel]
    col = COLUMN_BY_NAME[channel]
    return col.label, col.display[0], col.display[1], Band(t_tol, 0.0, offset, gain,
                                                           _HISTORY_SOURCE)


def _swd_metrics(log: MeasuredLog) -> fmvss126.SineWithDwellResult:
    man = log.config.get("maneuver") if isinstance(log.config.get("maneuver"), Mapping) else {}
    start = man.get("start_s") if isinstance(man, Mapping) else None
    return fmvss126.sine_with_dwell_metrics(
        log.time_s, log.channels["steering_wheel_angle_rad"], log.channels["yaw_rate_radps"],
        log.channels["lateral_accel_mps2"],
        zero_before_s=(log.time_s[0] + float(start)) if isinstance(start, (int, float))
        else None)


# ------------------------------------------------------------------------------ entry

#: Curves whose band ``--band`` may set: the cross-plots and the time-history channels.
BAND_KEYS: tuple[str, ...] = (*(p.key for p in CROSS_PLOTS), *HISTORY_BANDS)


def parse_band(text: str) -> tuple[str, Band]:
    """``CURVE=X_OFFSET,X_GAIN,Y_OFFSET,Y_GAIN`` (``fourws validate --band``) as the curve's
    key and its band (display units of the curve; time histories: x is the time, s).

    Raises
    ------
    ParameterError
        An unknown curve, not four numbers, a negative number or a band of zero width.
    """
    key, _, numbers = text.partition("=")
    key = key.strip()
    if key not in BAND_KEYS:
        raise ParameterError("--band", f"unknown curve {key!r} (valid: {', '.join(BAND_KEYS)})")
    try:
        values = [float(v) for v in numbers.split(",")]
    except ValueError:
        values = []
    if len(values) != 4 or not all(math.isfinite(v) and v >= 0.0 for v in values):
        raise ParameterError("--band", f"{text!r}: give {key}=X_OFFSET,X_GAIN,Y_OFFSET,Y_GAIN, "
                             "four numbers >= 0")
    if values[0] == 0.0 or values[2] == 0.0:
        raise ParameterError("--band", f"{text!r}: the offsets must be > 0 (a band of zero "
                             "width at zero)")
    return key, Band(*values, source=f"--band {text}")


def choose_standard(standard: str, sim: MeasuredLog, ref: MeasuredLog) -> str:
    """``standard``, or for ``auto`` the one the runs' maneuver asks for (:data:`AUTO_STANDARD`,
    else ``band``).

    Raises
    ------
    ParameterError
        An unknown standard.
    """
    if standard == "auto":
        man = sim.maneuver or ref.maneuver
        return AUTO_STANDARD.get(man, "band")
    if standard not in STANDARDS:
        raise ParameterError("--standard", f"unknown standard {standard!r} (valid: auto, "
                             f"{', '.join(STANDARDS)})")
    return standard


def validate(sim: MeasuredLog, ref: MeasuredLog, standard: str = "auto",
             required_share: float = DEFAULT_REQUIRED_SHARE,
             bands: Mapping[str, Band] | None = None) -> ValidationResult:
    """Validate ``sim`` against ``ref`` by ``standard`` (module docstring).

    Parameters
    ----------
    sim, ref : MeasuredLog
    standard : str
        ``auto`` or one of :data:`STANDARDS`.
    required_share : float
        Share of each curve that must lie in its band, 0-1.
    bands : mapping, optional
        Bands replacing the defaults, by curve key (``steering_wheel_angle``, ...,
        ``yaw_rate_radps`` for a time history).

    Raises
    ------
    ParameterError
        An unknown standard, a required share outside [0, 1].
    """
    if not (isinstance(required_share, (int, float)) and 0.0 <= required_share <= 1.0):
        raise ParameterError("--min-share", f"must be within [0, 1], got {required_share!r}")
    kind = choose_standard(standard, sim, ref)
    result = ValidationResult(kind, sim, ref)
    if standard == "auto":
        result.notes.append(f"standard {kind} chosen for the maneuver "
                            f"{sim.maneuver or ref.maneuver or 'of neither log (unknown)'}")
    over = dict(bands or {})
    if kind == "iso19364":
        for plot in CROSS_PLOTS:
            p = replace(plot, band=over.get(plot.key, plot.band))
            try:
                result.curves.append(cross_plot(sim, ref, p, required_share))
            except MetricUnavailableError as exc:
                result.skipped[plot.key] = str(exc)
    elif kind == "iso19365":
        _sine_with_dwell(result, over, required_share)
    else:
        span = min(sim.duration_s, ref.duration_s)
        for channel in HISTORY_BANDS:
            if not (sim.has(channel) and ref.has(channel)):
                result.skipped[channel] = "not in both logs"
                continue
            label, scale, unit, band = _history_band(channel)
            result.curves.append(history_curve(sim, ref, channel, sim.time_s[0],
                                               ref.time_s[0], span, over.get(channel, band),
                                               label, scale, unit, required_share,
                                               "time from the start of the record"))
    return result


def _sine_with_dwell(result: ValidationResult, over: Mapping[str, Band],
                     required_share: float) -> None:
    try:
        ms, mr = _swd_metrics(result.simulation), _swd_metrics(result.reference)
    except FourwsError as exc:
        result.skipped["sine_with_dwell"] = str(exc)
        return
    span = (mr.cos_s - mr.bos_s) + fmvss126.YAW_RATIO_TIMES_S[-1]
    for channel in SWD_HISTORIES:
        label, scale, unit, band = _history_band(channel)
        result.curves.append(history_curve(result.simulation, result.reference, channel,
                                           ms.bos_s, mr.bos_s, span, over.get(channel, band),
                                           label, scale, unit, required_share,
                                           "time from the beginning of steer"))
    ds, dr = ms.to_dict(), mr.to_dict()
    units = {"peak_yaw_rate_degps": "deg/s", "yaw_ratio_1_00": "–", "yaw_ratio_1_75": "–",
             "lateral_displacement_m": "m"}
    for key, (absolute, relative) in SWD_METRIC_TOLERANCES.items():
        s, r = float(ds[key]), float(dr[key])
        result.metrics.append(MetricComparison(key, units[key], s, r,
                                               absolute + relative * abs(r)))
    result.verdicts = {"simulation": ms.passed, "reference": mr.passed}
    if ms.passed != mr.passed:
        result.notes.append("the FMVSS 126 verdicts differ: the simulation "
                            f"{'passes' if ms.passed else 'fails'}, the reference "
                            f"{'passes' if mr.passed else 'fails'}")


__all__ = ["AUTO_STANDARD", "BAND_KEYS", "BIN_WIDTH_MPS2", "Band", "CROSS_PLOTS", "CrossPlot",
           "CurveResult", "DEFAULT_REQUIRED_SHARE", "HISTORY_BANDS", "MetricComparison",
           "STANDARDS", "SWD_HISTORIES", "SWD_METRIC_TOLERANCES", "ValidationResult",
           "band_distance", "band_edges", "binned_curve", "choose_standard", "cross_plot",
           "history_curve", "parse_band", "steady_samples", "validate"]
