# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Open-loop steering maneuvers: step, ramp, slowly increasing, sine, swept sine, random, pulse.

Each runs a steering waveform of time (road-wheel or steering-wheel angle, ``steer_input``)
while the speed-hold driver holds the initial speed. Step, sine, random and pulse follow
ISO 7401 (lateral transient response); the slowly increasing steer follows ISO 4138
(steady-state circular driving, constant-speed method); the ramp is the ch. 8 maneuver of
Samsundar (1996).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

import numpy as np

from fourws_sim.errors import ParameterError, describe
from fourws_sim.maneuvers.base import (ANGLE_BOUNDS_RAD, FREQUENCY_BOUNDS_HZ,
                                       MAX_DURATION_S, MAX_HAND_WHEEL_ANGLE_RAD,
                                       MAX_RANDOM_SAMPLES, RANDOM_PEAK_PER_RMS,
                                       RATE_BOUNDS_RADPS, TIME_BOUNDS_S, TIME_EPS_S, Maneuver,
                                       ManeuverSpec, check_pulse_shape, finite_or_none,
                                       pulse_shape, smooth_ramp)
from fourws_sim.params import Vehicle, _spec


class RampAndHold:
    """Shape shared by step and ramp steer: 0 until ``start_s``, a ramp of ``ramp_time_s`` to
    ``amplitude_rad``, then held (the subclasses give the three values)."""

    amplitude_rad: float
    start_s: float
    ramp_time_s: float

    def steer(self, t: float) -> float:
        """Input angle (rad) at time ``t`` (s)."""
        if self.ramp_time_s == 0.0:
            return self.amplitude_rad if t >= self.start_s - TIME_EPS_S else 0.0
        return self.amplitude_rad * smooth_ramp((t - self.start_s) / self.ramp_time_s)

    def phase(self, t: float) -> str:
        """``settle`` before the ramp, ``steer`` during it, then ``hold``."""
        if t < self.start_s:
            return "settle"
        return "steer" if t < self.start_s + self.ramp_time_s else "hold"


@dataclass(frozen=True)
class StepSteerParams(RampAndHold):
    """ISO 7401 step steer: 0 until ``start_s``, linear ramp over ``ramp_time_s`` to
    ``amplitude_rad``, then held. ISO 7401 asks for a 10-90 % rise within 0.15 s; the default
    0.1 s ramp (0.08 s from 10 to 90 %) meets it.

    Equal steer or equal lateral acceleration: with ``amplitude_rad`` every law gets the same
    steer, so the laws reach different lateral accelerations. ISO 7401 compares at one steady
    lateral acceleration instead (4 m/s^2 is customary): set ``target_lateral_accel_mps2``
    and the amplitude is found for each law before its run
    (:func:`fourws_run.step_target.resolve_maneuver_for_law`, with the offline twin of the
    run); ``amplitude_rad`` then only gives the direction (its sign) and the first guess, and
    may be left out (a left turn). A resolved maneuver holds the amplitude found, the law it
    was found for (``amplitude_law``) and the steady lateral acceleration the twin reached
    with it (``amplitude_lateral_accel_mps2``, m/s^2): the run configuration of a bag says
    which amplitude ran and why. An unresolved target cannot run (:class:`StepSteer` refuses
    it), since the amplitude depends on the law.
    """

    amplitude_rad: float | None = None
    start_s: float = _spec("nonnegative", default=0.5, bounds=TIME_BOUNDS_S)
    ramp_time_s: float = _spec("nonnegative", default=0.1, bounds=TIME_BOUNDS_S)
    target_lateral_accel_mps2: float | None = None
    amplitude_law: str = ""
    amplitude_lateral_accel_mps2: float | None = None

    #: Plausibility bounds of the optional number fields (not ``_spec`` fields: they may be
    #: absent), rad and m/s^2.
    OPTIONAL_BOUNDS: ClassVar[Mapping[str, tuple[float, float]]] = {
        "amplitude_rad": ANGLE_BOUNDS_RAD, "target_lateral_accel_mps2": (0.01, 30.0),
        "amplitude_lateral_accel_mps2": (0.0, 30.0)}
    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        finite_or_none(self, self.OPTIONAL_BOUNDS, source, prefix, unchecked)
        if not isinstance(self.amplitude_law, str):
            raise ParameterError(f"{prefix}amplitude_law",
                                 f"must be a law name, got {describe(self.amplitude_law)}",
                                 source)
        target = self.target_lateral_accel_mps2
        if target is None:
            if self.amplitude_rad is None:
                raise ParameterError(f"{prefix}amplitude_rad", "missing required field (or "
                                     "set target_lateral_accel_mps2)", source)
            for name in ("amplitude_law", "amplitude_lateral_accel_mps2"):
                if getattr(self, name) not in ("", None):
                    raise ParameterError(f"{prefix}{name}",
                                         "only with target_lateral_accel_mps2", source)
            return
        if target <= 0.0:
            raise ParameterError(f"{prefix}target_lateral_accel_mps2",
                                 f"must be > 0 (the steady |a_y|), got {target!r}", source)
        if self.amplitude_rad == 0.0:
            raise ParameterError(f"{prefix}amplitude_rad", "must be nonzero with "
                                 "target_lateral_accel_mps2 (its sign is the direction)",
                                 source)
        if self.amplitude_law and self.amplitude_rad is None:
            raise ParameterError(f"{prefix}amplitude_rad",
                                 "missing: a resolved target records its amplitude", source)

    @property
    def resolved(self) -> bool:
        """True when the amplitude is known (given, or found for ``amplitude_law``)."""
        return self.target_lateral_accel_mps2 is None or bool(self.amplitude_law)

    def to_dict(self) -> dict[str, Any]:
        """The fields as a mapping; the target fields only when a target is set."""
        out = dataclasses.asdict(self)
        if self.target_lateral_accel_mps2 is None:
            for name in ("target_lateral_accel_mps2", "amplitude_law",
                         "amplitude_lateral_accel_mps2"):
                del out[name]
        if out["amplitude_rad"] is None:
            del out["amplitude_rad"]
        return out


class StepSteer(Maneuver):
    """ISO 7401 step steer (:class:`StepSteerParams`).

    Raises
    ------
    ParameterError
        The amplitude is a lateral-acceleration target not yet resolved for a law.
    """

    Params = StepSteerParams

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        super().__init__(spec, vehicle)
        if not spec.params.resolved:
            raise ParameterError(
                "target_lateral_accel_mps2", "the step amplitude for this target is found per "
                "law before a run (fourws run and run_scenario do it, see "
                "fourws_run.step_target.resolve_maneuver_for_law); this maneuver was not "
                "resolved", spec.source or spec.name)


@dataclass(frozen=True)
class RampSteerParams(RampAndHold):
    """Ramp steer (ch. 8, after Nalecz and Bindemann): from ``start_s`` the angle grows at
    ``rate_radps`` until it reaches ``amplitude_rad``, then is held."""

    amplitude_rad: float = _spec("any", bounds=ANGLE_BOUNDS_RAD)
    rate_radps: float = _spec(bounds=RATE_BOUNDS_RADPS)
    start_s: float = _spec("nonnegative", default=0.5, bounds=TIME_BOUNDS_S)

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    @property
    def ramp_time_s(self) -> float:
        """Duration of the ramp in s."""
        return abs(self.amplitude_rad) / self.rate_radps


class RampSteer(Maneuver):
    """Ramp steer of ch. 8 (:class:`RampSteerParams`)."""

    Params = RampSteerParams


@dataclass(frozen=True)
class SlowRampSteerParams(RampSteerParams):
    """ISO 4138 constant-speed method: steer increased slowly (default rate well under the
    standard's quasi-steady limit) at constant speed; the run ends when
    ``|a_y| >= max_lateral_accel_mps2``, when ``|sideslip| > max_sideslip_rad`` (the car left
    the quasi-steady regime; whether it spun is the run's vehicle limits' call), or at
    ``duration_s``."""

    # end conditions: any small threshold is meaningful (it ends the run early on purpose)
    max_lateral_accel_mps2: float = _spec(default=8.0, bounds=(0.0, 30.0))
    max_sideslip_rad: float = _spec(default=0.15, bounds=(0.0, math.pi / 2))


class SlowRampSteer(Maneuver):
    """ISO 4138 slowly increasing steer at constant speed (:class:`SlowRampSteerParams`); ends
    at the lateral-acceleration limit (its end condition) or when the car spins (abort)."""

    Params = SlowRampSteerParams

    def check_end(self, t: float, outputs: Mapping[str, Any]) -> None:
        """End at ``|a_y| >= max_lateral_accel_mps2`` or ``|sideslip| > max_sideslip_rad``."""
        self.end_at_limits(outputs, self.params.max_lateral_accel_mps2,
                           self.params.max_sideslip_rad)


@dataclass(frozen=True)
class SineParams:
    """ISO 7401 single-period sine: ``A sin(2 pi f (t - t0))`` for one period from ``start_s``,
    zero before and after."""

    amplitude_rad: float = _spec("any", bounds=ANGLE_BOUNDS_RAD)
    frequency_hz: float = _spec(bounds=FREQUENCY_BOUNDS_HZ)
    start_s: float = _spec("nonnegative", default=0.5, bounds=TIME_BOUNDS_S)

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def shortest_period_s(self) -> tuple[str, float]:
        """The field setting the shortest period of the input, and that period in s."""
        return "frequency_hz", 1.0 / self.frequency_hz

    def steer(self, t: float) -> float:
        """Input angle (rad) at time ``t`` (s)."""
        tau = t - self.start_s
        if tau < 0.0 or tau > 1.0 / self.frequency_hz:
            return 0.0
        return self.amplitude_rad * math.sin(2.0 * math.pi * self.frequency_hz * tau)

    def phase(self, t: float) -> str:
        """``settle``, ``steer`` (the period), ``recover``."""
        if t < self.start_s:
            return "settle"
        return "steer" if t <= self.start_s + 1.0 / self.frequency_hz else "recover"


class Sine(Maneuver):
    """ISO 7401 single-period sine (:class:`SineParams`)."""

    Params = SineParams


@dataclass(frozen=True)
class SweptSineParams:
    """Swept sine (chirp) for frequency response (ISO 7401 continuous sinusoidal input):
    ``A sin(phi(tau))``, ``tau = t - start_s`` in [0, sweep_time_s], with instantaneous
    frequency ``f(tau) = dphi/dtau / 2 pi`` going from ``f_start_hz`` to ``f_end_hz``,
    linearly (``f0 + (f1 - f0) tau / T``) or logarithmically (``f0 (f1/f0)^(tau/T)``)."""

    amplitude_rad: float = _spec("any", bounds=ANGLE_BOUNDS_RAD)
    f_start_hz: float = _spec(bounds=FREQUENCY_BOUNDS_HZ)
    f_end_hz: float = _spec(bounds=FREQUENCY_BOUNDS_HZ)
    sweep_time_s: float = _spec(bounds=(1e-2, MAX_DURATION_S))
    start_s: float = _spec("nonnegative", default=1.0, bounds=TIME_BOUNDS_S)
    spacing: str = "logarithmic"

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def shortest_period_s(self) -> tuple[str, float]:
        """The field setting the shortest period of the input, and that period in s."""
        if self.f_end_hz >= self.f_start_hz:
            return "f_end_hz", 1.0 / self.f_end_hz
        return "f_start_hz", 1.0 / self.f_start_hz

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if self.spacing not in ("linear", "logarithmic"):
            raise ParameterError(f"{prefix}spacing",
                                 f"must be linear or logarithmic, got {self.spacing!r}", source)

    def instantaneous_frequency_hz(self, t: float) -> float:
        """``f(tau)`` in Hz (the analytic definition the phase integrates)."""
        s = smooth_ramp((t - self.start_s) / self.sweep_time_s)
        if self.spacing == "linear":
            return self.f_start_hz + (self.f_end_hz - self.f_start_hz) * s
        return self.f_start_hz * (self.f_end_hz / self.f_start_hz) ** s

    def phase_rad(self, tau: float) -> float:
        """``phi(tau) = 2 pi \\int_0^tau f`` in rad."""
        f0, f1, big_t = self.f_start_hz, self.f_end_hz, self.sweep_time_s
        if self.spacing == "linear":
            return 2.0 * math.pi * (f0 * tau + 0.5 * (f1 - f0) * tau * tau / big_t)
        if f1 == f0:
            return 2.0 * math.pi * f0 * tau
        k = math.log(f1 / f0)
        return 2.0 * math.pi * f0 * big_t * (math.exp(k * tau / big_t) - 1.0) / k

    def steer(self, t: float) -> float:
        """Input angle (rad) at time ``t`` (s)."""
        tau = t - self.start_s
        if tau < 0.0 or tau > self.sweep_time_s:
            return 0.0
        return self.amplitude_rad * math.sin(self.phase_rad(tau))

    def phase(self, t: float) -> str:
        """``settle``, ``sweep``, ``recover``."""
        if t < self.start_s:
            return "settle"
        return "sweep" if t <= self.start_s + self.sweep_time_s else "recover"


class SweptSine(Maneuver):
    """Swept sine for the frequency response (:class:`SweptSineParams`)."""

    Params = SweptSineParams


@dataclass(frozen=True)
class RandomSteerParams:
    """ISO 7401 random input: band-limited noise with power only within
    [``f_low_hz``, ``f_high_hz``] (brick-wall filter in the frequency domain of seeded white
    noise sampled at ``sample_rate_hz``), scaled to ``rms_rad``, faded in with a raised cosine
    over ``fade_s`` from ``start_s`` and linearly interpolated between samples."""

    rms_rad: float = _spec(bounds=(0.0, MAX_HAND_WHEEL_ANGLE_RAD / RANDOM_PEAK_PER_RMS))
    f_high_hz: float = _spec(bounds=FREQUENCY_BOUNDS_HZ)
    f_low_hz: float = _spec("nonnegative", default=0.0, bounds=(0.0, FREQUENCY_BOUNDS_HZ[1]))
    length_s: float = _spec(default=60.0, bounds=(1e-2, MAX_DURATION_S))
    seed: int = 0
    start_s: float = _spec("nonnegative", default=1.0, bounds=TIME_BOUNDS_S)
    fade_s: float = _spec("nonnegative", default=1.0, bounds=TIME_BOUNDS_S)
    sample_rate_hz: float = _spec(default=200.0, bounds=(1.0, 1e4))

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def shortest_period_s(self) -> tuple[str, float]:
        """The field setting the shortest period of the input, and that period in s."""
        return "f_high_hz", 1.0 / self.f_high_hz

    def peak_input(self) -> tuple[str, float]:
        """The field that sets the largest input angle and that angle (rad): a band-limited
        Gaussian input exceeds ``RANDOM_PEAK_PER_RMS`` times its rms on ~1 sample in 16 000."""
        return "rms_rad", RANDOM_PEAK_PER_RMS * self.rms_rad

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ParameterError(f"{prefix}seed",
                                 f"must be an integer >= 0, got {describe(self.seed)}", source)
        if self.length_s * self.sample_rate_hz > MAX_RANDOM_SAMPLES:
            raise ParameterError(f"{prefix}length_s", f"length_s * sample_rate_hz = "
                                 f"{self.length_s * self.sample_rate_hz:.3g} samples, more "
                                 f"than the limit {MAX_RANDOM_SAMPLES}", source)
        if self.f_high_hz <= self.f_low_hz:
            raise ParameterError(f"{prefix}f_high_hz", "must be > f_low_hz", source)
        if self.f_high_hz >= 0.5 * self.sample_rate_hz:
            raise ParameterError(f"{prefix}f_high_hz", "must be below sample_rate_hz / 2",
                                 source)

    def samples(self) -> np.ndarray:
        """The band-limited sequence (rad) at ``sample_rate_hz`` (before the fade-in)."""
        n = int(round(self.length_s * self.sample_rate_hz)) + 1
        rng = np.random.default_rng(self.seed)
        spectrum = np.fft.rfft(rng.standard_normal(n))
        freqs = np.fft.rfftfreq(n, d=1.0 / self.sample_rate_hz)
        spectrum[(freqs < self.f_low_hz) | (freqs > self.f_high_hz)] = 0.0
        signal = np.fft.irfft(spectrum, n)
        signal -= signal.mean() if self.f_low_hz > 0.0 else 0.0
        return signal * (self.rms_rad / float(np.sqrt(np.mean(signal * signal))))


class RandomSteer(Maneuver):
    """ISO 7401 random steer (:class:`RandomSteerParams`): the sequence is drawn once per run."""

    Params = RandomSteerParams

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        super().__init__(spec, vehicle)
        self._random = spec.params.samples()
        self._random_index = np.arange(self._random.size, dtype=float)

    def steer_input(self, t: float) -> float:
        """The faded-in, interpolated sequence at ``t`` (rad)."""
        p = self.params
        tau = t - p.start_s
        if tau <= 0.0:
            return 0.0
        fade = 1.0 if p.fade_s == 0.0 else 0.5 * (1.0 - math.cos(
            math.pi * smooth_ramp(tau / p.fade_s)))
        return fade * float(np.interp(tau * p.sample_rate_hz, self._random_index,
                                      self._random))

    def type_phase(self, t: float) -> str:
        """``settle``, then ``random``."""
        return "settle" if t < self.params.start_s else "random"


@dataclass(frozen=True)
class PulseParams:
    """ISO 7401 pulse input: a single pulse of ``width_s`` from ``start_s``, ``triangle``
    (area A w / 2) or ``half_sine`` (area 2 A w / pi)."""

    amplitude_rad: float = _spec("any", bounds=ANGLE_BOUNDS_RAD)
    width_s: float = _spec(default=0.4, bounds=(1e-3, MAX_DURATION_S))
    start_s: float = _spec("nonnegative", default=0.5, bounds=TIME_BOUNDS_S)
    shape: str = "triangle"

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def shortest_period_s(self) -> tuple[str, float]:
        """The field setting the shortest period of the input, and that period in s."""
        return "width_s", self.width_s

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        check_pulse_shape(self.shape, source, prefix)

    def steer(self, t: float) -> float:
        """Input angle (rad) at time ``t`` (s)."""
        return self.amplitude_rad * pulse_shape(t, self.start_s, self.width_s, self.shape)

    @property
    def area_rad_s(self) -> float:
        """Time integral of the pulse in rad s."""
        if self.shape == "triangle":
            return 0.5 * self.amplitude_rad * self.width_s
        return 2.0 * self.amplitude_rad * self.width_s / math.pi

    def phase(self, t: float) -> str:
        """``settle``, ``pulse``, ``recover``."""
        if t < self.start_s:
            return "settle"
        return "pulse" if t < self.start_s + self.width_s else "recover"


class Pulse(Maneuver):
    """ISO 7401 pulse (:class:`PulseParams`)."""

    Params = PulseParams


__all__ = ["Pulse", "PulseParams", "RampAndHold", "RampSteer", "RampSteerParams",
           "RandomSteer", "RandomSteerParams", "Sine", "SineParams", "SlowRampSteer",
           "SlowRampSteerParams", "StepSteer", "StepSteerParams", "SweptSine",
           "SweptSineParams"]
