"""The maneuver types by name: the file's ``type`` -> the :class:`~.base.Maneuver` subclass.

Adding a maneuver type is one class (its parameters and what it does differently, in a module
of this package) and one line here.
"""

from __future__ import annotations

from fourws_sim.maneuvers.base import Maneuver
from fourws_sim.maneuvers.braking import BrakeInTurn
from fourws_sim.maneuvers.esc import SineWithDwell, SlowlyIncreasingSteer
from fourws_sim.maneuvers.free_steer import SteeringPulse, SteeringRelease, SteeringTorqueStep
from fourws_sim.maneuvers.open_loop import (Pulse, RampSteer, RandomSteer, Sine, SlowRampSteer,
                                            StepSteer, SweptSine)
from fourws_sim.maneuvers.path_following import ConstantRadius, DoubleLaneChange

#: Maneuver type name -> class.
MANEUVER_CLASSES: dict[str, type[Maneuver]] = {
    "step_steer": StepSteer,
    "ramp_steer": RampSteer,
    "sine": Sine,
    "swept_sine": SweptSine,
    "random_steer": RandomSteer,
    "pulse": Pulse,
    "slow_ramp_steer": SlowRampSteer,
    "constant_radius": ConstantRadius,
    "double_lane_change": DoubleLaneChange,
    "brake_in_turn": BrakeInTurn,
    "steering_torque_step": SteeringTorqueStep,
    "steering_release": SteeringRelease,
    "steering_pulse": SteeringPulse,
    "slowly_increasing_steer": SlowlyIncreasingSteer,
    "sine_with_dwell": SineWithDwell,
}

#: Maneuver type name -> parameter class (the type fields of a file).
MANEUVER_TYPES: dict[str, type] = {name: cls.Params for name, cls in MANEUVER_CLASSES.items()}

#: The spec fields that hold a type's driver (path-following types).
DRIVER_KEYS: tuple[str, ...] = ("path_driver", "tracking_driver")

__all__ = ["DRIVER_KEYS", "MANEUVER_CLASSES", "MANEUVER_TYPES"]
