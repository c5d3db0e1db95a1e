"""Series of runs: one scenario, several maneuvers per law.

A scenario's ``series`` field says which maneuvers each law runs instead of the one
``maneuver``:

``series: regulation``
    the maneuver type's regulation series (:data:`REGULATION_SERIES`). For ``sine_with_dwell``
    (FMVSS No. 126 S7.9): the slowly increasing steer left and right that finds A with the law
    (recorded too, so the bags show where A came from), then the sine with dwell at 1.5 A,
    2.0 A, ... up to the larger of 6.5 A and 270 deg (at most 300 deg), first half wave left,
    then the same right (:func:`fourws_sim.maneuvers.esc.regulation_series`). The series of a
    law depends on its A, so it is built per law (:func:`scenario_runs`).
``series: [{...}, {...}]``
    a list of runs, each a mapping of maneuver fields that replace the scenario maneuver's
    (e.g. ``{amplitude_rad: 0.02}``; ``name`` defaults to ``<maneuver>_<n>``); each run is
    resolved for the law as a single maneuver is.

``fourws run`` runs every law's series through the node graph, one recorded run per member;
:func:`run_series` is the offline twin of the same runs.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, Mapping, Sequence

from fourws_run.closed_loop import ClosedLoopResult, run_twin
from fourws_run.reference_amplitude import reference_amplitude_for_law
from fourws_run.step_target import resolve_maneuver_for_law
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers import (ManeuverSpec, SineWithDwellParams,
                                  maneuver_spec_from_mapping)
from fourws_sim.maneuvers.esc import regulation_series

#: The keyword of a scenario's ``series`` field that asks for the maneuver's regulation series.
REGULATION = "regulation"


def _sine_with_dwell_series(scenario: Any, law: str, spec: ManeuverSpec) -> list[ManeuverSpec]:
    """FMVSS No. 126: the slowly increasing steer runs, then the amplitude series."""
    found = reference_amplitude_for_law(scenario, law, spec)
    return [*found.maneuvers, *regulation_series(spec, found.reference_rad, law)]


#: Maneuver parameter class -> its regulation series for a law (``series: regulation``).
REGULATION_SERIES: dict[type, Callable[[Any, str, ManeuverSpec], list[ManeuverSpec]]] = {
    SineWithDwellParams: _sine_with_dwell_series,
}


def check_series(data: Any, maneuver: ManeuverSpec, source: str
                 ) -> str | tuple[ManeuverSpec, ...] | None:
    """Validate a scenario's ``series`` field for its maneuver: None, ``regulation`` (the
    type must have one) or a non-empty list of maneuver-field mappings (each merged into the
    maneuver and validated).

    Returns
    -------
    None, ``"regulation"`` or the tuple of member specs (not yet resolved for a law).

    Raises
    ------
    ParameterError
        (field ``series`` or ``series[i].<field>``) otherwise.
    """
    if data is None:
        return None
    if data == REGULATION:
        if type(maneuver.params) not in REGULATION_SERIES:
            kinds = ", ".join(sorted(c.__name__ for c in REGULATION_SERIES))
            raise ParameterError("series", f"maneuver type {maneuver.type} has no regulation "
                                 f"series (types with one: {kinds})", source)
        return REGULATION
    if not isinstance(data, Sequence) or isinstance(data, str) or not data:
        raise ParameterError("series", f"must be {REGULATION!r} or a non-empty list of "
                             f"maneuver-field mappings, got {data!r}", source)
    base = maneuver.to_dict()
    members = []
    for i, entry in enumerate(data):
        if not isinstance(entry, Mapping):
            raise ParameterError(f"series[{i}]", "must be a mapping of maneuver fields", source)
        if "type" in entry and entry["type"] != maneuver.type:
            raise ParameterError(f"series[{i}].type", "a series varies one maneuver type; "
                                 f"this one is {maneuver.type}", source)
        merged = {**base, "name": f"{maneuver.name}_{i + 1}", **entry}
        members.append(maneuver_spec_from_mapping(merged, f"{source} (series[{i}])"))
    return tuple(members)


def scenario_runs(scenario: Any, law: str) -> list[ManeuverSpec]:
    """The maneuvers ``law`` runs in ``scenario``, resolved for the law: its series (module
    docstring), or its one maneuver.

    Raises
    ------
    ParameterError
        What resolving a maneuver for the law raises (a target not reached, A not found).
    """
    series = getattr(scenario, "series", None)
    if series is None:
        return [resolve_maneuver_for_law(scenario, law)]
    if series == REGULATION:
        return REGULATION_SERIES[type(scenario.maneuver.params)](scenario, law,
                                                                 scenario.maneuver)
    return [resolve_maneuver_for_law(scenario, law, spec) for spec in series]


def run_series(scenario: Any, law: str | None = None,
               members: Sequence[ManeuverSpec] | None = None) -> list[ClosedLoopResult]:
    """Run a scenario's series for one law (its first by default) offline: the twin of the
    lockstep graph runs ``fourws run`` makes. ``members`` (e.g. a part of
    :func:`scenario_runs`) replaces the whole series.

    Raises
    ------
    ParameterError
        ``law`` is not one of the scenario's laws, or resolving fails.
    """
    law = scenario.laws[0] if law is None else law
    if law not in scenario.laws:
        raise ParameterError("law", f"{law!r} is not in the scenario's laws "
                             f"({', '.join(scenario.laws)})", scenario.source or scenario.name)
    specs = scenario_runs(scenario, law) if members is None else list(members)
    # each member as the graph runs it: through the run's description (a RunConfig)
    return [run_twin(scenario.run_config(law, maneuver=spec)) for spec in specs]


def with_series(scenario: Any, series: Any) -> Any:
    """``scenario`` with another ``series`` field value (validated)."""
    checked = check_series(series, scenario.maneuver, scenario.source or scenario.name)
    return dataclasses.replace(scenario, series=checked)


__all__ = ["REGULATION", "REGULATION_SERIES", "check_series", "run_series", "scenario_runs",
           "with_series"]
