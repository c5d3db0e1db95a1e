"""A of the FMVSS No. 126 sine with dwell for a law: the slowly increasing steer run with the law.

The regulation's sine-with-dwell amplitudes are multiples of A, the steering-wheel angle of
0.3 g in the steady state (S7.6.1). A depends on the law (the car with its rear-steer law is the
vehicle under test), so a sine with dwell given as a multiple of A is resolved for each law
before its runs, with the offline twin of those runs, as a step steer to a target lateral
acceleration is (:mod:`fourws_run.step_target`, whose :func:`resolve_maneuver_for_law`
dispatches to :func:`resolve_reference_amplitude`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from fourws_run.closed_loop import run_closed_loop
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers import ManeuverSpec, SlowlyIncreasingSteerParams, load_maneuver_spec
from fourws_sim.maneuvers.esc import (reference_amplitude_rad, resolved_sine_with_dwell,
                                      round_reference)


@dataclass(frozen=True)
class ReferenceAmplitude:
    """A of the sine with dwell for one law (FMVSS No. 126 S7.6.1).

    Attributes
    ----------
    reference_rad : float
        A: the mean of ``per_run_rad``'s magnitudes rounded to 0.1 deg, steering-wheel rad.
    per_run_rad : tuple of float
        The steering-wheel angle of 0.3 g of each slowly-increasing-steer run (left, right),
        rad, signed.
    maneuvers : tuple of ManeuverSpec
        The slowly-increasing-steer runs (left, right).
    """

    reference_rad: float
    per_run_rad: tuple[float, ...]
    maneuvers: tuple[ManeuverSpec, ...]


def reference_maneuvers(spec: ManeuverSpec) -> tuple[ManeuverSpec, ManeuverSpec]:
    """The slowly-increasing-steer runs that find A for the sine with dwell ``spec``: its
    ``reference_maneuver`` file steered left and right (names ``<name>_L``, ``<name>_R``)."""
    sis = load_maneuver_spec(spec.params.reference_maneuver)
    return tuple(dataclasses.replace(  # type: ignore[return-value]
        sis, name=f"{sis.name}_{d[0].upper()}",
        params=dataclasses.replace(sis.params, direction=d)) for d in ("left", "right"))


def reference_amplitude_for_law(scenario: Any, law: str,
                                spec: ManeuverSpec) -> ReferenceAmplitude:
    """A of the sine with dwell ``spec`` with ``law``: its slowly increasing steer run on the
    offline twin of the scenario's runs (:func:`reference_maneuvers`, left and right), the
    steering-wheel angle of 0.3 g in each from the regulation's regression
    (:func:`fourws_sim.maneuvers.esc.reference_amplitude_rad`), A the mean of the two
    magnitudes rounded to 0.1 deg (repeated runs of a simulation are identical, so one run
    per direction stands for the regulation's three).

    Raises
    ------
    ParameterError
        A run did not reach the regression's lateral accelerations (it spun, or ended too
        early), or the reference maneuver is not a slowly increasing steer.
    """
    where = spec.source or spec.name
    vehicle = scenario.build_vehicle()
    belief = scenario.build_belief(vehicle)
    runs = reference_maneuvers(spec)
    values = []
    for sis in runs:
        if not isinstance(sis.params, SlowlyIncreasingSteerParams):
            raise ParameterError("reference_maneuver", f"{sis.name!r} is a {sis.type}, not a "
                                 "slowly_increasing_steer", where)
        res = run_closed_loop(vehicle, sis, law, model=scenario.model,
                              dt_s=scenario.integration_step_s,
                              control_period_s=scenario.control_period_s,
                              belief_vehicle=belief, integrator=scenario.integrator,
                              law_options=scenario.law_options.get(law))
        try:
            values.append(reference_amplitude_rad(
                res.time_s, res["steering_wheel_angle_rad"], res["lateral_accel_mps2"],
                start_s=sis.params.start_s))
        except ParameterError as exc:
            raise ParameterError("reference_maneuver", f"{exc.problem} ({sis.name}, law "
                                 f"{law}, ended: {res.end_reason})", where) from None
    reference = round_reference(float(np.mean(np.abs(values))))
    return ReferenceAmplitude(reference, tuple(values), runs)


def resolve_reference_amplitude(scenario: Any, law: str, spec: ManeuverSpec) -> ManeuverSpec:
    """A sine with dwell given as a multiple of A, resolved for ``law``: A found with the law
    (:func:`reference_amplitude_for_law`; or the file's ``reference_amplitude_rad`` when it
    gives one without a law), the amplitude ``amplitude_factor`` x A. One given by its
    amplitude, or already resolved for ``law``, is returned unchanged."""
    p = spec.params
    if p.amplitude_factor is None or (p.resolved and p.reference_law in (law, "")):
        return spec
    if p.reference_amplitude_rad is not None and not p.reference_law:
        return resolved_sine_with_dwell(spec, p.reference_amplitude_rad, "")
    found = reference_amplitude_for_law(scenario, law, spec)
    return resolved_sine_with_dwell(spec, found.reference_rad, law)


__all__ = ["ReferenceAmplitude", "reference_amplitude_for_law", "reference_maneuvers",
           "resolve_reference_amplitude"]
