"""ISO 7401 step steer at a target steady lateral acceleration: the amplitude per law; and
the dispatch of every maneuver that depends on the law (:data:`LAW_DEPENDENT`).

ISO 7401 runs the step at a lateral acceleration (e.g. 4 m/s^2), not at an angle, so laws that
need different steer for it are compared at equal lateral acceleration. A ``step_steer`` with
``target_lateral_accel_mps2`` is resolved per law before its run
(:func:`resolve_maneuver_for_law`): the offline twin finds the amplitude, and the graph and the
twin then run an ordinary step of that amplitude (recorded in the run description with the law
it was found for).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from fourws_run.closed_loop import ClosedLoopResult, run_closed_loop
from fourws_sim.errors import ParameterError
from fourws_run.reference_amplitude import resolve_reference_amplitude
from fourws_sim.maneuvers import ManeuverSpec, SineWithDwellParams, StepSteerParams

#: The amplitude search stops when the steady |a_y| is within this fraction of the target
#: (ISO 7401 asks for the lateral acceleration within a tolerance of the nominal value; 0.5 %
#: is far inside what a test track reaches and costs one or two more offline runs).
TARGET_ACCEL_RTOL = 0.005
#: Offline runs the amplitude search may use before it gives up.
TARGET_MAX_RUNS = 12
#: Largest amplitude the search tries, rad of road-wheel angle (20 deg: far past any car's
#: steady-state limit at the speeds of a step steer; beyond it the target is unreachable).
TARGET_MAX_ROAD_WHEEL_RAD = math.radians(20.0)
#: Window at the end of the hold averaged as the steady state, s (the same window as the
#: ISO 7401 analysis, fourws_analysis.iso7401.STEADY_WINDOW_S).
STEADY_WINDOW_S = 1.0
#: A run whose |a_y| varies over the steady window by more than this fraction of its mean has
#: not settled (a spinning or oscillating car; a settled step varies by well under 2 %).
UNSETTLED_FRACTION = 0.1


@dataclass(frozen=True)
class AmplitudeSearch:
    """Result of :func:`find_step_amplitude`.

    Attributes
    ----------
    amplitude : float
        The amplitude found, rad (> 0).
    lateral_accel_mps2 : float
        Steady |a_y| it gives, m/s^2.
    runs : int
        Evaluations used.
    """

    amplitude: float
    lateral_accel_mps2: float
    runs: int


def find_step_amplitude(evaluate: Callable[[float], float], target_mps2: float,
                        first_guess: float, max_amplitude: float,
                        rtol: float = TARGET_ACCEL_RTOL,
                        max_runs: int = TARGET_MAX_RUNS) -> AmplitudeSearch:
    """The step amplitude ``x > 0`` whose steady lateral acceleration is ``target_mps2``.

    Solves ``evaluate(x) = target`` (``evaluate``: amplitude -> steady |a_y|, m/s^2, or
    ``inf`` when the run diverges or does not settle) by the secant method safeguarded by
    bisection: the first step is proportional (the secant through the origin, exact for a
    linear car, where ``a_y(0) = 0``), later steps are secants through the last two points;
    a step that leaves the bracket ``[largest x below the target, smallest x above it]`` is
    replaced by its midpoint (or, before any point above the target, by doubling). Saturating
    tires make ``a_y(x)`` concave, so the secant converges from below in a few runs.

    Parameters
    ----------
    evaluate : callable
        Amplitude -> steady |a_y| in m/s^2 (one offline run).
    target_mps2 : float
        Target steady |a_y|, m/s^2 (> 0).
    first_guess : float
        First amplitude tried (> 0).
    max_amplitude : float
        Largest amplitude tried.
    rtol : float
        Stop when ``|a_y - target| <= rtol * target``.
    max_runs : int
        Evaluations allowed.

    Raises
    ------
    ParameterError
        (field ``target_lateral_accel_mps2``) when the target is not reached within
        ``max_runs`` runs or needs more than ``max_amplitude``; the message gives the closest
        amplitude and what it reached.
    """
    lo_x, lo_a = 0.0, 0.0          # a_y(0) = 0: straight running
    hi_x: float | None = None
    prev_x, prev_a = 0.0, 0.0
    unsettled: float | None = None  # smallest amplitude whose run did not settle
    x = min(first_guess, max_amplitude)
    best = (math.inf, x, math.nan)
    for runs in range(1, max_runs + 1):
        a = float(evaluate(x))
        if math.isfinite(a) and abs(a - target_mps2) < best[0]:
            best = (abs(a - target_mps2), x, a)
        elif not math.isfinite(a):
            unsettled = x if unsettled is None else min(unsettled, x)
        if math.isfinite(a) and abs(a - target_mps2) <= rtol * target_mps2:
            return AmplitudeSearch(x, a, runs)
        if math.isfinite(a) and a < target_mps2:
            if x >= max_amplitude:
                break
            lo_x, lo_a = x, a
        else:
            hi_x = x
        step = math.nan
        if math.isfinite(a) and a != prev_a:
            step = x + (target_mps2 - a) * (x - prev_x) / (a - prev_a)
        upper = hi_x if hi_x is not None else max_amplitude
        if not (math.isfinite(step) and lo_x < step < upper):
            step = 0.5 * (lo_x + hi_x) if hi_x is not None else min(2.0 * x, max_amplitude)
        if math.isfinite(a):
            prev_x, prev_a = x, a
        else:  # a diverged run has no secant: continue from the bracket's lower end
            prev_x, prev_a = lo_x, lo_a
        x = step
    _, x_best, a_best = best
    closest = (f"the closest steady run, amplitude {x_best:.4g} rad "
               f"({math.degrees(x_best):.3g} deg), gives {a_best:.4g} m/s^2"
               if math.isfinite(a_best) else "no run settled")
    beyond = (f"; from {unsettled:.4g} rad on the run does not settle (the car spins or "
              "oscillates)" if unsettled is not None else "")
    raise ParameterError(
        "target_lateral_accel_mps2",
        f"{target_mps2:g} m/s^2 not reached after {runs} run(s): {closest}{beyond}")


def steady_lateral_accel(result: ClosedLoopResult,
                         window_s: float = STEADY_WINDOW_S) -> float:
    """Mean lateral acceleration over the last ``window_s`` seconds of a run, m/s^2."""
    t = result.time_s
    return float(np.mean(result["lateral_accel_mps2"][t >= t[-1] - window_s]))


def resolve_maneuver_for_law(scenario: Any, law: str,
                             spec: ManeuverSpec | None = None) -> ManeuverSpec:
    """The scenario's maneuver (or ``spec``, e.g. a member of its series) as it runs with
    ``law``: what depends on the law is found with the offline twin of the run by the
    maneuver type's resolver (:data:`LAW_DEPENDENT`, by parameter class): a ``step_steer``
    with ``target_lateral_accel_mps2`` gets the amplitude that reaches that steady lateral
    acceleration (:func:`resolve_step_target`), a ``sine_with_dwell`` given as a multiple of
    A gets A (:func:`fourws_run.reference_amplitude.resolve_reference_amplitude`); any other
    maneuver is returned unchanged.

    Raises
    ------
    ParameterError
        The resolver's (see there).
    """
    spec = scenario.maneuver if spec is None else spec
    resolver = LAW_DEPENDENT.get(type(spec.params))
    return spec if resolver is None else resolver(scenario, law, spec)


def resolve_step_target(scenario: Any, law: str, spec: ManeuverSpec) -> ManeuverSpec:
    """A step steer with ``target_lateral_accel_mps2``, resolved for ``law``: the amplitude
    that reaches that steady lateral acceleration with this law; a step without a target, or
    already resolved for ``law``, is returned unchanged.

    The amplitude is found by :func:`find_step_amplitude` on the offline twin of the run
    (:func:`run_closed_loop` with the scenario's vehicle, model, belief, law options,
    integrator and periods), measuring the steady |a_y| as the mean over the last
    :data:`STEADY_WINDOW_S` of the hold (as the ISO 7401 analysis does). The result is an
    ordinary step of that amplitude, which the node graph and the offline runner run alike;
    it records the law it was found for and the |a_y| reached (see
    :class:`fourws_sim.maneuvers.StepSteerParams`). A maneuver already resolved for ``law``
    is returned as it is.

    Raises
    ------
    ParameterError
        Initial speed 0, a hold shorter than twice the steady window, or a target that is
        not reached (see :func:`find_step_amplitude`).
    """
    p = spec.params
    if p.target_lateral_accel_mps2 is None or p.amplitude_law == law:
        return spec
    where = spec.source or spec.name
    speed = spec.initial_speed_mps
    if speed <= 0.0:
        raise ParameterError("initial_speed_mps", "must be > 0 with "
                             "target_lateral_accel_mps2", where)
    hold = spec.duration_s - p.start_s - p.ramp_time_s
    if hold < 2.0 * STEADY_WINDOW_S:
        raise ParameterError("duration_s", f"the hold after the ramp is {hold:.2f} s; "
                             f"target_lateral_accel_mps2 needs >= {2 * STEADY_WINDOW_S:g} s "
                             "to reach a steady state", where)
    vehicle = scenario.build_vehicle()
    belief = scenario.build_belief(vehicle)
    ratio = 1.0
    if spec.steer_input == "steering_wheel":
        vehicle.require("steering", user=f"maneuver {spec.name!r} (steer_input "
                                         "steering_wheel)")
        ratio = vehicle.steering.ratio
    target = p.target_lateral_accel_mps2
    sign = -1.0 if p.amplitude_rad is not None and p.amplitude_rad < 0.0 else 1.0
    # first guess: the amplitude given, else the neutral-steer angle L a_y / U^2
    guess = abs(p.amplitude_rad) if p.amplitude_rad is not None \
        else ratio * vehicle.chassis.wheelbase_m * target / speed ** 2

    def evaluate(amplitude: float) -> float:
        trial = dataclasses.replace(spec, params=dataclasses.replace(
            p, amplitude_rad=sign * amplitude, target_lateral_accel_mps2=None,
            amplitude_law="", amplitude_lateral_accel_mps2=None))
        res = run_closed_loop(vehicle, trial, law, model=scenario.model,
                              dt_s=scenario.integration_step_s,
                              control_period_s=scenario.control_period_s,
                              belief_vehicle=belief, integrator=scenario.integrator,
                              law_options=scenario.law_options.get(law))
        if res.diverged:
            return math.inf
        t = res.time_s
        window = res["lateral_accel_mps2"][t >= t[-1] - STEADY_WINDOW_S]
        mean = float(np.mean(window))
        if np.ptp(window) > UNSETTLED_FRACTION * abs(mean):
            return math.inf
        return abs(mean)

    try:
        found = find_step_amplitude(evaluate, target, guess,
                                    ratio * TARGET_MAX_ROAD_WHEEL_RAD)
    except ParameterError as exc:
        raise ParameterError(exc.field, f"{exc.problem} (law {law})", where) from None
    return dataclasses.replace(spec, params=dataclasses.replace(
        p, amplitude_rad=sign * found.amplitude, amplitude_law=law,
        amplitude_lateral_accel_mps2=found.lateral_accel_mps2))


#: Maneuver parameter class -> how a maneuver of that class is resolved for a law.
LAW_DEPENDENT: dict[type, Callable[[Any, str, ManeuverSpec], ManeuverSpec]] = {
    StepSteerParams: resolve_step_target,
    SineWithDwellParams: resolve_reference_amplitude,
}


def scenario_for_law(scenario: Any, law: str) -> Any:
    """``scenario`` with its maneuver resolved for ``law`` (:func:`resolve_maneuver_for_law`);
    the same object when there is nothing to resolve. Call it where a law's run is prepared
    (the offline runner and the node-graph launcher), so both run the same amplitude."""
    spec = resolve_maneuver_for_law(scenario, law)
    return scenario if spec is scenario.maneuver else dataclasses.replace(scenario,
                                                                          maneuver=spec)


__all__ = ["AmplitudeSearch", "LAW_DEPENDENT", "STEADY_WINDOW_S", "TARGET_ACCEL_RTOL",
           "find_step_amplitude", "resolve_maneuver_for_law", "resolve_step_target",
           "scenario_for_law", "steady_lateral_accel"]
