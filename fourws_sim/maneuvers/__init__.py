"""Maneuvers: steering inputs, closed-loop driving tasks and the speed-hold driver, from YAML.

A maneuver file (``config/maneuvers/<name>.yaml``) is a mapping::

    name: step_steer_85kmh          # optional, defaults to the file stem
    type: step_steer                # a registered type (MANEUVER_CLASSES)
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

Types
-----
Each type is one class (:class:`Maneuver` subclass) owning its parameters (``Params``, the
file's type fields), its steering, speed target, phases, end condition and driver; the
registry (:data:`MANEUVER_CLASSES`, :mod:`fourws_sim.maneuvers.registry`) maps the file's
``type`` to it. Adding a type is one class and one registry line.

Runtime interface (the maneuver node and the offline runner use only this)::

    m = make_maneuver(load_maneuver_spec("step_steer_85kmh"), vehicle)
    m.initial_speed_mps, m.duration_s
    m.command(t, outputs) -> DriverCommand     # outputs: dict of Simulator.outputs()
    m.phase(t) -> str;  m.progress(t) -> float in [0, 1];  m.done(t, outputs) -> bool
    m.abort_reason, m.end_kind
    m.to_dict() -> mapping (the file layout; load_maneuver_spec(m.to_dict()) rebuilds it)

``command`` must be called once per control tick with increasing ``t`` (stateful drivers advance
only there, see :mod:`fourws_sim.drivers`); ``phase``, ``progress`` and ``done`` have no side
effects except that ``done`` of a type with an end condition (``slow_ramp_steer``,
``constant_radius``) looks at the outputs it is given.

Standards and the source: step steer, sine, random and pulse inputs follow ISO 7401 (lateral
transient response test methods); slowly increasing steer and constant radius follow ISO 4138
(steady-state circular driving); the lane change follows the ISO 3888-2 obstacle-avoidance track;
ramp steer and braking in a turn are the ch. 8 maneuvers of Samsundar (1996).
"""

from __future__ import annotations

from fourws_sim.drivers import DriverCommand
from fourws_sim.maneuvers.base import (MAX_DURATION_S, MAX_HAND_WHEEL_ANGLE_RAD,
                                       MAX_PATH_POINTS, MAX_RANDOM_SAMPLES,
                                       MAX_ROAD_WHEEL_ANGLE_RAD, MAX_STEER_FREQUENCY_HZ,
                                       RANDOM_PEAK_PER_RMS, STEER_INPUTS, STEERING_CONTROLS,
                                       Maneuver, ManeuverSpec)
from fourws_sim.maneuvers.braking import BrakeInTurn, BrakeInTurnParams
from fourws_sim.maneuvers.esc import (SineWithDwell, SineWithDwellParams, SlowlyIncreasingSteer,
                                      SlowlyIncreasingSteerParams)
from fourws_sim.maneuvers.files import (MANEUVER_DIR, available_maneuvers, check_model,
                                        check_sampling, load_maneuver_spec, make_maneuver,
                                        maneuver_class, maneuver_spec_from_mapping,
                                        resolve_maneuver_path)
from fourws_sim.maneuvers.free_steer import (SteeringPulse, SteeringPulseParams,
                                             SteeringRelease, SteeringReleaseParams,
                                             SteeringTorqueStep, SteeringTorqueStepParams)
from fourws_sim.maneuvers.open_loop import (Pulse, PulseParams, RampSteer, RampSteerParams,
                                            RandomSteer, RandomSteerParams, Sine, SineParams,
                                            SlowRampSteer, SlowRampSteerParams, StepSteer,
                                            StepSteerParams, SweptSine, SweptSineParams)
from fourws_sim.maneuvers.path_following import (ConstantRadius, ConstantRadiusParams,
                                                 DoubleLaneChange, DoubleLaneChangeParams)
from fourws_sim.maneuvers.registry import MANEUVER_CLASSES, MANEUVER_TYPES

__all__ = [
    "BrakeInTurn", "BrakeInTurnParams", "ConstantRadius", "ConstantRadiusParams",
    "DoubleLaneChange", "DoubleLaneChangeParams", "DriverCommand", "MANEUVER_CLASSES",
    "MANEUVER_DIR", "MANEUVER_TYPES", "MAX_DURATION_S", "MAX_HAND_WHEEL_ANGLE_RAD",
    "MAX_PATH_POINTS", "MAX_RANDOM_SAMPLES", "MAX_ROAD_WHEEL_ANGLE_RAD",
    "MAX_STEER_FREQUENCY_HZ", "Maneuver", "ManeuverSpec", "Pulse", "PulseParams",
    "RANDOM_PEAK_PER_RMS", "RampSteer", "RampSteerParams", "RandomSteer", "RandomSteerParams",
    "STEERING_CONTROLS", "STEER_INPUTS", "Sine", "SineParams", "SineWithDwell",
    "SineWithDwellParams", "SlowRampSteer", "SlowRampSteerParams", "SlowlyIncreasingSteer",
    "SlowlyIncreasingSteerParams", "SteeringPulse", "SteeringPulseParams", "SteeringRelease",
    "SteeringReleaseParams", "SteeringTorqueStep", "SteeringTorqueStepParams", "StepSteer",
    "StepSteerParams", "SweptSine", "SweptSineParams", "available_maneuvers", "check_model",
    "check_sampling", "load_maneuver_spec", "make_maneuver", "maneuver_class",
    "maneuver_spec_from_mapping", "resolve_maneuver_path",
]
