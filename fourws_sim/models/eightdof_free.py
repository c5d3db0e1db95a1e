# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The 8-DOF model with free steering control (model ``8dof-free``).

The model of :mod:`fourws_sim.models.eightdof` with its steering system switched on: the front
road-wheel angle is the state ``DELTA_S`` of a steering system driven by the driver's torque on
the steering wheel (input ``STEER_TORQUE``) and the front tires' returning torque; the input
``DELTA_F`` is not used. Equations, parameters and their meaning: the "Free steering system"
section of :mod:`fourws_sim.models.eightdof`. Same state, input and parameter layout, same
compiled kernels (the system is a flag in the parameters).
"""

from __future__ import annotations

from fourws_sim.models.eightdof import (INPUT, PARAM, STATE, Params, derivatives,
                                        derivatives_compiled, evaluate, initial_state)
from fourws_sim.models.eightdof import params_for as _fixed_params_for
from fourws_sim.params import Vehicle

#: The front road-wheel angle a law sees is the steering system's angle, this state
#: (:func:`fourws_control.signals.signal_map`).
FRONT_ANGLE_STATE = "DELTA_S"


def params_for(vehicle: Vehicle, tire: str | None = None, *,
               v_min_mps: float | None = None) -> Params:
    """The 8-DOF parameters of ``vehicle`` with the free steering system on
    (:func:`fourws_sim.models.eightdof.params_for` with ``free_steering=True``).

    Raises
    ------
    ParameterError
        As :func:`fourws_sim.models.eightdof.params_for`; also no ``steering`` data or a
        steering inertia of 0.
    """
    return _fixed_params_for(vehicle, tire, v_min_mps=v_min_mps, free_steering=True)


__all__ = ["FRONT_ANGLE_STATE", "INPUT", "PARAM", "STATE", "Params", "derivatives",
           "derivatives_compiled", "evaluate", "initial_state", "params_for"]
