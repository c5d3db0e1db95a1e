# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""What every maneuver type shares: the validated definition and the runtime base class.

A maneuver type is a subclass of :class:`Maneuver` that names its parameter class
(:attr:`Maneuver.Params`, a frozen dataclass validated by :func:`fourws_sim.params._from_mapping`
rules) and overrides only what it does differently: the open-loop input angle
(:meth:`Maneuver.steer_input`), the steering angles of a closed-loop driver
(:meth:`Maneuver.steer_angles`), the speed target (:meth:`Maneuver.target_speed_mps`), the
whole command (:meth:`Maneuver.command`), the phase names (:meth:`Maneuver.type_phase`) or an
end condition (:meth:`Maneuver.check_end`). The registry
(:mod:`fourws_sim.maneuvers.registry`) maps the file's ``type`` to the class.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar, Mapping

from fourws_sim.drivers import Path as ReferencePath
from fourws_sim.drivers import (DriverCommand, PathDriverSpec, SpeedHoldDriver, SpeedHoldSpec,
                                TrackingDriverSpec)
from fourws_sim.errors import ParameterError, describe
from fourws_sim.outcome import DEFAULT_LIMITS, VehicleLimits
from fourws_sim.params import UNCHECKED_KEY, Vehicle, check_plausible

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
#: Plausibility bounds shared by the types' fields: times (s), angles (rad), steering
#: frequencies (Hz), steering rates (rad/s).
TIME_BOUNDS_S = (0.0, MAX_DURATION_S)
ANGLE_BOUNDS_RAD = (-MAX_HAND_WHEEL_ANGLE_RAD, MAX_HAND_WHEEL_ANGLE_RAD)
FREQUENCY_BOUNDS_HZ = (1e-3, MAX_STEER_FREQUENCY_HZ)
RATE_BOUNDS_RADPS = (1e-4, 100.0)
#: How a maneuver type steers: ``angle`` (fixed steering control: the driver's angle is the
#: front road-wheel angle) or ``torque`` (free steering control: the driver's torque drives a
#: steering system, the front angle is a state of the model).
STEERING_CONTROLS = ("angle", "torque")
#: Tolerance on ``t >= duration`` so a tick time k*Tc that lands a rounding error short of the
#: duration still ends the run (s; far below any control period).
TIME_EPS_S = 1e-9


def smooth_ramp(s: float) -> float:
    """Linear 0 -> 1 ramp clipped to [0, 1]."""
    return min(max(s, 0.0), 1.0)


@dataclass(frozen=True)
class ManeuverSpec:
    """A validated maneuver definition (vehicle independent; the file layout of
    :mod:`fourws_sim.maneuvers`). ``type`` names the class in
    :data:`fourws_sim.maneuvers.registry.MANEUVER_CLASSES`; ``params`` is an instance of that
    class's :attr:`Maneuver.Params`."""

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
    #: When the car's motion is no longer this maneuver's (:mod:`fourws_sim.outcome`).
    vehicle_limits: VehicleLimits = DEFAULT_LIMITS
    source: str = field(default="", compare=False)
    unchecked_fields: frozenset[str] = frozenset()

    def to_dict(self) -> dict[str, Any]:
        """The file layout as a plain mapping (round-trips through
        :func:`fourws_sim.maneuvers.load_maneuver_spec`)."""
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
        if self.vehicle_limits != DEFAULT_LIMITS:  # absent when default (older run records)
            out["vehicle_limits"] = self.vehicle_limits.to_dict()
        to_dict = getattr(self.params, "to_dict", None)
        out.update(to_dict() if to_dict is not None else dataclasses.asdict(self.params))
        if self.unchecked_fields:
            out[UNCHECKED_KEY] = sorted(self.unchecked_fields)
        return out


class Maneuver:
    """A maneuver bound to a vehicle, with its drivers' state (one instance per run).

    The base class is the open-loop angle maneuver held at its initial speed by the speed-hold
    driver; a type overrides what it does differently (see the module docstring).

    Parameters
    ----------
    spec : ManeuverSpec
        The validated definition (``spec.params`` is an instance of :attr:`Params`).
    vehicle : Vehicle
        The simulated vehicle (steering ratio, mass, wheel radius, wheelbase, understeer).

    Raises
    ------
    ParameterError
        ``steer_input: steering_wheel`` on a vehicle without ``steering`` data, or a
        steering-wheel input whose road-wheel angle on this vehicle is beyond
        :data:`MAX_ROAD_WHEEL_ANGLE_RAD` (unless the field is unchecked).
    """

    #: Parameter class of the type (a frozen dataclass; the file's type fields).
    Params: ClassVar[type]
    #: The spec field holding this type's driver (``path_driver``, ``tracking_driver``), if any.
    driver_key: ClassVar[str | None] = None
    #: ``angle`` or ``torque`` (:data:`STEERING_CONTROLS`).
    steering_control: ClassVar[str] = "angle"
    #: ``steer_input`` when the file gives none (:data:`STEER_INPUTS`).
    default_steer_input: ClassVar[str] = "road_wheel"
    #: The type only takes its default ``steer_input`` (its angles are defined in it).
    fixed_steer_input: ClassVar[bool] = False

    def __init__(self, spec: ManeuverSpec, vehicle: Vehicle) -> None:
        self.spec = spec
        self.vehicle = vehicle
        self.params = spec.params
        if spec.steer_input == "steering_wheel":
            vehicle.require("steering", user=f"maneuver {spec.name!r} (steer_input "
                                             "steering_wheel)")
        # Vehicles with no steering data report the hand-wheel angle equal to the road-wheel
        # angle (ratio 1); they only run road-wheel inputs.
        self._ratio = vehicle.steering.ratio if vehicle.steering is not None else 1.0
        peak = peak_input(spec.params)
        if (spec.steer_input == "steering_wheel" and peak is not None
                and peak[0] not in spec.unchecked_fields
                and peak[1] / self._ratio > MAX_ROAD_WHEEL_ANGLE_RAD):
            raise ParameterError(peak[0], f"asks for a road-wheel angle of "
                                 f"{peak[1] / self._ratio:.4g} rad on {vehicle.name} (steering "
                                 f"ratio {self._ratio:g}), beyond the plausible "
                                 f"{MAX_ROAD_WHEEL_ANGLE_RAD:g} rad (list it under "
                                 f"{UNCHECKED_KEY} to accept it)", spec.source or spec.name)
        self._speed_driver = SpeedHoldDriver(spec.speed_hold, vehicle)
        self._aborted = ""
        self._end_kind = ""

    # -- validation of a definition (before any vehicle) -----------------------------------
    @classmethod
    def check_spec(cls, params: Any, common: Mapping[str, float], source: str) -> None:
        """Checks across the type fields and the common fields (``initial_speed_mps``,
        ``duration_s``) of a definition; raises :class:`ParameterError`. None by default."""

    # -- the interface -------------------------------------------------------------------
    @property
    def name(self) -> str:
        """Maneuver name."""
        return self.spec.name

    @property
    def reference_path(self) -> ReferencePath | None:
        """The path a path-following driver follows (None for open-loop types)."""
        return None

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
        return float(self.params.steer(t))

    def steer_angles(self, t: float, outputs: Mapping[str, Any]) -> tuple[float, float]:
        """Steering-wheel and front road-wheel angle (rad) at tick time ``t`` (s)."""
        angle = self.steer_input(t)
        if self.spec.steer_input == "steering_wheel":
            return angle, angle / self._ratio
        return angle * self._ratio, angle

    def target_speed_mps(self, t: float) -> float:
        """Speed the speed-hold driver aims at (m/s)."""
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
        hand, front = self.steer_angles(t, outputs)
        drive, brake = self._speed_driver.command(t, speed, self.target_speed_mps(t))
        return DriverCommand(hand, front, 0.0, drive, brake)

    def type_phase(self, t: float) -> str:
        """Name of the type's phase at ``t`` before the run is done (the parameters' phase)."""
        return str(self.params.phase(t))

    def phase(self, t: float) -> str:
        """Name of the phase at time ``t`` (``done`` at or after the duration)."""
        if self._aborted:
            return "done"
        if t >= self.duration_s - TIME_EPS_S:
            return "done"
        return self.type_phase(t)

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
        ``aborted`` (the driver could not do it: left the path), ``spun`` (the car spun or
        drives backwards) or ``diverged`` (the car left the states the model represents; both
        by :class:`fourws_sim.outcome.VehicleLimits`). Meaningful once :meth:`done` is
        true."""
        if not self._aborted:
            return "completed"
        return self._end_kind

    def end(self, reason: str, end_condition: bool = False, kind: str = "") -> None:
        """End the run early: ``reason`` (the abort reason), as the designed end condition
        of the type, as an abort, or as ``kind`` (``spun``, ``diverged``)."""
        self._aborted = reason
        self._end_kind = kind or ("end_condition" if end_condition else "aborted")

    def check_end(self, t: float, outputs: Mapping[str, Any]) -> None:
        """Look for the type's end condition in ``outputs`` and :meth:`end` the run if it is
        met (none by default)."""

    def end_at_limits(self, outputs: Mapping[str, Any], max_lateral_accel_mps2: float,
                      max_sideslip_rad: float) -> None:
        """The end of a slowly increasing steer: the lateral-acceleration limit reached, or
        the sideslip past the maneuver's own limit (the car leaves steady-state cornering).
        Both are the designed end of the test, whose record up to there is valid: whether the
        car *spun* is decided by one rule only, the run's
        :class:`~fourws_sim.outcome.VehicleLimits` (20 deg by default, beyond the 0.15 rad
        these maneuvers stop at)."""
        if abs(float(outputs["lateral_accel_mps2"])) >= max_lateral_accel_mps2:
            self.end("lateral acceleration limit reached", end_condition=True)
        elif abs(float(outputs.get("sideslip_rad", 0.0))) > max_sideslip_rad:
            self.end(f"the maneuver's sideslip limit reached (|sideslip| > "
                     f"{math.degrees(max_sideslip_rad):.3g} deg: the car leaves steady-state "
                     "cornering)", end_condition=True)

    def done(self, t: float, outputs: Mapping[str, Any] | None = None) -> bool:
        """True once the run may end: duration reached, an end condition of the type, or the
        car's motion past the maneuver's :class:`~fourws_sim.outcome.VehicleLimits` (the
        run ends ``spun`` or ``diverged`` at this state)."""
        if self._aborted:
            return True
        if t >= self.duration_s - TIME_EPS_S:
            return True
        if outputs is None:
            return False
        self.check_end(t, outputs)
        if not self._aborted:
            breach = self.spec.vehicle_limits.violation(t, outputs)
            if breach is not None:
                self.end(breach.reason, kind=breach.kind)
        return bool(self._aborted)

    def to_dict(self) -> dict[str, Any]:
        """The maneuver definition as a plain mapping (for the run configuration)."""
        return self.spec.to_dict()


def finite_or_none(params: Any, bounds: Mapping[str, tuple[float, float]],
                   source: str | None, prefix: str,
                   unchecked: frozenset[str] = frozenset()) -> None:
    """Check that the optional fields of ``params`` named in ``bounds`` are finite numbers
    within their plausibility bounds (angles by magnitude: ``*_rad`` fields are signed) or
    None, and store them as floats (a frozen dataclass's ``_check`` helper)."""
    for name, limits in bounds.items():
        value = getattr(params, name)
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise ParameterError(f"{prefix}{name}",
                                 f"must be a finite number, got {describe(value)}", source)
        check_plausible(f"{prefix}{name}", abs(float(value)) if name.endswith("_rad")
                        else float(value), limits, source, unchecked)
        object.__setattr__(params, name, float(value))


#: Shapes of a single pulse input (ISO 7401 steering pulse, ISO 17288-2 torque pulse).
PULSE_SHAPES = ("triangle", "half_sine")


def check_pulse_shape(shape: str, source: str | None, prefix: str) -> None:
    """A pulse's ``shape`` must be one of :data:`PULSE_SHAPES`."""
    if shape not in PULSE_SHAPES:
        raise ParameterError(f"{prefix}shape",
                             f"must be triangle or half_sine, got {shape!r}", source)


def pulse_shape(t: float, start_s: float, width_s: float, shape: str) -> float:
    """A single pulse of unit peak at ``t`` (s): 0 outside ``(start_s, start_s + width_s)``,
    a ``triangle`` (area w / 2) or a ``half_sine`` (area 2 w / pi) within."""
    s = (t - start_s) / width_s
    if s <= 0.0 or s >= 1.0:
        return 0.0
    if shape == "triangle":
        return 1.0 - abs(2.0 * s - 1.0)
    return math.sin(math.pi * s)


def peak_input(params: Any) -> tuple[str, float] | None:
    """The field that sets the largest open-loop input angle of a type's parameters and that
    angle (rad, in the unit of ``steer_input``): the parameters' own ``peak_input()`` if they
    have one, else ``amplitude_rad``; None for types without an open-loop angle (closed-loop
    drivers, torque inputs) or a step still to be resolved."""
    own = getattr(params, "peak_input", None)
    if own is not None:
        return own()
    if getattr(params, "amplitude_rad", None) is not None:
        return "amplitude_rad", abs(params.amplitude_rad)
    return None


__all__ = ["ANGLE_BOUNDS_RAD", "FREQUENCY_BOUNDS_HZ", "MAX_DURATION_S",
           "MAX_HAND_WHEEL_ANGLE_RAD", "MAX_PATH_POINTS", "MAX_RANDOM_SAMPLES",
           "MAX_ROAD_WHEEL_ANGLE_RAD", "MAX_STEER_FREQUENCY_HZ", "Maneuver", "ManeuverSpec",
           "PULSE_SHAPES", "RANDOM_PEAK_PER_RMS", "RATE_BOUNDS_RADPS", "STEERING_CONTROLS",
           "STEER_INPUTS", "TIME_BOUNDS_S", "TIME_EPS_S", "check_pulse_shape", "finite_or_none",
           "peak_input", "pulse_shape", "smooth_ramp"]
