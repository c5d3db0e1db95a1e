r"""Frequency response of recorded runs and of linear models (ISO 7401 frequency domain).

Estimated response (H1 estimator, Welch-averaged spectra, Hann windows, 50 % overlap):

.. math::

    \hat H_1(f) = \frac{\hat S_{uy}(f)}{\hat S_{uu}(f)}, \qquad
    \gamma^2(f) = \frac{|\hat S_{uy}(f)|^2}{\hat S_{uu}(f)\,\hat S_{yy}(f)},

with :math:`u` the input (front road-wheel angle, rad, or steering-wheel angle, rad) and
:math:`y` the output (yaw rate rad/s, lateral acceleration m/s^2, sideslip rad, roll rad).
H1 is unbiased by output noise; coherence :math:`\gamma^2` near 1 marks the frequencies where
the estimate can be trusted.

Analytic response of a linear model ``dx/dt = A x + B u``, ``y = C x + D u`` (a python-control
``StateSpace`` with named outputs and inputs, e.g. from
:func:`fourws_analysis.linear.linear_system`): :math:`H(j\omega) = C (j\omega I - A)^{-1} B + D`,
with :math:`\omega = 2\pi f` (:func:`model_response`, :func:`dc_gain`).

Frequencies are in Hz throughout; phases in degrees; gains in output unit per input unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import control
import numpy as np
from scipy import signal

from fourws_analysis import units
from fourws_analysis.bag import MetricUnavailableError

#: Coherence above which an estimated point is trusted (ISO 7401 asks for "good" coherence;
#: 0.95 keeps random error of the H1 gain below ~2 % with a few tens of averages).
COHERENCE_MIN = 0.95
#: Input power spectrum below this fraction of its peak is "not excited" (20 dB down): there
#: window leakage and record-end effects, not the vehicle, dominate H1 even when the coherence
#: of a noise-free simulation stays near 1.
EXCITATION_MIN = 1e-2
#: Frequency at which the phase lag is reported, Hz (the customary ISO 7401 comparison point).
PHASE_LAG_FREQ_HZ = 1.0
#: -3 dB: amplitude ratio 1/sqrt(2).
HALF_POWER_DB = -3.0103
#: Upper end of the handling band analysed, Hz (driver inputs hardly exceed 3-4 Hz).
MAX_FREQ_HZ = 5.0
#: Frequency standing in for 0 Hz when a model's A matrix is singular, Hz.
DC_LIMIT_HZ = 1e-6
#: Default Welch segment length, s: 0.1 Hz resolution.
DEFAULT_SEGMENT_S = 10.0

#: Outputs analysed (channel names; labels and units in :data:`fourws_analysis.units.OUTPUTS`).
OUTPUTS: tuple[str, ...] = tuple(units.OUTPUTS)


@dataclass
class FrequencyResponse:
    """Gain and phase of one output per one input.

    Attributes
    ----------
    output, input : str
        Channel names (e.g. ``"yaw_rate_radps"`` per ``"front_wheel_angle_rad"``).
    freq_hz : ndarray
        Frequencies in Hz.
    response : ndarray of complex
        Complex frequency response (output unit per input unit).
    coherence : ndarray or None
        Ordinary coherence (estimates only; ``None`` for analytic responses).
    input_power : ndarray or None
        Input auto-spectrum relative to its peak (estimates only).
    label : str
        Legend label.
    """

    output: str
    input: str
    freq_hz: np.ndarray
    response: np.ndarray
    coherence: np.ndarray | None = None
    label: str = ""
    input_power: np.ndarray | None = None

    @property
    def gain(self) -> np.ndarray:
        """|H| in output unit per input unit."""
        return np.abs(self.response)

    @property
    def gain_db(self) -> np.ndarray:
        """20 log10 |H| in dB."""
        return 20.0 * np.log10(np.maximum(np.abs(self.response), 1e-300))

    @property
    def phase_deg(self) -> np.ndarray:
        """Phase in degrees, unwrapped from the lowest frequency, in (-360, 180]."""
        return _unwrapped_phase_deg(self.response)

    def trusted(self, coherence_min: float = COHERENCE_MIN) -> np.ndarray:
        """Boolean mask of points to trust: a finite response, coherence above
        ``coherence_min`` and the input excited (power at least :data:`EXCITATION_MIN` of its
        peak). 0 Hz appears only in transient estimates, where it is a real point (see
        :func:`estimate_response`)."""
        mask = np.isfinite(self.response)
        if self.coherence is not None:
            mask &= self.coherence > coherence_min
        if self.input_power is not None:
            mask &= self.input_power >= EXCITATION_MIN
        return mask


@dataclass
class ResponseMetrics:
    """Frequency-response metrics of one output (ISO 7401 frequency-domain characteristics).

    Attributes
    ----------
    steady_state_gain : float
        Gain at the lowest trusted frequency (output unit per input unit): 0 Hz for a
        transient record (pulse, sweep) whose input integral is excited, else the first bin
        (a note then says which frequency).
    resonance_ratio : float or None
        Peak gain / steady-state gain (None: no peak inside the trusted band).
    resonance_freq_hz : float or None
        Frequency of the peak gain, Hz.
    phase_lag_1hz_deg : float or None
        Phase lag (positive = output lags) at 1 Hz, degrees.
    bandwidth_hz : float or None
        First frequency where the gain falls 3 dB below the steady-state gain, Hz.
    band_hz : tuple of float
        Trusted frequency band (lowest, highest), Hz.
    notes : list of str
        Why a metric is missing.
    output, input : str
        Channel names of the response (they name the gain's unit).
    """

    steady_state_gain: float
    resonance_ratio: float | None
    resonance_freq_hz: float | None
    phase_lag_1hz_deg: float | None
    bandwidth_hz: float | None
    band_hz: tuple[float, float]
    notes: list[str] = field(default_factory=list)
    output: str = ""
    input: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping; the gain's key names its unit (:func:`units.gain_key`)."""
        return {units.gain_key(self.output, self.input): self.steady_state_gain,
                "resonance_ratio": self.resonance_ratio,
                "resonance_freq_hz": self.resonance_freq_hz,
                "phase_lag_1hz_deg": self.phase_lag_1hz_deg,
                "bandwidth_hz": self.bandwidth_hz,
                "trusted_band_hz": list(self.band_hz), "notes": list(self.notes)}


#: Maneuvers whose whole record is one transient (a sweep, a pulse or the ISO 7401 single-period
#: sine, each starting from rest): estimated from the full record, since Welch segments would
#: cut the response apart.
TRANSIENT_MANEUVERS = ("swept_sine", "pulse", "sine")
#: Maneuvers that excite a frequency band at all.
FREQUENCY_MANEUVERS = ("swept_sine", "pulse", "random_steer", "sine")


def estimate_response(u: np.ndarray, y: np.ndarray, dt_s: float, *, method: str = "welch",
                      resolution_hz: float = 1.0 / DEFAULT_SEGMENT_S,
                      max_freq_hz: float = MAX_FREQ_HZ, output: str = "",
                      input_name: str = "") -> FrequencyResponse:
    """H1 estimate with coherence of ``y`` per ``u`` sampled every ``dt_s`` seconds.

    Two spectral estimators, both from :func:`scipy.signal.csd` / :func:`scipy.signal.welch`:

    * ``"welch"`` -- Hann segments of ``1/resolution_hz`` s, 50 % overlap: for stationary
      excitation (random steer, continuous sine).
    * ``"transient"`` -- one rectangular window over the whole record, then the cross and
      auto spectra averaged over bands of ``resolution_hz`` (Daniell smoothing). For a swept
      sine or a pulse that starts from rest the record holds the whole response, so
      ``Y(f) = H(f) U(f)`` holds bin by bin; Welch segments would cut the sweep into pieces
      whose windowed responses no longer satisfy it (measured: 0.8 dB error at the a_y notch
      of the Table 4.1 set 1 vehicle with 10 s Welch segments, 0.3 dB with this estimator).
      The signals are taken as deviations from their first sample (the rest or trim state
      the record starts in), not from their mean, and the 0 Hz bin is kept on its own: for
      a record that also ends in that state it holds the time integrals, and their ratio
      ``H(0) = sum(y) / sum(u)`` is the steady-state gain. A pulse puts most of its
      energy there, while its lowest nonzero bin, 1/T (0.2 Hz for a 5 s record), can be far
      from steady state (Table 4.1 set 1, 85 km/h: yaw-rate gain 7.6 % above DC).

    Parameters
    ----------
    u, y : ndarray
        Input and output on the same uniform grid (means are removed).
    dt_s : float
        Sample period in s.
    method : {"welch", "transient"}
    resolution_hz : float
        Frequency resolution in Hz.
    max_freq_hz : float
        Highest frequency kept, Hz.

    Raises
    ------
    MetricUnavailableError
        If the input carries no excitation (constant input) or the record is too short.
    """
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    fs = 1.0 / dt_s
    what = f"frequency response of {output or 'output'}"
    if u.size < 64:
        raise MetricUnavailableError(f"{what}: record has {u.size} samples; need 64")
    if np.ptp(u) <= 1e-9 * max(1.0, float(np.max(np.abs(u)))):
        raise MetricUnavailableError(
            f"{what}: input {input_name or 'u'} is constant (no excitation band)")
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
        raise MetricUnavailableError(f"{what}: non-finite samples in the record")
    if method == "transient":
        # before decimating, so the decimation filter sees no step at the record start
        u, y = u - u[0], y - y[0]
    # decimate first when sampled far above the band: same estimate, much less work
    step = max(1, int(fs / (8.0 * max_freq_hz)))
    if step > 1 and u.size // step >= 64:
        u, y = _decimate_chain(u, step), _decimate_chain(y, step)
        fs /= step
    if method == "welch":
        nper = max(64, min(int(round(fs / resolution_hz)),
                           u.size // 4 if u.size >= 256 else u.size))
        kw: dict[str, Any] = {"fs": fs, "nperseg": nper, "detrend": "constant"}
        f, p_uy = signal.csd(u, y, **kw)
        _, p_uu = signal.welch(u, **kw)
        _, p_yy = signal.welch(y, **kw)
        # 0 Hz of mean-removed Hann segments carries no information
        f, p_uy, p_uu, p_yy = f[1:], p_uy[1:], p_uu[1:], p_yy[1:]
    elif method == "transient":
        kw = {"fs": fs, "nperseg": u.size, "window": "boxcar", "detrend": False}
        f, p_uy = signal.csd(u, y, **kw)
        _, p_uu = signal.welch(u, **kw)
        _, p_yy = signal.welch(y, **kw)
        width = max(1, int(round(resolution_hz / (f[1] - f[0]))))
        n_band = (f.size - 1) // width
        sl = slice(1, 1 + n_band * width)  # 0 Hz stays a band of its own
        f, p_uy, p_uu, p_yy = (
            np.concatenate(([p[0]], p[sl].reshape(n_band, width).mean(axis=1)))
            for p in (f, p_uy, p_uu, p_yy))
    else:
        raise ValueError(f"method must be 'welch' or 'transient', got {method!r}")
    keep = f <= max_freq_hz
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.where(p_uu[keep] > 0, p_uy[keep] / p_uu[keep], np.nan)
        coh = np.where((p_uu[keep] > 0) & (p_yy[keep] > 0),
                       np.abs(p_uy[keep]) ** 2 / (p_uu[keep] * p_yy[keep]), 0.0)
    peak = float(np.max(p_uu))
    return FrequencyResponse(output=output, input=input_name, freq_hz=f[keep], response=h,
                             coherence=np.nan_to_num(coh), label="measured",
                             input_power=p_uu[keep] / peak)


def _decimate_chain(x: np.ndarray, step: int) -> np.ndarray:
    """Decimate by ``step`` in stages of at most 10 (scipy's advice for large factors)."""
    remaining = step
    out = x
    while remaining > 1:
        factor = next(k for k in range(min(10, remaining), 1, -1) if remaining % k == 0) \
            if any(remaining % k == 0 for k in range(2, min(10, remaining) + 1)) else remaining
        out = signal.decimate(out, factor, ftype="fir", zero_phase=True)
        remaining //= factor
    return out


def _unwrapped_phase_deg(response: np.ndarray) -> np.ndarray:
    """Phase of ``response`` in degrees, unwrapped from its first point, which is put in
    (-180, 180]."""
    ph = np.unwrap(np.angle(response))
    if ph.size and ph[0] > math.pi:
        ph -= 2 * math.pi
    elif ph.size and ph[0] <= -math.pi:
        ph += 2 * math.pi
    return np.degrees(ph)


#: Neighbouring points of a drawn phase curve further apart than this are not joined, deg.
#: A jump over 180 deg is always a branch artefact (the nearest branch is within 180 deg);
#: 90 deg also breaks the near-vertical swing at an input or model zero on the jw axis,
#: where the phase is undefined. A smooth curve sampled as densely as the plots are (300
#: points over 2.5 decades) turns by at most a few degrees per point unless a pole or zero
#: has a damping ratio below ~0.01.
PHASE_BREAK_DEG = 90.0


def display_phase_deg(fr: FrequencyResponse,
                      coherence_min: float = COHERENCE_MIN) -> np.ndarray:
    """Phase of ``fr`` for drawing, deg: the trusted points unwrapped among themselves (as
    :func:`response_metrics` does), each untrusted point put on the branch nearest the
    closest trusted point before it (after it, below the trusted band). An untrusted point
    (an input zero, noise) can turn by any angle; unwrapping through it would move every
    later trusted point by 360 deg, and unwrapping noise drifts by hundreds of degrees."""
    ok = fr.trusted(coherence_min)
    raw = np.degrees(np.angle(fr.response))
    out = np.full(raw.shape, np.nan)
    if not np.any(ok):
        return raw
    idx = np.nonzero(ok)[0]
    out[idx] = _unwrapped_phase_deg(fr.response[idx])
    for i in np.nonzero(~ok & np.isfinite(raw))[0]:
        before = idx[idx < i]
        ref = out[before[-1]] if before.size else out[idx[0]]
        out[i] = raw[i] + 360.0 * round((ref - raw[i]) / 360.0)
    return out


def break_phase_jumps(x: np.ndarray, phase_deg: np.ndarray,
                      max_jump_deg: float = PHASE_BREAK_DEG) -> tuple[np.ndarray, np.ndarray]:
    """``(x, phase)`` with a NaN inserted between neighbours more than ``max_jump_deg``
    apart, so a line plot leaves the gap open instead of drawing a vertical line."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(phase_deg, dtype=float)
    with np.errstate(invalid="ignore"):
        jumps = np.nonzero(np.abs(np.diff(y)) > max_jump_deg)[0] + 1
    return np.insert(x, jumps, np.nan), np.insert(y, jumps, np.nan)


def response_metrics(fr: FrequencyResponse, coherence_min: float = COHERENCE_MIN,
                     phase_freq_hz: float = PHASE_LAG_FREQ_HZ) -> ResponseMetrics:
    """Steady-state gain, resonance, phase lag at 1 Hz and -3 dB bandwidth of ``fr``.

    Only trusted points (coherence above ``coherence_min``) are used; a metric whose frequency
    lies outside the trusted band is ``None`` with a note saying so.

    Raises
    ------
    MetricUnavailableError
        If no point is trusted.
    """
    mask = fr.trusted(coherence_min)
    if not np.any(mask):
        raise MetricUnavailableError(
            f"frequency response of {fr.output}: no frequency with coherence > {coherence_min}")
    f = fr.freq_hz[mask]
    gain = fr.gain[mask]
    # unwrapped over the trusted points only: an untrusted point (an input zero, noise) in
    # between can turn by any angle and would shift the branch of everything above it
    phase = _unwrapped_phase_deg(fr.response[mask])
    notes: list[str] = []
    g0 = float(gain[0])
    if f[0] > 0.0:
        notes.append(f"steady-state gain taken at the lowest trusted frequency, {f[0]:.3g} Hz")
    i_peak = int(np.argmax(gain))
    if 0 < i_peak < gain.size - 1 and gain[i_peak] > g0 * 1.001:
        res_ratio: float | None = float(gain[i_peak] / g0)
        res_f: float | None = float(f[i_peak])
    else:
        res_ratio = res_f = None
        notes.append("no resonance peak inside the trusted band "
                     f"{f[0]:.2f}-{f[-1]:.2f} Hz")
    lag: float | None = None
    if f[0] <= phase_freq_hz <= f[-1]:
        lag = float(-np.interp(phase_freq_hz, f, phase))
    else:
        notes.append(f"{phase_freq_hz:g} Hz outside the trusted band {f[0]:.2f}-{f[-1]:.2f} Hz")
    bw: float | None = None
    rel_db = 20.0 * np.log10(gain / g0)
    below = np.nonzero(rel_db < HALF_POWER_DB)[0]
    if below.size:
        k = int(below[0])
        if k == 0:
            bw = float(f[0])
        else:
            bw = float(np.interp(HALF_POWER_DB, [rel_db[k], rel_db[k - 1]], [f[k], f[k - 1]]))
    else:
        notes.append("gain stays within 3 dB of its steady-state value over the trusted band")
    return ResponseMetrics(g0, res_ratio, res_f, lag, bw, (float(f[0]), float(f[-1])), notes,
                           fr.output, fr.input)


# --------------------------------------------------------------------------------------------
# analytic responses of linear models (python-control ``StateSpace``)


def _port(system: control.StateSpace, output: str, input_name: str) -> tuple[int, int]:
    """Indices of output ``output`` and input ``input_name`` of ``system``.

    Raises
    ------
    MetricUnavailableError
        The system has no such output or input.
    """
    i, j = system.find_output(output), system.find_input(input_name)
    if i is None or j is None:
        missing = f"output {output!r}" if i is None else f"input {input_name!r}"
        raise MetricUnavailableError(
            f"linear model {system.name!r} has no {missing}; outputs "
            f"{', '.join(system.output_labels)}, inputs {', '.join(system.input_labels)}")
    return i, j


def model_response(system: control.StateSpace, output: str, freq_hz: np.ndarray,
                   input_name: str = units.ROAD_WHEEL.channel) -> FrequencyResponse:
    """Frequency response of output ``output`` of ``system`` per its input ``input_name``
    (default the front road-wheel angle, rad) at ``freq_hz`` (Hz):
    ``C (j 2 pi f I - A)^-1 B + D``, evaluated by python-control. The system's name is the
    response's label.

    Raises
    ------
    MetricUnavailableError
        The system has no such output or input.
    """
    i, j = _port(system, output, input_name)
    f = np.asarray(freq_hz, dtype=float)
    h = system(2j * math.pi * np.atleast_1d(f), squeeze=False)[i, j]
    return FrequencyResponse(output, input_name, f, h.reshape(f.shape), None, system.name)


def dc_gain(system: control.StateSpace, output: str,
            input_name: str = units.ROAD_WHEEL.channel) -> float:
    """Steady-state gain of output ``output`` of ``system`` per input ``input_name`` (default
    the front road-wheel angle), output unit per input unit.

    ``C (-A)^{-1} B + D``; when A is singular (the 8-DOF's coasting-speed and wheel-spin modes
    have zero eigenvalues at a trim without drag, but the steer does not reach them) the limit
    of the response at :data:`DC_LIMIT_HZ` is returned.

    Raises
    ------
    MetricUnavailableError
        The system has no such output or input.
    """
    i, j = _port(system, output, input_name)
    try:
        return float(system.C[i] @ np.linalg.solve(-system.A, system.B[:, j]) + system.D[i, j])
    except np.linalg.LinAlgError:
        return float(model_response(system, output, np.array([DC_LIMIT_HZ]),
                                    input_name).response[0].real)
