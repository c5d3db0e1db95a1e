# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Maneuvers: steering inputs, closed-loop driving tasks and the speed-hold driver, from YAML.

A maneuver file (``config/maneuvers/<name>.yaml``) is a mapping::

    name: step_steer_85kmh          # optional, defaults to the file stem
    type: step_steer                # one of MANEUVER_TYPES
    description: ...
    initial_speed_mps: 23.611       # speed the simulator is reset to
    duration_s: 5.0
    steer_input: road_wheel         # amplitudes are road-wheel (front) angles ...
                                    # ... or "steering_wheel" (hand-wheel angles, divided by
                                    # the vehicle's steering.ratio)
    speed_hold: {kp_per_s: 2.0}     # optional, see fourws_sim.drivers.SpeedHoldSpec
    path_driver: {...}              # optional, constant_radius only (PathDriverSpec)
    tracking_driver: {...}          # optional, double_lane_change only (TrackingDriverSpec)
    <type fields>                   # e.g. amplitude_rad, start_s, ramp_time_s

All angles are in rad, times in s, speeds in m/s, accelerations in m/s^2. Every type holds the
initial speed with the speed-hold driver (so "constant speed" really is constant on the 8-DOF
model), except while ``brake_in_turn`` brakes.

Runtime interface (the maneuver node and the offline runner use only this)::

    m = make_maneuver(load_maneuver_spec("step_steer_85kmh"), vehicle)
    m.initial_speed_mps, m.duration_s
    m.command(t, outputs) -> DriverCommand     # outputs: dict of Simulator.outputs()
    m.phase(t) -> str;  m.progress(t) -> float in [0, 1];  m.done(t, outputs) -> bool
    m.to_dict() -> mapping (the file layout; load_maneuver_spec(m.to_dict()) rebuilds it)

``command`` must be called once per control tick with increasing ``t`` (stateful drivers advance
only there, see :mod:`fourws_sim.drivers`); ``phase``, ``progress`` and ``done`` have no side
effects except that ``done`` of ``slow_ramp_steer`` and ``constant_radius`` looks at the
outputs it is given.

Standards and the source: step steer, sine, random and pulse inputs follow ISO 7401 (lateral
transient response test methods); slowly increasing steer and constant radius follow ISO 4138
(steady-state circular driving); the lane change follows the ISO 3888-2 obstacle-avoidance track;
ramp steer and braking in a turn are the ch. 8 maneuvers of Samsundar (1996).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field
from pathlib import Path as FilePath
from typing import Any, ClassVar, Mapping

import numpy as np

from fourws_sim.corridor import CorridorPlan, plan_corridor_path
from fourws_sim.drivers import Path as ReferencePath
from fourws_sim.drivers import (
    CirclePath, DriverCommand, PathDriverSpec, PathTrackingDriver, PreviewPathDriver,
    SpeedHoldDriver, SpeedHoldSpec, SplinePath, TrackingDriverSpec, path_driver_spec_from,
    speed_hold_spec_from, split_brake_torque, tracking_driver_spec_from,
)
from fourws_sim.errors import ParameterError, UnknownNameError, describe
from fourws_sim.params import (CONFIG_DIR, GRAVITY_MPS2, MAX_SPEED_MPS, UNCHECKED_KEY, Vehicle,
                               _from_mapping, _spec, available_configs, bounded_fields,
                               check_plausible, read_yaml, resolve_config_path,
                               unchecked_fields_from)

MANEUVER_DIR = CONFIG_DIR / "maneuvers"
STEER_INPUTS = ("road_wheel", "steering_wheel")

# Plausibility bounds of maneuvers (docs/architecture.md, "Parameters"; a file may lift one
# with ``unchecked_fields``). Speeds are bounded by fourws_sim.params.MAX_SPEED_MPS.
#: Longest run, s (a realtime soak test is 10 min).
MAX_DURATION_S = 3600.0
#: Largest front road-wheel angle an input may ask for, rad (57 deg; steering locks are
#: 30-45 deg).
MAX_ROAD_WHEEL_ANGLE_RAD = 1.0
#: Largest hand-wheel angle, rad (3 turns; cars have 1.2-1.8 turns from centre to lock).
MAX_HAND_WHEEL_ANGLE_RAD = 6.0 * math.pi
#: Highest steering frequency, Hz (ISO 7401 tests reach 4-5 Hz; no steering system follows
#: more than ~20 Hz).
MAX_STEER_FREQUENCY_HZ = 20.0
# Hard limits (never lifted): what a maneuver may cost before it runs.
#: Samples of a random input (``length_s * sample_rate_hz``).
MAX_RANDOM_SAMPLES = 4_000_000
#: Grid points of a planned lane-change line (the planner solves two linear programs of this
#: size; 0.5 m steps give ~220).
MAX_PATH_POINTS = 5_000
#: Peak of a random input per unit rms, used for its angle bound (band-limited Gaussian
#: noise exceeds 4 rms on ~1 sample in 16 000).
RANDOM_PEAK_PER_RMS = 4.0

_TIME_S = (0.0, MAX_DURATION_S)
_ANGLE_RAD = (-MAX_HAND_WHEEL_ANGLE_RAD, MAX_HAND_WHEEL_ANGLE_RAD)
_FREQUENCY_HZ = (1e-3, MAX_STEER_FREQUENCY_HZ)
_RATE_RADPS = (1e-4, 100.0)
#: Tolerance on ``t >= duration`` so a tick time k*Tc that lands a rounding error short of the
#: duration still ends the run (s; far below any control period).
_TIME_EPS_S = 1e-9


def _smooth_ramp(s: float) -> float:
    """Linear 0 -> 1 ramp clipped to [0, 1]."""
    return min(max(s, 0.0), 1.0)


# ---------------------------------------------------------------- per-type parameters

class _RampAndHold:
    """Shape shared by step and ramp steer: 0 until ``start_s``, a ramp of ``ramp_time_s`` to
    ``amplitude_rad``, then held (the subclasses give the three values)."""

    amplitude_rad: float
    start_s: float
    ramp_time_s: float

    def steer(self, t: float) -> float:
        """Input angle (rad) at time ``t`` (s)."""
        if self.ramp_time_s == 0.0:
            return self.amplitude_rad if t >= self.start_s - _TIME_EPS_S else 0.0
        return self.amplitude_rad * _smooth_ramp((t - self.start_s) / self.ramp_time_s)

    def phase(self, t: float) -> str:
        """``settle`` before the ramp, ``steer`` during it, then ``hold``."""
        if t < self.start_s:
            return "settle"
        return "steer" if t < self.start_s + self.ramp_time_s else "hold"


@dataclass(frozen=True)
class StepSteerParams(_RampAndHold):
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
    which amplitude ran and why. An unresolved target cannot run (:class:`Maneuver` refuses
    it), since the amplitude depends on the law.
    """

    amplitude_rad: float | None = None
    start_s: float = _spec("nonnegative", default=0.5, bounds=_TIME_S)
    ramp_time_s: float = _spec("nonnegative", default=0.1, bounds=_TIME_S)
    target_lateral_accel_mps2: float | None = None
    amplitude_law: str = ""
    amplitude_lateral_accel_mps2: float | None = None

    #: Plausibility bounds of the optional number fields (not ``_spec`` fields: they may be
    #: absent), rad and m/s^2.
    OPTIONAL_BOUNDS: ClassVar[Mapping[str, tuple[float, float]]] = {
        "amplitude_rad": _ANGLE_RAD, "target_lateral_accel_mps2": (0.01, 30.0),
        "amplitude_lateral_accel_mps2": (0.0, 30.0)}
    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        for name in ("amplitude_rad", "target_lateral_accel_mps2",
                     "amplitude_lateral_accel_mps2"):
            value = getattr(self, name)
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value):
                raise ParameterError(f"{prefix}{name}",
                                     f"must be a finite number, got {describe(value)}", source)
            check_plausible(f"{prefix}{name}", abs(float(value)) if name == "amplitude_rad"
                            else float(value), self.OPTIONAL_BOUNDS[name], source, unchecked)
            object.__setattr__(self, name, float(value))
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


@dataclass(frozen=True)
class RampSteerParams(_RampAndHold):
    """Ramp steer (ch. 8, after Nalecz and Bindemann): from ``start_s`` the angle grows at
    ``rate_radps`` until it reaches ``amplitude_rad``, then is held."""

    amplitude_rad: float = _spec("any", bounds=_ANGLE_RAD)
    rate_radps: float = _spec(bounds=_RATE_RADPS)
    start_s: float = _spec("nonnegative", default=0.5, bounds=_TIME_S)

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    @property
    def ramp_time_s(self) -> float:
        """Duration of the ramp in s."""
        return abs(self.amplitude_rad) / self.rate_radps


@dataclass(frozen=True)
class SlowRampSteerParams(RampSteerParams):
    """ISO 4138 constant-speed method: steer increased slowly (default rate well under the
    standard's quasi-steady limit) at constant speed; the run ends when
    ``|a_y| >= max_lateral_accel_mps2``, when ``|sideslip| > max_sideslip_rad`` (the car left
    the quasi-steady regime: it is spinning), or at ``duration_s``."""

    # end conditions: any small threshold is meaningful (it ends the run early on purpose)
    max_lateral_accel_mps2: float = _spec(default=8.0, bounds=(0.0, 30.0))
    max_sideslip_rad: float = _spec(default=0.15, bounds=(0.0, math.pi / 2))


@dataclass(frozen=True)
class SineParams:
    """ISO 7401 single-period sine: ``A sin(2 pi f (t - t0))`` for one period from ``start_s``,
    zero before and after."""

    amplitude_rad: float = _spec("any", bounds=_ANGLE_RAD)
    frequency_hz: float = _spec(bounds=_FREQUENCY_HZ)
    start_s: float = _spec("nonnegative", default=0.5, bounds=_TIME_S)

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


@dataclass(frozen=True)
class SweptSineParams:
    """Swept sine (chirp) for frequency response (ISO 7401 continuous sinusoidal input):
    ``A sin(phi(tau))``, ``tau = t - start_s`` in [0, sweep_time_s], with instantaneous
    frequency ``f(tau) = dphi/dtau / 2 pi`` going from ``f_start_hz`` to ``f_end_hz``,
    linearly (``f0 + (f1 - f0) tau / T``) or logarithmically (``f0 (f1/f0)^(tau/T)``)."""

    amplitude_rad: float = _spec("any", bounds=_ANGLE_RAD)
    f_start_hz: float = _spec(bounds=_FREQUENCY_HZ)
    f_end_hz: float = _spec(bounds=_FREQUENCY_HZ)
    sweep_time_s: float = _spec(bounds=(1e-2, MAX_DURATION_S))
    start_s: float = _spec("nonnegative", default=1.0, bounds=_TIME_S)
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
        s = _smooth_ramp((t - self.start_s) / self.sweep_time_s)
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


@dataclass(frozen=True)
class RandomSteerParams:
    """ISO 7401 random input: band-limited noise with power only within
    [``f_low_hz``, ``f_high_hz``] (brick-wall filter in the frequency domain of seeded white
    noise sampled at ``sample_rate_hz``), scaled to ``rms_rad``, faded in with a raised cosine
    over ``fade_s`` from ``start_s`` and linearly interpolated between samples."""

    rms_rad: float = _spec(bounds=(0.0, MAX_HAND_WHEEL_ANGLE_RAD / RANDOM_PEAK_PER_RMS))
    f_high_hz: float = _spec(bounds=_FREQUENCY_HZ)
    f_low_hz: float = _spec("nonnegative", default=0.0, bounds=(0.0, MAX_STEER_FREQUENCY_HZ))
    length_s: float = _spec(default=60.0, bounds=(1e-2, MAX_DURATION_S))
    seed: int = 0
    start_s: float = _spec("nonnegative", default=1.0, bounds=_TIME_S)
    fade_s: float = _spec("nonnegative", default=1.0, bounds=_TIME_S)
    sample_rate_hz: float = _spec(default=200.0, bounds=(1.0, 1e4))

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def shortest_period_s(self) -> tuple[str, float]:
        """The field setting the shortest period of the input, and that period in s."""
        return "f_high_hz", 1.0 / self.f_high_hz

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


@dataclass(frozen=True)
class PulseParams:
    """ISO 7401 pulse input: a single pulse of ``width_s`` from ``start_s``, ``triangle``
    (area A w / 2) or ``half_sine`` (area 2 A w / pi)."""

    amplitude_rad: float = _spec("any", bounds=_ANGLE_RAD)
    width_s: float = _spec(default=0.4, bounds=(1e-3, MAX_DURATION_S))
    start_s: float = _spec("nonnegative", default=0.5, bounds=_TIME_S)
    shape: str = "triangle"

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def shortest_period_s(self) -> tuple[str, float]:
        """The field setting the shortest period of the input, and that period in s."""
        return "width_s", self.width_s

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if self.shape not in ("triangle", "half_sine"):
            raise ParameterError(f"{prefix}shape",
                                 f"must be triangle or half_sine, got {self.shape!r}", source)

    def steer(self, t: float) -> float:
        """Input angle (rad) at time ``t`` (s)."""
        s = (t - self.start_s) / self.width_s
        if s <= 0.0 or s >= 1.0:
            return 0.0
        if self.shape == "triangle":
            return self.amplitude_rad * (1.0 - abs(2.0 * s - 1.0))
        return self.amplitude_rad * math.sin(math.pi * s)

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


@dataclass(frozen=True)
class ConstantRadiusParams:
    """ISO 4138 constant-radius method (closed loop): the path driver follows a circle of
    ``radius_m`` (``direction`` left or right, tangent to the start pose) while the target
    speed steps from the initial speed by ``speed_step_mps`` every ``dwell_s`` up to
    ``final_speed_mps`` (quasi-steady: each step settles before the next). The run ends after
    the last dwell, or aborts when the path error exceeds ``max_path_error_m`` (the car can no
    longer hold the circle) or the sideslip exceeds ``max_sideslip_rad`` (the car spun; the
    kinematic sideslip b/R of a 40 m circle is ~0.04 rad)."""

    radius_m: float = _spec(bounds=(0.1, 1e4))
    final_speed_mps: float = _spec(bounds=(0.0, MAX_SPEED_MPS))
    speed_step_mps: float = _spec(default=1.0, bounds=(1e-3, MAX_SPEED_MPS))
    dwell_s: float = _spec(default=8.0, bounds=(1e-2, MAX_DURATION_S))
    direction: str = "left"
    # abort thresholds: any small one is meaningful (it ends the run early on purpose)
    max_path_error_m: float = _spec(default=5.0, bounds=(0.0, 1e3))
    max_sideslip_rad: float = _spec(default=0.25, bounds=(0.0, math.pi / 2))

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if self.direction not in ("left", "right"):
            raise ParameterError(f"{prefix}direction",
                                 f"must be left or right, got {self.direction!r}", source)


@dataclass(frozen=True)
class DoubleLaneChangeParams:
    """ISO 3888-2 obstacle-avoidance lane change, driven by the path-tracking driver.

    Track (ISO 3888-2:2011, Table 1; W = ``vehicle_width_m``; the car starts at x = 0, y = 0
    heading +x, section 1 begins ``approach_m`` = x0 ahead, y = 0 on its centre line, lane
    change to the left; positions below relative to x0): section 1 x in [0, 12],
    width 1.1 W + 0.25; section 2 (free) 13.5 m; section 3 x in [25.5, 36.5], width W + 1,
    its right edge 1 m left of the left edge of section 1; section 4 (free) 12.5 m; section 5
    x in [49, 61], width 1.3 W + 0.25 but at least 3 m, its right edge in line with that of
    section 1. The driver's reference line is the widest-margin line through the three gated
    sections (:func:`fourws_sim.corridor.plan_corridor_path`) at the maneuver's speed, with
    its lateral acceleration bounded by ``path_lateral_accel_mps2`` and its lateral jerk by
    ``path_lateral_jerk_mps3``; it starts at the start pose and runs out straight
    ``path_runout_m`` after section 5, on a grid of ``path_step_m``.
    """

    vehicle_width_m: float = _spec(default=1.7, bounds=(0.05, 5.0))
    approach_m: float = _spec(default=30.0, doc="start to section 1, m", bounds=(0.1, 1e3))
    path_lateral_accel_mps2: float = _spec(default=6.25,
                                           doc="line's lateral-acceleration bound",
                                           bounds=(0.1, 30.0))
    path_lateral_jerk_mps3: float = _spec(default=30.0, doc="line's lateral-jerk bound",
                                          bounds=(0.1, 1e3))
    path_runout_m: float = _spec(default=20.0, doc="straight run-out after section 5, m",
                                 bounds=(0.1, 1e3))
    path_step_m: float = _spec(default=0.5, doc="grid step of the line, m", bounds=(0.01, 5.0))

    #: Length of the ISO 3888-2 course from the entry of section 1 to the exit of section 5, m.
    COURSE_LENGTH_M: ClassVar[float] = 61.0

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        points = (self.approach_m + self.COURSE_LENGTH_M + self.path_runout_m) / self.path_step_m
        if points > MAX_PATH_POINTS:
            raise ParameterError(f"{prefix}path_step_m", f"gives a line of {points:.3g} points, "
                                 f"more than the limit {MAX_PATH_POINTS}", source)

    @property
    def sections(self) -> list[tuple[float, float, float, float]]:
        """Gated sections as (x_start, x_end, y_right, y_left) in m (earth frame)."""
        x0 = self.approach_m
        w = self.vehicle_width_m
        w1 = 1.1 * w + 0.25
        w3 = w + 1.0
        w5 = max(1.3 * w + 0.25, 3.0)
        y3_right = 0.5 * w1 + 1.0
        return [(x0, x0 + 12.0, -0.5 * w1, 0.5 * w1),
                (x0 + 25.5, x0 + 36.5, y3_right, y3_right + w3),
                (x0 + 49.0, x0 + 61.0, -0.5 * w1, -0.5 * w1 + w5)]

    def plan(self, speed_mps: float) -> CorridorPlan:
        """The widest-margin line for ``speed_mps`` (m/s), earth frame (cached per input)."""
        return _planned_line(tuple(self.sections), self.vehicle_width_m, float(speed_mps),
                             self.path_lateral_accel_mps2, self.path_lateral_jerk_mps3,
                             self.approach_m + self.COURSE_LENGTH_M + self.path_runout_m,
                             self.path_step_m)

    def path(self, speed_mps: float) -> SplinePath:
        """The driver's reference line for ``speed_mps`` (m/s) as a :class:`SplinePath`."""
        plan = self.plan(speed_mps)
        return SplinePath(plan.x_m, plan.y_m, plan.margin_m)


@functools.lru_cache(maxsize=32)
def _planned_line(sections: tuple[tuple[float, float, float, float], ...], width_m: float,
                  speed_mps: float, accel_mps2: float, jerk_mps3: float, x_end_m: float,
                  step_m: float) -> CorridorPlan:
    """:func:`plan_corridor_path` from the start pose, cached: a run, its twin in the node graph
    and every law of a comparison plan the same line once (two linear programs, ~0.1 s)."""
    plan = plan_corridor_path(sections, width_m, speed_mps, accel_mps2, jerk_mps3,
                              x_start_m=0.0, x_end_m=x_end_m, step_m=step_m)
    plan.x_m.flags.writeable = False
    plan.y_m.flags.writeable = False
    return plan


@dataclass(frozen=True)
class BrakeInTurnParams:
    """Braking in a turn (ch. 8, Figs. 8.23-8.27): ramp steer to ``amplitude_rad`` at
    ``rate_radps`` from ``steer_start_s``; at ``brake_start_s`` a step brake torque meant to give
    ``deceleration_mps2`` (default 0.3 g) is applied for ``brake_duration_s`` (1 s) — total
    torque ``(m + 4 I_w / R^2) R a``: the vehicle mass plus the equivalent mass of the four
    spinning wheels, which the brakes decelerate too (7 % of m on table_8_1; with ``m R a``
    alone the car reaches 0.28 g). The paper applies a step torque (Fig. 8.23), not a
    deceleration controller, and so does fourws. The torque is split by the speed-hold
    ``brake_front_fraction``. No drive torque while braking; afterwards the speed-hold driver
    holds the speed reached at the brake release."""

    amplitude_rad: float = _spec("any", bounds=_ANGLE_RAD)
    rate_radps: float = _spec(bounds=_RATE_RADPS)
    steer_start_s: float = _spec("nonnegative", default=0.5, bounds=_TIME_S)
    brake_start_s: float = _spec("nonnegative", default=2.0, bounds=_TIME_S)
    brake_duration_s: float = _spec(default=1.0, bounds=(1e-3, MAX_DURATION_S))
    deceleration_mps2: float = _spec(default=0.3 * GRAVITY_MPS2, bounds=(0.01, 15.0))

    event_fields: ClassVar[tuple[str, ...]] = ("steer_start_s", "brake_start_s")

    def steer(self, t: float) -> float:
        """Input angle (rad) at time ``t`` (s)."""
        ramp = abs(self.amplitude_rad) / self.rate_radps
        if ramp == 0.0:
            return self.amplitude_rad if t >= self.steer_start_s - _TIME_EPS_S else 0.0
        return self.amplitude_rad * _smooth_ramp((t - self.steer_start_s) / ramp)

    def braking(self, t: float) -> bool:
        """True while the brake torque is applied (edges with a 1 ns tolerance, so tick
        times that differ by rounding, k*Tc vs n*dt, switch at the same tick)."""
        return (self.brake_start_s - _TIME_EPS_S <= t
                < self.brake_start_s + self.brake_duration_s - _TIME_EPS_S)

    def phase(self, t: float) -> str:
        """``settle``, ``steer``, ``brake``, ``hold``."""
        if t < self.steer_start_s:
            return "settle"
        if self.braking(t):
            return "brake"
        if t < self.brake_start_s:
            return "steer"
        return "hold"


#: Maneuver type name -> parameter class.
MANEUVER_TYPES: dict[str, type] = {
    "step_steer": StepSteerParams,
    "ramp_steer": RampSteerParams,
    "sine": SineParams,
    "swept_sine": SweptSineParams,
    "random_steer": RandomSteerParams,
    "pulse": PulseParams,
    "slow_ramp_steer": SlowRampSteerParams,
    "constant_radius": ConstantRadiusParams,
    "double_lane_change": DoubleLaneChangeParams,
    "brake_in_turn": BrakeInTurnParams,
}
#: Maneuver type -> its driver key (path-following types only).
_DRIVER_KEYS = {"constant_radius": "path_driver", "double_lane_change": "tracking_driver"}
_COMMON = ("name", "type", "description", "initial_speed_mps", "duration_s", "steer_input",
           "speed_hold", "path_driver", "tracking_driver", UNCHECKED_KEY)


@dataclass(frozen=True)
class ManeuverSpec:
    """A validated maneuver definition (vehicle independent; see the module docstring)."""

    name: str
    type: str
    initial_speed_mps: float
    duration_s: float
    params: Any
    steer_input: str = "road_wheel"
    description: str = ""
    speed_hold: SpeedHoldSpec = field(default_factory=SpeedHoldSpec)
    path_driver: PathDriverSpec | None = None
    tracking_driver: TrackingDriverSpec | None = None
    source: str = field(default="", compare=False)
    unchecked_fields: frozenset[str] = frozenset()

    def to_dict(self) -> dict[str, Any]:
        """The file layout as a plain mapping (round-trips through :func:`load_maneuver_spec`)."""
        out: dict[str, Any] = {
            "name": self.name, "type": self.type, "description": self.description,
            "initial_speed_mps": self.initial_speed_mps, "duration_s": self.duration_s,
            "steer_input": self.steer_input,
            "speed_hold": dataclasses.asdict(self.speed_hold),
        }
        if self.path_driver is not None:
            out["path_driver"] = dataclasses.asdict(self.path_driver)
        if self.tracking_driver is not None:
            out["tracking_driver"] = dataclasses.asdict(self.tracking_driver)
        to_dict = getattr(self.params, "to_dict", None)
        out.update(to_dict() if to_dict is not None else dataclasses.asdict(self.params))
        if self.unchecked_fields:
            out[UNCHECKED_KEY] = sorted(self.unchecked_fields)
        return out


def available_maneuvers() -> list[str]:
    """Names (file stems) of the shipped maneuver files."""
    return available_configs(MANEUVER_DIR)


def maneuver_spec_from_mapping(data: Any, source: str = "<mapping>",
                               default_name: str = "maneuver") -> ManeuverSpec:
    """Validate a maneuver mapping and build a :class:`ManeuverSpec`.

    Raises
    ------
    UnknownNameError
        ``type`` is not one of :data:`MANEUVER_TYPES`.
    ParameterError
        A field is missing, unknown, of the wrong type, out of range or outside its
        plausibility bounds (names field and file).
    """
    if not isinstance(data, Mapping):
        raise ParameterError("<root>", f"maneuver must be a mapping, got {describe(data)}",
                             source)
    if "type" not in data:
        raise ParameterError("type", f"missing required field (valid: "
                             f"{', '.join(sorted(MANEUVER_TYPES))})", source)
    kind = data["type"]
    if not isinstance(kind, str) or kind not in MANEUVER_TYPES:
        raise UnknownNameError("maneuver type", kind, list(MANEUVER_TYPES), source)
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name:
        raise ParameterError("name", f"must be a non-empty string, got {describe(name)}", source)
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ParameterError("description", f"must be a string, got {describe(description)}",
                             source)
    params_cls = MANEUVER_TYPES[kind]
    unchecked = unchecked_fields_from(data, _maneuver_bounded_fields(params_cls), source)
    common: dict[str, float] = {}
    for key in ("initial_speed_mps", "duration_s"):
        if key not in data:
            raise ParameterError(key, "missing required field", source)
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise ParameterError(key, f"must be a finite number, got {describe(value)}", source)
        common[key] = float(value)
    if common["initial_speed_mps"] < 0.0:
        raise ParameterError("initial_speed_mps", "must be >= 0", source)
    if common["duration_s"] <= 0.0:
        raise ParameterError("duration_s", "must be > 0", source)
    for key, bounds in _COMMON_BOUNDS.items():
        check_plausible(key, common[key], bounds, source, unchecked)
    steer_input = data.get("steer_input", "road_wheel")
    if steer_input not in STEER_INPUTS:
        raise ParameterError("steer_input", f"must be one of {', '.join(STEER_INPUTS)}, "
                                            f"got {describe(steer_input)}", source)
    for key in ("path_driver", "tracking_driver"):
        if key in data and _DRIVER_KEYS.get(kind) != key:
            types = [k for k, v in _DRIVER_KEYS.items() if v == key]
            raise ParameterError(key, f"only for {', '.join(types)}", source)
    type_fields = {k: v for k, v in data.items() if k not in _COMMON}
    params = _from_mapping(params_cls, type_fields, source, "", unchecked)
    if kind == "constant_radius" and params.final_speed_mps < common["initial_speed_mps"]:
        raise ParameterError("final_speed_mps", "must be >= initial_speed_mps", source)
    if kind == "double_lane_change":
        if common["initial_speed_mps"] <= 0.0:
            raise ParameterError("initial_speed_mps", "must be > 0 (the line is planned for it)",
                                 source)
        course_end_m = params.approach_m + params.COURSE_LENGTH_M
        if common["initial_speed_mps"] * common["duration_s"] < course_end_m:
            raise ParameterError("duration_s", f"too short to reach the end of the course "
                                 f"({course_end_m:g} m) at initial_speed_mps", source)
    for key in getattr(params_cls, "event_fields", ()):
        if getattr(params, key) >= common["duration_s"]:
            raise ParameterError(key, f"{getattr(params, key):g} s is not before the end of the "
                                 f"run (duration_s {common['duration_s']:g} s): the input "
                                 "would never be applied", source)
    _check_peak_input(params, steer_input, source, unchecked)
    return ManeuverSpec(
        name=name, type=kind, params=params, steer_input=steer_input,
        description=description,
        speed_hold=speed_hold_spec_from(data.get("speed_hold"), source, unchecked=unchecked),
        path_driver=(path_driver_spec_from(data.get("path_driver"), source,
                                           unchecked=unchecked)
                     if _DRIVER_KEYS.get(kind) == "path_driver" else None),
        tracking_driver=(tracking_driver_spec_from(data.get("tracking_driver"), source,
                                                   unchecked=unchecked)
                         if _DRIVER_KEYS.get(kind) == "tracking_driver" else None),
        source=source, unchecked_fields=unchecked, **common)


#: Plausibility bounds of the fields every maneuver has.
_COMMON_BOUNDS = {"initial_speed_mps": (0.0, MAX_SPEED_MPS), "duration_s": (1e-3, MAX_DURATION_S)}


def _maneuver_bounded_fields(params_cls: type) -> set[str]:
    """Names ``unchecked_fields`` of a maneuver of this parameter class may list."""
    return {*_COMMON_BOUNDS, *bounded_fields(params_cls),
            *bounded_fields(SpeedHoldSpec, "speed_hold."),
            *bounded_fields(PathDriverSpec, "path_driver."),
            *bounded_fields(TrackingDriverSpec, "tracking_driver.")}


def _peak_input(params: Any) -> tuple[str, float] | None:
    """The field that sets the largest open-loop input angle and that angle (rad, in the unit
    of ``steer_input``); None for closed-loop types."""
    if isinstance(params, RandomSteerParams):
        return "rms_rad", RANDOM_PEAK_PER_RMS * params.rms_rad
    if getattr(params, "amplitude_rad", None) is not None:  # None: a step still to resolve
        return "amplitude_rad", abs(params.amplitude_rad)
    return None


def _check_peak_input(params: Any, steer_input: str, source: str | None,
                      unchecked: frozenset[str]) -> None:
    peak = _peak_input(params)
    if peak is None or peak[0] in unchecked:
        return
    limit, what = ((MAX_ROAD_WHEEL_ANGLE_RAD, "road-wheel") if steer_input == "road_wheel"
                   else (MAX_HAND_WHEEL_ANGLE_RAD, "hand-wheel"))
    if peak[1] > limit:
        raise ParameterError(peak[0], f"asks for a {what} angle of {peak[1]:.4g} rad, beyond the "
                             f"plausible {limit:.4g} rad (list it under {UNCHECKED_KEY} to "
                             "accept it)", source)


def check_sampling(spec: ManeuverSpec, control_period_s: float, source: str | None) -> None:
    """Refuse an input the control rate cannot represent: its shortest period (a sine's, the
    end of a sweep, a random input's band edge, a pulse's width) must span more than two
    control periods, i.e. its frequency must lie below the Nyquist frequency of the control
    rate (the driver samples the input once per control period; a sine at exactly the Nyquist
    frequency may be sampled at its zeros only).

    Raises
    ------
    ParameterError
        Naming the maneuver field and the control period (never lifted by
        ``unchecked_fields``: the run would not contain the input asked for).
    """
    shortest = getattr(spec.params, "shortest_period_s", None)
    if shortest is None:
        return
    key, period = shortest()
    if period <= 2.0 * control_period_s:
        raise ParameterError(f"maneuver.{key}", f"its period {period:.4g} s is not longer than "
                             f"two control periods ({control_period_s:g} s): not below the "
                             f"control rate's Nyquist frequency {0.5 / control_period_s:g} Hz",
                             source)


def resolve_maneuver_path(name_or_path: str | FilePath) -> FilePath:
    """A maneuver name (file stem under ``config/maneuvers``) or a path, as a path."""
    return resolve_config_path("maneuver", name_or_path, MANEUVER_DIR)


def load_maneuver_spec(name_path_or_mapping: str | FilePath | Mapping[str, Any]
                       ) -> ManeuverSpec:
    """Load a maneuver by name, YAML path, or an inline mapping (e.g. from a recorded run)."""
    if isinstance(name_path_or_mapping, Mapping):
        return maneuver_spec_from_mapping(name_path_or_mapping, "<inline maneuver>")
    path = resolve_maneuver_path(name_path_or_mapping)
    return maneuver_spec_from_mapping(read_yaml(path), str(path), default_name=path.stem)


# ---------------------------------------------------------------------------- runtime

class Maneuver:
    """A maneuver bound to a vehicle, with its drivers' state (one instance per run).

    Parameters
    ----------
    spec : ManeuverSpec
        The validated definition.
    vehicle : Vehicle
        The simulated vehicle (steering ratio, mass, wheel radius, wheelbase, understeer).
    """

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        self.spec = spec
        self.vehicle = vehicle
        p = spec.params
        if spec.steer_input == "steering_wheel":
            vehicle.require("steering", user=f"maneuver {spec.name!r} (steer_input "
                                             "steering_wheel)")
        # Vehicles with no steering data report the hand-wheel angle equal to the road-wheel
        # angle (ratio 1); they only run road-wheel inputs.
        self._ratio = vehicle.steering.ratio if vehicle.steering is not None else 1.0
        peak = _peak_input(p)
        if (spec.steer_input == "steering_wheel" and peak is not None
                and peak[0] not in spec.unchecked_fields
                and peak[1] / self._ratio > MAX_ROAD_WHEEL_ANGLE_RAD):
            raise ParameterError(peak[0], f"asks for a road-wheel angle of "
                                 f"{peak[1] / self._ratio:.4g} rad on {vehicle.name} (steering "
                                 f"ratio {self._ratio:g}), beyond the plausible "
                                 f"{MAX_ROAD_WHEEL_ANGLE_RAD:g} rad (list it under "
                                 f"{UNCHECKED_KEY} to accept it)", spec.source or spec.name)
        self._speed_driver = SpeedHoldDriver(spec.speed_hold, vehicle)
        self._path_driver: PreviewPathDriver | PathTrackingDriver | None = None
        self._random: np.ndarray | None = None
        self._random_index = np.empty(0)
        self._hold_after_brake_mps: float | None = None
        self._aborted = ""
        self._end_condition = False
        if not getattr(p, "resolved", True):
            raise ParameterError(
                "target_lateral_accel_mps2", "the step amplitude for this target is found per "
                "law before a run (fourws run and run_scenario do it, see "
                "fourws_run.step_target.resolve_maneuver_for_law); this maneuver was not "
                "resolved", spec.source or spec.name)
        if spec.type == "constant_radius":
            direction = 1 if p.direction == "left" else -1
            assert spec.path_driver is not None
            self._path_driver = PreviewPathDriver(spec.path_driver, vehicle,
                                                  CirclePath(p.radius_m, direction))
        elif spec.type == "double_lane_change":
            assert spec.tracking_driver is not None
            self._path_driver = PathTrackingDriver(spec.tracking_driver, vehicle,
                                                   p.path(spec.initial_speed_mps))
        elif spec.type == "random_steer":
            self._random = p.samples()
            self._random_index = np.arange(self._random.size, dtype=float)

    # -- the interface -------------------------------------------------------------------
    @property
    def name(self) -> str:
        """Maneuver name."""
        return self.spec.name

    @property
    def reference_path(self) -> ReferencePath | None:
        """The path the path-following driver follows (None for open-loop types)."""
        return None if self._path_driver is None else self._path_driver.path

    @property
    def initial_speed_mps(self) -> float:
        """Speed (m/s) the simulator is reset to."""
        return self.spec.initial_speed_mps

    @property
    def duration_s(self) -> float:
        """Planned duration in s (a run may end earlier, see :meth:`done`)."""
        return self.spec.duration_s

    def steer_input(self, t: float) -> float:
        """Open-loop input angle (rad, in the unit of ``steer_input``) at time ``t``."""
        p = self.spec.params
        if self.spec.type == "random_steer":
            assert self._random is not None
            tau = t - p.start_s
            if tau <= 0.0:
                return 0.0
            fade = 1.0 if p.fade_s == 0.0 else 0.5 * (1.0 - math.cos(
                math.pi * _smooth_ramp(tau / p.fade_s)))
            return fade * float(np.interp(tau * p.sample_rate_hz, self._random_index,
                                          self._random))
        return float(p.steer(t))

    def target_speed_mps(self, t: float) -> float:
        """Speed the speed-hold driver aims at (m/s)."""
        p = self.spec.params
        if self.spec.type == "constant_radius":
            steps = math.floor((t + _TIME_EPS_S) / p.dwell_s)
            return min(self.initial_speed_mps + steps * p.speed_step_mps, p.final_speed_mps)
        if self._hold_after_brake_mps is not None:
            return self._hold_after_brake_mps
        return self.initial_speed_mps

    def command(self, t: float, outputs: Mapping[str, Any]) -> DriverCommand:
        """Driver command at tick time ``t`` (s) from the vehicle outputs (stateful).

        Parameters
        ----------
        t : float
            Tick time in s (``VehicleState.sim_time_s``), increasing from call to call.
        outputs : mapping
            ``VehicleState`` fields; read here: ``speed_mps`` (all types), ``x_m``, ``y_m``,
            ``heading_rad``, ``yaw_rate_radps`` (path-following types), ``sideslip_rad`` and
            ``lateral_accel_mps2`` (``double_lane_change``). :meth:`done` also reads
            ``lateral_accel_mps2`` and ``sideslip_rad``.
        """
        speed = float(outputs["speed_mps"])
        if self._path_driver is not None:
            front = self._path_driver.steer(t, outputs)
            hand = front * self._ratio
        else:
            angle = self.steer_input(t)
            if self.spec.steer_input == "steering_wheel":
                hand, front = angle, angle / self._ratio
            else:
                hand, front = angle * self._ratio, angle
        if self.spec.type == "brake_in_turn":
            p = self.spec.params
            if p.braking(t):
                self._speed_driver.command(t, speed, speed)  # keeps its clock, no integration
                total = self._brake_torque_nm(p.deceleration_mps2)
                brake = split_brake_torque(total, self.spec.speed_hold.brake_front_fraction)
                return DriverCommand(hand, front, 0.0, (0.0, 0.0, 0.0, 0.0), brake)
            if t >= p.brake_start_s - _TIME_EPS_S and self._hold_after_brake_mps is None:
                self._hold_after_brake_mps = speed
                self._speed_driver.reset()
        drive, brake = self._speed_driver.command(t, speed, self.target_speed_mps(t))
        return DriverCommand(hand, front, 0.0, drive, brake)

    def _brake_torque_nm(self, decel_mps2: float) -> float:
        """Total brake torque (N m) for ``decel_mps2``: ``(m + 4 I_w / R^2) R a``."""
        self.vehicle.require("body", user="maneuver brake_in_turn (brake torque from m, R, I_w)")
        body = self.vehicle.body
        assert body is not None
        radius = body.wheel_radius_m
        mass = self.vehicle.chassis.mass_kg + 4.0 * body.wheel_spin_inertia_kgm2 / radius ** 2
        return mass * radius * decel_mps2

    def phase(self, t: float) -> str:
        """Name of the phase at time ``t`` (``done`` at or after the duration)."""
        if self._aborted:
            return "done"
        if t >= self.duration_s - _TIME_EPS_S:
            return "done"
        kind, p = self.spec.type, self.spec.params
        if kind == "random_steer":
            return "settle" if t < p.start_s else "random"
        if kind == "constant_radius":
            return f"speed_{self.target_speed_mps(t):.2f}_mps"
        if kind == "double_lane_change":
            x = t * self.initial_speed_mps - p.approach_m  # nominal position in the course
            return "approach" if x < 0.0 else ("course" if x < 61.0 else "exit")
        return p.phase(t)

    def progress(self, t: float) -> float:
        """Fraction of the planned duration elapsed, in [0, 1]."""
        return min(max(t / self.duration_s, 0.0), 1.0)

    @property
    def abort_reason(self) -> str:
        """Why the run ended early ('' if it did not)."""
        return self._aborted

    @property
    def end_kind(self) -> str:
        """How the maneuver ended: ``completed`` (its duration), ``end_condition`` (the stop
        criterion it is designed to reach, e.g. the ISO 4138 lateral-acceleration limit) or
        ``aborted`` (the car or the driver could not do it: spun, left the path). Meaningful
        once :meth:`done` is true."""
        if not self._aborted:
            return "completed"
        return "end_condition" if self._end_condition else "aborted"

    def done(self, t: float, outputs: Mapping[str, Any] | None = None) -> bool:
        """True once the run may end: duration reached, or an end condition of the type."""
        if self._aborted:
            return True
        if t >= self.duration_s - _TIME_EPS_S:
            return True
        if outputs is None:
            return False
        kind, p = self.spec.type, self.spec.params
        if kind == "slow_ramp_steer":
            if abs(float(outputs["lateral_accel_mps2"])) >= p.max_lateral_accel_mps2:
                self._aborted = "lateral acceleration limit reached"
                self._end_condition = True
            elif abs(float(outputs.get("sideslip_rad", 0.0))) > p.max_sideslip_rad:
                self._aborted = "sideslip limit reached (the car spins)"
        elif kind == "constant_radius" and self._path_driver is not None:
            error = self._path_driver.path.lateral_error(float(outputs["x_m"]),
                                                         float(outputs["y_m"]))
            sideslip = float(outputs.get("sideslip_rad", 0.0))
            if abs(error) > p.max_path_error_m:
                self._aborted = f"path error {error:.2f} m exceeds max_path_error_m"
            elif abs(sideslip) > p.max_sideslip_rad:
                self._aborted = f"sideslip {sideslip:.2f} rad exceeds max_sideslip_rad (spun)"
        return bool(self._aborted)

    def to_dict(self) -> dict[str, Any]:
        """The maneuver definition as a plain mapping (for the run configuration)."""
        return self.spec.to_dict()


def make_maneuver(spec_or_name: ManeuverSpec | str | FilePath | Mapping[str, Any],
                  vehicle: Vehicle) -> Maneuver:
    """Build a runnable :class:`Maneuver` for ``vehicle`` from a spec, name, path or mapping."""
    spec = (spec_or_name if isinstance(spec_or_name, ManeuverSpec)
            else load_maneuver_spec(spec_or_name))
    return Maneuver(spec, vehicle)


__all__ = [
    "BrakeInTurnParams", "ConstantRadiusParams", "DoubleLaneChangeParams", "DriverCommand",
    "MANEUVER_DIR", "MANEUVER_TYPES", "Maneuver", "ManeuverSpec", "PulseParams",
    "RampSteerParams", "RandomSteerParams", "STEER_INPUTS", "SineParams", "SlowRampSteerParams",
    "StepSteerParams", "SweptSineParams", "available_maneuvers", "load_maneuver_spec",
    "make_maneuver", "maneuver_spec_from_mapping", "resolve_maneuver_path",
]
