# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""The electronic-stability-control test maneuvers: slowly increasing steer and sine with dwell
(FMVSS No. 126 S7.6 and S7.9; UN R13-H annex 9 and UN GTR 8 describe the same tests).

Angles are steering-wheel angles (the regulation's): the road-wheel angle is the steering-wheel
angle over the vehicle's ``steering.ratio`` (both types fix ``steer_input: steering_wheel``).
Signs: positive steers left (ISO 8855; the regulation calls it counter-clockwise).

Slowly increasing steer (S7.6): at 80 km/h held constant, the steering-wheel angle grows at
13.5 deg/s until the lateral acceleration reaches about 0.5 g. The run gives the steering-wheel
angle that produces 0.3 g of lateral acceleration in the steady state, from a linear
regression of the (filtered, zeroed) steering-wheel angle on the lateral acceleration
(:func:`reference_amplitude_rad`); A is the mean of its magnitude over the runs in both
directions, rounded to 0.1 deg (S7.6.1; UN R13-H regresses at 3.0 m/s^2 instead of 0.3 g:
``REFERENCE_LATERAL_ACCEL_MPS2`` is one constant).

Sine with dwell (S7.9): from 80 km/h, coasting (drive torque released), one period of a
0.7 Hz sine of amplitude ``amplitude_rad`` with a 500 ms dwell at its second peak:

.. math::

    \delta_H(\tau) = \begin{cases}
        A_s \sin(2\pi f\tau) & 0 \le \tau < \tfrac{3}{4f} \\
        -A_s & \tfrac{3}{4f} \le \tau < \tfrac{3}{4f} + t_d \\
        A_s \sin(2\pi f(\tau - t_d)) & \tfrac{3}{4f} + t_d \le \tau \le \tfrac1f + t_d \\
        0 & \text{otherwise,}
    \end{cases} \qquad \tau = t - t_0 .

Its amplitude is a multiple of A (``amplitude_factor``; 1.5 A to the larger of 6.5 A and
270 deg in steps of 0.5 A, at most 300 deg, both directions: :func:`regulation_series`). A
sine with dwell given by its factor, without A, is resolved for each law before its runs (the
run layer runs the slowly increasing steer with the law, :mod:`fourws_run.closed_loop`), as a
step to a target lateral acceleration is; a resolved one records A, the law it was found for
and the amplitude that runs.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

import numpy as np

from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers.base import (MAX_HAND_WHEEL_ANGLE_RAD, RATE_BOUNDS_RADPS,
                                       TIME_BOUNDS_S, TIME_EPS_S, Maneuver, ManeuverSpec,
                                       finite_or_none, smooth_ramp)
from fourws_sim.params import GRAVITY_MPS2, Vehicle, _spec

#: Test speed, m/s (80 km/h, S7.6 and S7.9; the regulation's tolerance is +-2 km/h).
TEST_SPEED_MPS = 80.0 / 3.6
#: Steering-wheel rate of the slowly increasing steer, rad/s (13.5 deg/s, S7.6).
SIS_RATE_RADPS = math.radians(13.5)
#: The slowly increasing steer runs until about 0.5 g (S7.6), m/s^2.
SIS_END_LATERAL_ACCEL_MPS2 = 0.5 * GRAVITY_MPS2
#: A is the steering-wheel angle of this steady lateral acceleration (0.3 g, S7.6.1), m/s^2.
REFERENCE_LATERAL_ACCEL_MPS2 = 0.3 * GRAVITY_MPS2
#: Lateral accelerations whose samples enter the regression of A, m/s^2: 0.1 g to 0.375 g
#: (NHTSA's data-processing procedure for FMVSS No. 126, the SIS analysis).
REGRESSION_RANGE_MPS2 = (0.1 * GRAVITY_MPS2, 0.375 * GRAVITY_MPS2)
#: A is rounded to this, rad (0.1 deg, S7.6.1).
REFERENCE_ROUNDING_RAD = math.radians(0.1)
#: Cut-off frequencies of the 12-pole phaseless Butterworth filters (S7.11.1-S7.11.3), Hz.
STEERING_FILTER_HZ = 10.0
MOTION_FILTER_HZ = 6.0
#: Order of the filter run forward and backward (6 + 6 = the regulation's 12 poles).
FILTER_ORDER = 6
#: Sine with dwell: frequency (Hz) and dwell at the second peak (s), S7.9.
SWD_FREQUENCY_HZ = 0.7
SWD_DWELL_S = 0.5
#: The amplitude series (S7.9.4): first factor, step, last factor, and the larger-of and
#: at-most steering-wheel angles, rad.
SERIES_FIRST_FACTOR = 1.5
SERIES_STEP_FACTOR = 0.5
SERIES_LAST_FACTOR = 6.5
SERIES_FLOOR_RAD = math.radians(270.0)
SERIES_CAP_RAD = math.radians(300.0)


def phaseless_lowpass(x: np.ndarray, dt_s: float, cutoff_hz: float) -> np.ndarray:
    """The regulation's "12-pole phaseless Butterworth" low-pass: a 6th-order Butterworth
    (second-order sections) run forward and backward (scipy ``sosfiltfilt``), so the
    magnitude falls as a 12th-order filter's and the phase is zero. Records too short for the
    filter's padding are returned unfiltered (a simulated record has no sensor noise)."""
    # imported here: scipy.signal takes about a second to import, and only the regulation's
    # data processing needs it, not every process that plays a maneuver (the maneuver node)
    import scipy.signal

    x = np.asarray(x, dtype=float)
    nyquist = 0.5 / dt_s
    if cutoff_hz >= nyquist:
        return x.copy()
    sos = scipy.signal.butter(FILTER_ORDER, cutoff_hz / nyquist, output="sos")
    pad = 3 * (2 * len(sos) + 1)
    if x.size <= pad:
        return x.copy()
    return scipy.signal.sosfiltfilt(sos, x)


def zeroed(x: np.ndarray, t: np.ndarray, before_s: float) -> np.ndarray:
    """``x`` less its mean over ``t < before_s`` (the regulation zeroes each channel with the
    static data before the maneuver); unchanged when no sample precedes ``before_s``."""
    x = np.asarray(x, dtype=float)
    pre = np.asarray(t) < before_s
    return x - float(np.mean(x[pre])) if np.any(pre) else x.copy()


def reference_amplitude_rad(t: np.ndarray, steering_wheel_rad: np.ndarray,
                            lateral_accel_mps2: np.ndarray, start_s: float = 0.0,
                            reference_mps2: float = REFERENCE_LATERAL_ACCEL_MPS2,
                            window_mps2: tuple[float, float] = REGRESSION_RANGE_MPS2) -> float:
    """The steering-wheel angle (rad, signed) of ``reference_mps2`` lateral acceleration in one
    slowly-increasing-steer run: both channels filtered (:func:`phaseless_lowpass`, 10 Hz and
    6 Hz) and zeroed (:func:`zeroed`, before ``start_s``), the angle regressed linearly on the
    lateral acceleration over the samples with ``|a_y|`` in ``window_mps2`` (least squares,
    ``numpy.polyfit``) and evaluated at ``reference_mps2`` in the run's direction.

    Raises
    ------
    ParameterError
        Fewer than 3 samples in the window (the run did not reach 0.375 g).
    """
    t = np.asarray(t, dtype=float)
    dt = float(np.median(np.diff(t)))
    swa = zeroed(phaseless_lowpass(steering_wheel_rad, dt, STEERING_FILTER_HZ), t, start_s)
    ay = zeroed(phaseless_lowpass(lateral_accel_mps2, dt, MOTION_FILTER_HZ), t, start_s)
    lo, hi = window_mps2
    # the part of the run up to its largest |a_y|: the regression of the quasi-steady ramp
    end = int(np.argmax(np.abs(ay))) + 1
    sel = (np.abs(ay[:end]) >= lo) & (np.abs(ay[:end]) <= hi)
    if np.count_nonzero(sel) < 3:
        raise ParameterError("slowly_increasing_steer", f"the run reaches |a_y| = "
                             f"{float(np.max(np.abs(ay))):.3g} m/s^2; the regression of A needs "
                             f"samples from {lo:.3g} to {hi:.3g} m/s^2")
    slope, intercept = np.polyfit(ay[:end][sel], swa[:end][sel], 1)
    direction = math.copysign(1.0, float(np.mean(ay[:end][sel])))
    return float(intercept + slope * direction * reference_mps2)


def round_reference(amplitude_rad: float) -> float:
    """A rounded to the nearest 0.1 deg (S7.6.1), rad."""
    return round(amplitude_rad / REFERENCE_ROUNDING_RAD) * REFERENCE_ROUNDING_RAD


def series_factors(reference_rad: float) -> list[float]:
    """The amplitude factors (multiples of A) of one direction's series for A =
    ``reference_rad`` (S7.9.4): 1.5 A, then up by 0.5 A from run to run; the final run has
    the larger of 6.5 A and 270 deg, unless that is beyond 300 deg, when it has 300 deg. So
    the final amplitude is ``min(max(6.5 A, 270 deg), 300 deg)`` and the runs before it are
    the 0.5 A steps below it.

    Raises
    ------
    ParameterError
        A is not > 0.
    """
    a = abs(reference_rad)
    if not a > 0.0:
        raise ParameterError("reference_amplitude_rad", f"must be > 0, got {reference_rad!r}")
    last = min(max(SERIES_LAST_FACTOR * a, SERIES_FLOOR_RAD), SERIES_CAP_RAD)
    factors = []
    factor = SERIES_FIRST_FACTOR
    while factor * a < last * (1.0 - 1e-12):
        factors.append(factor)
        factor += SERIES_STEP_FACTOR
    factors.append(last / a)
    return factors


class SteeringWheelManeuver(Maneuver):
    """A maneuver defined in steering-wheel angles (the file's ``steer_input`` must be, and
    defaults to, ``steering_wheel``)."""

    default_steer_input = "steering_wheel"
    fixed_steer_input = True


@dataclass(frozen=True)
class SlowlyIncreasingSteerParams:
    """FMVSS No. 126 S7.6 slowly increasing steer (module docstring): from ``start_s`` the
    steering-wheel angle grows at ``rate_radps`` (13.5 deg/s) in ``direction`` (``left`` or
    ``right``) up to ``max_steering_wheel_rad``; the run ends when ``|a_y|`` reaches
    ``max_lateral_accel_mps2`` (0.5 g, the designed end), or when the sideslip exceeds
    ``max_sideslip_rad`` (it leaves steady-state cornering; whether it spun is the run's
    vehicle limits' call)."""

    rate_radps: float = _spec(default=SIS_RATE_RADPS, bounds=RATE_BOUNDS_RADPS)
    direction: str = "left"
    start_s: float = _spec("nonnegative", default=1.0, bounds=TIME_BOUNDS_S)
    max_steering_wheel_rad: float = _spec(default=math.radians(540.0),
                                          bounds=(0.0, MAX_HAND_WHEEL_ANGLE_RAD))
    # end conditions: any small threshold is meaningful (it ends the run early on purpose)
    max_lateral_accel_mps2: float = _spec(default=SIS_END_LATERAL_ACCEL_MPS2,
                                          bounds=(0.0, 30.0))
    max_sideslip_rad: float = _spec(default=0.15, bounds=(0.0, math.pi / 2))

    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if self.direction not in ("left", "right"):
            raise ParameterError(f"{prefix}direction",
                                 f"must be left or right, got {self.direction!r}", source)

    @property
    def sign(self) -> float:
        """+1 left, -1 right."""
        return 1.0 if self.direction == "left" else -1.0

    def steer(self, t: float) -> float:
        """Steering-wheel angle (rad) at ``t`` (s)."""
        ramp = self.max_steering_wheel_rad / self.rate_radps
        return self.sign * self.max_steering_wheel_rad * smooth_ramp((t - self.start_s) / ramp)

    def phase(self, t: float) -> str:
        """``settle``, ``steer``."""
        return "settle" if t < self.start_s else "steer"


class SlowlyIncreasingSteer(SteeringWheelManeuver):
    """FMVSS No. 126 slowly increasing steer (:class:`SlowlyIncreasingSteerParams`)."""

    Params = SlowlyIncreasingSteerParams

    def check_end(self, t: float, outputs: Mapping[str, Any]) -> None:
        """End at the lateral-acceleration limit or abort when the car spins."""
        self.end_at_limits(outputs, self.params.max_lateral_accel_mps2,
                           self.params.max_sideslip_rad)


@dataclass(frozen=True)
class SineWithDwellParams:
    """FMVSS No. 126 S7.9 sine with dwell (module docstring).

    The amplitude (steering wheel, rad, > 0) is ``amplitude_rad``, or ``amplitude_factor``
    times A = ``reference_amplitude_rad``; without A the maneuver is resolved for each law
    before it runs (A from the slowly increasing steer ``reference_maneuver`` run with the
    law in both directions), and then records A, the law (``reference_law``) and the
    amplitude. ``direction`` is that of the first half wave. The sine starts at ``start_s``
    (the drive torque is released there: the car coasts), ``frequency_hz`` 0.7 and
    ``dwell_s`` 0.5 are the regulation's.
    """

    amplitude_rad: float | None = None
    amplitude_factor: float | None = None
    reference_amplitude_rad: float | None = None
    reference_law: str = ""
    reference_maneuver: str = "slowly_increasing_steer"
    direction: str = "left"
    start_s: float = _spec("nonnegative", default=1.0, bounds=TIME_BOUNDS_S)
    frequency_hz: float = _spec(default=SWD_FREQUENCY_HZ, bounds=(1e-3, 20.0))
    dwell_s: float = _spec("nonnegative", default=SWD_DWELL_S, bounds=TIME_BOUNDS_S)

    #: Plausibility bounds of the optional number fields: steering-wheel angles (rad) and the
    #: factor of A (the regulation's series reaches 300 deg / A).
    OPTIONAL_BOUNDS: ClassVar[Mapping[str, tuple[float, float]]] = {
        "amplitude_rad": (0.0, MAX_HAND_WHEEL_ANGLE_RAD),
        "amplitude_factor": (0.0, 100.0),
        "reference_amplitude_rad": (0.0, MAX_HAND_WHEEL_ANGLE_RAD)}
    event_fields: ClassVar[tuple[str, ...]] = ("start_s",)

    def shortest_period_s(self) -> tuple[str, float]:
        """The field setting the shortest period of the input, and that period in s."""
        return "frequency_hz", 1.0 / self.frequency_hz

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        finite_or_none(self, self.OPTIONAL_BOUNDS, source, prefix, unchecked)
        if self.direction not in ("left", "right"):
            raise ParameterError(f"{prefix}direction",
                                 f"must be left or right, got {self.direction!r}", source)
        for name in ("amplitude_rad", "amplitude_factor", "reference_amplitude_rad"):
            value = getattr(self, name)
            if value is not None and not value > 0.0:
                raise ParameterError(f"{prefix}{name}", f"must be > 0 (direction gives the "
                                     f"sign), got {value!r}", source)
        if self.amplitude_rad is None and self.amplitude_factor is None:
            raise ParameterError(f"{prefix}amplitude_rad", "missing: give amplitude_rad or "
                                 "amplitude_factor (a multiple of A)", source)
        if not isinstance(self.reference_law, str) or not isinstance(
                self.reference_maneuver, str) or not self.reference_maneuver:
            raise ParameterError(f"{prefix}reference_maneuver",
                                 "must be a maneuver name (and reference_law a law name)", source)

    @property
    def resolved(self) -> bool:
        """The amplitude is known."""
        return self.amplitude_rad is not None

    @property
    def sign(self) -> float:
        """+1 left, -1 right (the first half wave)."""
        return 1.0 if self.direction == "left" else -1.0

    @property
    def steer_time_s(self) -> float:
        """Time from the start to the completion of the steer, s (1/f + dwell)."""
        return 1.0 / self.frequency_hz + self.dwell_s

    def steer(self, t: float) -> float:
        """Steering-wheel angle (rad) at ``t`` (s)."""
        tau = t - self.start_s
        f = self.frequency_hz
        amp = self.sign * (self.amplitude_rad or 0.0)
        if tau < 0.0 or tau > self.steer_time_s:
            return 0.0
        peak2 = 0.75 / f
        if tau < peak2:
            return amp * math.sin(2.0 * math.pi * f * tau)
        if tau < peak2 + self.dwell_s:
            return -amp
        return amp * math.sin(2.0 * math.pi * f * (tau - self.dwell_s))

    def phase(self, t: float) -> str:
        """``settle``, ``sine``, ``dwell``, ``return``, ``coast``."""
        tau = t - self.start_s
        peak2 = 0.75 / self.frequency_hz
        if tau < 0.0:
            return "settle"
        if tau < peak2:
            return "sine"
        if tau < peak2 + self.dwell_s:
            return "dwell"
        return "return" if tau <= self.steer_time_s else "coast"

    def to_dict(self) -> dict[str, Any]:
        """The fields, leaving out the empty optional ones."""
        out = dataclasses.asdict(self)
        for name in ("amplitude_rad", "amplitude_factor", "reference_amplitude_rad"):
            if out[name] is None:
                del out[name]
        if not out["reference_law"]:
            del out["reference_law"]
        return out


class SineWithDwell(SteeringWheelManeuver):
    """FMVSS No. 126 sine with dwell (:class:`SineWithDwellParams`): the speed-hold driver
    holds the test speed until the steer starts, then the drive torque is released (coast).

    Raises
    ------
    ParameterError
        The amplitude is a multiple of an A not yet found for a law.
    """

    Params = SineWithDwellParams

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        super().__init__(spec, vehicle)
        if not spec.params.resolved:
            raise ParameterError(
                "amplitude_factor", "the sine-with-dwell amplitude is a multiple of A, which "
                "is found per law before a run (fourws run and run_series do it, see "
                "fourws_run.step_target.resolve_maneuver_for_law); this maneuver was not "
                "resolved", spec.source or spec.name)

    def command(self, t: float, outputs: Mapping[str, Any]) -> DriverCommand:
        """The steering wheel's sine with dwell; coasting (no drive or brake torque) from the
        start of the steer."""
        if t < self.params.start_s - TIME_EPS_S:
            return super().command(t, outputs)
        speed = float(outputs["speed_mps"])
        hand, front = self.steer_angles(t, outputs)
        self._speed_driver.command(t, speed, speed)  # keeps its clock, no integration
        return DriverCommand(hand, front, 0.0)


def resolved_sine_with_dwell(spec: ManeuverSpec, reference_rad: float, law: str,
                             factor: float | None = None, direction: str | None = None
                             ) -> ManeuverSpec:
    """``spec`` (a sine with dwell) with A = ``reference_rad`` found for ``law``: the amplitude
    ``factor`` x A (``spec``'s factor when None; at most 300 deg), in ``direction``, named
    after the direction and the factor (``<name>_L2.5A``)."""
    p = spec.params
    factor = p.amplitude_factor if factor is None else factor
    if factor is None:
        raise ParameterError("amplitude_factor", "missing: the amplitude is not a multiple of A",
                             spec.source or spec.name)
    direction = p.direction if direction is None else direction
    amplitude = min(factor * abs(reference_rad), SERIES_CAP_RAD)
    params = dataclasses.replace(p, amplitude_rad=amplitude, amplitude_factor=factor,
                                 reference_amplitude_rad=abs(reference_rad), reference_law=law,
                                 direction=direction)
    label = f"{spec.name}_{direction[0].upper()}{factor:.4g}A"
    return dataclasses.replace(spec, name=label, params=params)


def regulation_series(spec: ManeuverSpec, reference_rad: float, law: str
                      ) -> list[ManeuverSpec]:
    """The FMVSS No. 126 S7.9 series of sine-with-dwell runs for A = ``reference_rad``: left
    first half wave through the amplitude factors of :func:`series_factors`, then right."""
    return [resolved_sine_with_dwell(spec, reference_rad, law, factor, direction)
            for direction in ("left", "right") for factor in series_factors(reference_rad)]


__all__ = ["MOTION_FILTER_HZ", "REFERENCE_LATERAL_ACCEL_MPS2", "REGRESSION_RANGE_MPS2",
           "SIS_RATE_RADPS", "STEERING_FILTER_HZ", "SWD_DWELL_S", "SWD_FREQUENCY_HZ",
           "SineWithDwell", "SineWithDwellParams", "SlowlyIncreasingSteer",
           "SlowlyIncreasingSteerParams", "TEST_SPEED_MPS", "phaseless_lowpass",
           "reference_amplitude_rad", "regulation_series", "resolved_sine_with_dwell",
           "round_reference", "series_factors", "zeroed"]
