# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Run scenarios: which vehicle, maneuver, laws, model, clock and recording, from YAML.

A scenario file (``config/scenarios/<name>.yaml``)::

    name: default
    description: ...
    vehicle: table_8_1            # vehicle name (config/vehicles stem) or YAML path
    maneuver: step_steer_85kmh    # maneuver name, YAML path, or an inline mapping
    laws: [fws, sol1, rwc2_3dof]  # one run per law
    law_options: {}               # optional: {law name: {option: value}}
    model: 8dof                   # fourws_sim.models name
    tire: null                    # optional override of the vehicle's tire.model
    integrator: rk4
    clock_mode: lockstep          # lockstep | realtime
    integration_step_s: 0.001
    control_period_s: 0.01        # driver and controller rate (a multiple of the step)
    state_period_s: 0.01          # state publish period (a multiple of the step)
    belief:                       # the controllers' belief of the vehicle
      vehicle: null               # null = the simulated vehicle
      cornering_stiffness_scale_front: 1.0
      cornering_stiffness_scale_rear: 1.0
    recording:
      enabled: true
      output_dir: runs            # relative to the working directory
      topics: all                 # or a list of topic names
    controller:                   # optional: your own controller node instead of fourws's
      command: [python3, my_controller.py]   # started with the run's ROS environment
      name: fourws_controller     # its ROS node name (the launcher remaps it to this)
    road_friction_coefficient: 0.5   # optional: the road's friction, replacing the vehicle
                                  # file's tire.friction_coefficient (a test surface)
    series: regulation            # optional: several maneuvers per law, see fourws_run.series
                                  # ("regulation", or a list of maneuver-field mappings)
    vehicle_limits:               # optional: when a run ends spun/diverged, replacing the
      max_sideslip_rad: 0.349     # maneuvers' own (fourws_sim.outcome.VehicleLimits)
      min_forward_speed_mps: -0.5
      max_roll_rad: 0.524
    realtime:                     # optional: what a realtime run must achieve to be ok
      min_realtime_factor: 0.0    # simulated per wall time (0: no demand)
      max_stale_share: 0.01       # share of control ticks without a fresh command, and of
                                  # commands refused, beyond which the run fails

:func:`load_scenario` validates everything it can without building the run: names of the model,
tire, integrator and laws are checked against their registries, the maneuver is loaded and
validated, periods must be whole multiples of the integration step. Errors are
:class:`~fourws_sim.errors.ParameterError` (field and file named) or
:class:`~fourws_sim.errors.UnknownNameError` (valid names listed).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from fourws_control.registry import LAWS
from fourws_run import interface
from fourws_run.config import ControllerSpec, RealtimeDemand, RunConfig, software_versions
from fourws_run.series import check_series
from fourws_run.step_target import scenario_for_law
from fourws_run.ticks import whole_multiple
from fourws_sim.errors import ParameterError, UnknownNameError, describe
from fourws_sim.integrators import INTEGRATORS
from fourws_sim.maneuvers import (ManeuverSpec, check_model, check_sampling,
                                  load_maneuver_spec,
                                  maneuver_spec_from_mapping)
from fourws_sim.models import MODELS
from fourws_sim.outcome import VehicleLimits, vehicle_limits_from
from fourws_sim.params import (CONFIG_DIR, UNCHECKED_KEY, Tire, Vehicle, available_configs,
                               check_plausible, load_vehicle, read_yaml, resolve_config_path,
                               unchecked_fields_from)
from fourws_sim.tires import TIRES

SCENARIO_DIR = CONFIG_DIR / "scenarios"
CLOCK_MODES = ("lockstep", "realtime")
#: Plausibility bounds of a scenario's numbers (docs/architecture.md, "Parameters"; the file
#: may lift one with ``unchecked_fields``). Periods in s, scales dimensionless (the belief
#: range is the controller node's parameter range).
_BOUNDS = {
    "integration_step_s": (1e-5, 0.05),
    "control_period_s": (1e-4, 1.0),
    "state_period_s": (1e-4, 1.0),
    "belief.cornering_stiffness_scale_front": (0.05, 20.0),
    "belief.cornering_stiffness_scale_rear": (0.05, 20.0),
}
#: Hard limits on what one run may cost (never lifted): integration steps and recorded
#: states (``duration_s`` over the step and the state period).
MAX_RUN_STEPS = 100_000_000
MAX_RUN_STATES = 10_000_000


@dataclass(frozen=True)
class BeliefSpec:
    """The controllers' belief of the vehicle: another vehicle and/or scaled stiffnesses."""

    vehicle: str | None = None
    cornering_stiffness_scale_front: float = 1.0
    cornering_stiffness_scale_rear: float = 1.0

    def build(self, simulated: Vehicle) -> Vehicle:
        """The belief vehicle (``simulated`` when no other vehicle is named), scaled."""
        base = simulated if self.vehicle is None else load_vehicle(self.vehicle)
        if self.cornering_stiffness_scale_front == 1.0 \
                and self.cornering_stiffness_scale_rear == 1.0:
            return base
        return base.with_axle_tires(self.cornering_stiffness_scale_front,
                                    self.cornering_stiffness_scale_rear)


@dataclass(frozen=True)
class RecordingSpec:
    """Recording of a run: on/off, output folder and the topics (``"all"`` or a list)."""

    enabled: bool = True
    output_dir: str = "runs"
    topics: str | tuple[str, ...] = "all"


@dataclass(frozen=True)
class Scenario:
    """A validated run scenario (see the module docstring for the file layout)."""

    name: str
    vehicle: str
    maneuver: ManeuverSpec
    laws: tuple[str, ...] = ("fws",)
    law_options: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    model: str = "8dof"
    tire: str | None = None
    integrator: str = "rk4"
    clock_mode: str = "lockstep"
    integration_step_s: float = 1e-3
    control_period_s: float = 1e-2
    state_period_s: float = 1e-2
    belief: BeliefSpec = field(default_factory=BeliefSpec)
    recording: RecordingSpec = field(default_factory=RecordingSpec)
    controller: ControllerSpec = field(default_factory=ControllerSpec)
    description: str = ""
    road_friction_coefficient: float | None = None
    series: str | tuple[ManeuverSpec, ...] | None = None
    vehicle_limits: VehicleLimits | None = None
    realtime: RealtimeDemand = field(default_factory=RealtimeDemand)
    source: str = field(default="", compare=False)
    unchecked_fields: frozenset[str] = frozenset()

    def build_vehicle(self) -> Vehicle:
        """The simulated vehicle, with the tire-model and road-friction overrides applied."""
        vehicle = load_vehicle(self.vehicle)
        if self.tire is None and self.road_friction_coefficient is None:
            return vehicle
        tire = vehicle.tire if vehicle.tire is not None else Tire()
        if self.tire is not None:
            tire = dataclasses.replace(tire, model=self.tire)
        if self.road_friction_coefficient is not None:
            tire = dataclasses.replace(tire,
                                       friction_coefficient=self.road_friction_coefficient)
        return dataclasses.replace(vehicle, tire=tire)

    def build_belief(self, simulated: Vehicle) -> Vehicle:
        """The controllers' belief vehicle for the simulated vehicle ``simulated``."""
        return self.belief.build(simulated)

    @property
    def controller_period_s(self) -> float:
        """Interval between the controller's answers, s, over which its command is held: it
        answers every published state, in lockstep once per control period and in realtime
        once per state period. The law is built for this period."""
        return self.control_period_s if self.clock_mode == "lockstep" else self.state_period_s

    def run_config(self, law: str, controller: ControllerSpec | None = None,
                   maneuver: ManeuverSpec | None = None) -> RunConfig:
        """The run of this scenario with ``law`` (or ``controller``, the user's), as the graph
        and the offline twin both run it. A maneuver that depends on the law (a step steer to
        a target lateral acceleration, a sine with dwell in multiples of A) is resolved for it
        (:func:`fourws_run.step_target.scenario_for_law`). ``maneuver`` runs instead of the
        scenario's (a member of its series, :func:`fourws_run.series.scenario_runs`).

        Raises
        ------
        ParameterError
            The maneuver cannot be resolved with the law.
        """
        ctrl = controller if controller is not None else self.controller
        maneuver = self.maneuver if maneuver is None else maneuver
        if self.vehicle_limits is not None:
            maneuver = dataclasses.replace(maneuver, vehicle_limits=self.vehicle_limits)
        scenario = dataclasses.replace(self, maneuver=maneuver)
        scenario = scenario_for_law(scenario, law) if ctrl.builtin else scenario
        vehicle = scenario.build_vehicle()
        rec = scenario.recording
        recorded: tuple[str, ...] = ()
        if rec.enabled:
            recorded = (interface.RECORDED_TOPICS if rec.topics == "all"
                        else tuple(rec.topics))
        return RunConfig(vehicle=vehicle, belief=scenario.build_belief(vehicle),
                         maneuver=scenario.maneuver, law=law,
                         law_options=dict(scenario.law_options.get(law, {})),
                         model=scenario.model, tire=scenario.tire,
                         integrator=scenario.integrator,
                         integration_step_s=scenario.integration_step_s,
                         control_period_s=scenario.control_period_s,
                         state_period_s=scenario.state_period_s,
                         clock_mode=scenario.clock_mode, controller=ctrl,
                         scenario=scenario.name, recorded_topics=recorded,
                         realtime=scenario.realtime, versions=software_versions())

    @property
    def control_steps(self) -> int:
        """Integration steps per control period."""
        return int(round(self.control_period_s / self.integration_step_s))

    def to_dict(self) -> dict[str, Any]:
        """The file layout as a plain mapping, with the maneuver inline (for recording)."""
        rec = self.recording
        extra = {UNCHECKED_KEY: sorted(self.unchecked_fields)} if self.unchecked_fields else {}
        return {
            "name": self.name, "description": self.description, "vehicle": self.vehicle,
            "maneuver": self.maneuver.to_dict(), "laws": list(self.laws),
            "law_options": {k: dict(v) for k, v in self.law_options.items()},
            "model": self.model, "tire": self.tire, "integrator": self.integrator,
            "clock_mode": self.clock_mode, "integration_step_s": self.integration_step_s,
            "control_period_s": self.control_period_s, "state_period_s": self.state_period_s,
            "belief": dataclasses.asdict(self.belief),
            "recording": {"enabled": rec.enabled, "output_dir": rec.output_dir,
                          "topics": rec.topics if isinstance(rec.topics, str)
                          else list(rec.topics)},
            "controller": {"command": list(self.controller.command),
                           "name": self.controller.node_name},
            "road_friction_coefficient": self.road_friction_coefficient,
            "series": (self.series if self.series is None or isinstance(self.series, str)
                       else [m.to_dict() for m in self.series]),
            **({} if self.vehicle_limits is None
               else {"vehicle_limits": self.vehicle_limits.to_dict()}),
            "realtime": self.realtime.to_dict(),
            **extra,
        }


_FIELDS = ("name", "description", "vehicle", "maneuver", "laws", "law_options", "model", "tire",
           "integrator", "clock_mode", "integration_step_s", "control_period_s",
           "state_period_s", "belief", "recording", "controller", "road_friction_coefficient",
           "series", "vehicle_limits", "realtime", UNCHECKED_KEY)


def _number(data: Mapping[str, Any], key: str, default: float, source: str,
            prefix: str = "", unchecked: frozenset[str] = frozenset()) -> float:
    value = data.get(key, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value) or value <= 0.0:
        raise ParameterError(f"{prefix}{key}",
                             f"must be a finite number > 0, got {describe(value)}", source)
    check_plausible(f"{prefix}{key}", float(value), _BOUNDS.get(f"{prefix}{key}"), source,
                    unchecked)
    return float(value)


def _string(data: Mapping[str, Any], key: str, default: str | None, source: str,
            prefix: str = "", allow_none: bool = False) -> str | None:
    value = data.get(key, default)
    if value is None and allow_none:
        return None
    if not isinstance(value, str) or not value:
        raise ParameterError(f"{prefix}{key}",
                             f"must be a non-empty string, got {describe(value)}", source)
    return value


def _named(loader: Any, name: str, key: str, source: str) -> Any:
    """``loader(name)``; an unknown name or a missing file is reported as this scenario's
    field ``key`` (errors inside the named file already name that file)."""
    try:
        return loader(name)
    except UnknownNameError as exc:
        if exc.source is not None:
            raise
        raise UnknownNameError(exc.kind, exc.name, exc.valid, f"{source} ({key})") from None
    except ParameterError as exc:
        if exc.source is not None:
            raise
        raise ParameterError(key, exc.problem, source) from None


def _known_models() -> list[str]:
    return sorted(set(MODELS) | {"8dof"})


def scenario_from_mapping(data: Any, source: str = "<mapping>",
                          default_name: str = "scenario") -> Scenario:
    """Validate a scenario mapping and build a :class:`Scenario`.

    Raises
    ------
    ParameterError
        Missing, unknown or malformed field (named with the file).
    UnknownNameError
        Unknown vehicle, maneuver, model, tire, integrator or law name.
    """
    if not isinstance(data, Mapping):
        raise ParameterError("<root>", f"scenario must be a mapping, got {describe(data)}",
                             source)
    unknown = sorted(str(k) for k in data if k not in _FIELDS)
    if unknown:
        raise ParameterError(unknown[0], f"unknown field (valid: {', '.join(sorted(_FIELDS))})",
                             source)
    for key in ("vehicle", "maneuver"):
        if key not in data:
            raise ParameterError(key, "missing required field", source)
    name = _string(data, "name", default_name, source)
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ParameterError("description", f"must be a string, got {describe(description)}",
                             source)
    unchecked = unchecked_fields_from(data, set(_BOUNDS), source)
    vehicle = _string(data, "vehicle", None, source)
    _named(load_vehicle, vehicle, "vehicle", source)  # fail now on a bad vehicle
    maneuver_data = data["maneuver"]
    if isinstance(maneuver_data, Mapping):
        maneuver = maneuver_spec_from_mapping(maneuver_data, f"{source} (inline maneuver)")
    elif isinstance(maneuver_data, str) and maneuver_data:
        maneuver = _named(load_maneuver_spec, maneuver_data, "maneuver", source)
    else:
        raise ParameterError("maneuver", "must be a maneuver name, a path or a mapping", source)

    laws_data = data.get("laws", ["fws"])
    if isinstance(laws_data, str):
        laws_data = [laws_data]
    if not isinstance(laws_data, (list, tuple)) or not laws_data \
            or not all(isinstance(x, str) for x in laws_data):
        raise ParameterError("laws", f"must be a non-empty list of law names, got "
                                     f"{describe(laws_data)}", source)
    known_laws = list(LAWS)
    for law in laws_data:
        if law not in known_laws:
            raise UnknownNameError("law", law, known_laws, source)
    for law in laws_data:
        if laws_data.count(law) > 1:  # it would run (and be recorded) as often
            raise ParameterError("laws", f"{law!r} is listed {laws_data.count(law)} times; "
                                 "each law runs once", source)
    law_options = data.get("law_options") or {}
    if not isinstance(law_options, Mapping) or not all(
            isinstance(v, Mapping) for v in law_options.values()):
        raise ParameterError("law_options", "must map law names to option mappings", source)
    for law in law_options:
        if law not in laws_data:
            raise ParameterError(f"law_options.{law}", "names a law not in laws", source)
        if "control_period_s" in law_options[law]:
            # every law runs at the loop's period (fourws_control.make_loop_law)
            raise ParameterError(f"law_options.{law}.control_period_s",
                                 "is the scenario's control_period_s; set that instead", source)

    model = _string(data, "model", "8dof", source)
    if model not in _known_models():
        raise UnknownNameError("model", str(model), _known_models(), source)
    check_model(maneuver, str(model), source)
    tire = _string(data, "tire", None, source, allow_none=True)
    if tire is not None and tire not in TIRES:
        raise UnknownNameError("tire", tire, list(TIRES), source)
    integrator = _string(data, "integrator", "rk4", source)
    if integrator not in INTEGRATORS:
        raise UnknownNameError("integrator", str(integrator), list(INTEGRATORS), source)
    INTEGRATORS[integrator].check_model(str(model), source)
    clock = _string(data, "clock_mode", "lockstep", source)
    if clock not in CLOCK_MODES:
        raise ParameterError("clock_mode", f"must be one of {', '.join(CLOCK_MODES)}, "
                             f"got {describe(clock)}", source)
    step = _number(data, "integration_step_s", 1e-3, source, unchecked=unchecked)
    control = _number(data, "control_period_s", 1e-2, source, unchecked=unchecked)
    state = _number(data, "state_period_s", 1e-2, source, unchecked=unchecked)
    whole_multiple(control, step, "control_period_s", source)
    whole_multiple(state, step, "state_period_s", source)
    # the driver samples its input once per answered state: each control period in
    # lockstep, each state period in realtime (Scenario.controller_period_s)
    check_sampling(maneuver, control if clock == "lockstep" else state, source)
    for count, limit, what in ((maneuver.duration_s / step, MAX_RUN_STEPS,
                                "integration steps (maneuver duration_s / integration_step_s)"),
                               (maneuver.duration_s / state, MAX_RUN_STATES,
                                "states (maneuver duration_s / state_period_s)")):
        if count > limit:
            raise ParameterError("maneuver.duration_s", f"the run would take {count:.3g} "
                                 f"{what}, more than the limit {limit}", source)

    belief_data = data.get("belief") or {}
    if not isinstance(belief_data, Mapping):
        raise ParameterError("belief", "must be a mapping", source)
    bad = sorted(set(belief_data) - {f.name for f in dataclasses.fields(BeliefSpec)})
    if bad:
        raise ParameterError(f"belief.{bad[0]}", "unknown field (valid: vehicle, "
                             "cornering_stiffness_scale_front, cornering_stiffness_scale_rear)",
                             source)
    belief_vehicle = _string(belief_data, "vehicle", None, source, "belief.", allow_none=True)
    if belief_vehicle is not None:
        _named(load_vehicle, belief_vehicle, "belief.vehicle", source)
    belief = BeliefSpec(
        vehicle=belief_vehicle,
        cornering_stiffness_scale_front=_number(belief_data, "cornering_stiffness_scale_front",
                                                1.0, source, "belief.", unchecked),
        cornering_stiffness_scale_rear=_number(belief_data, "cornering_stiffness_scale_rear",
                                               1.0, source, "belief.", unchecked))

    rec_data = data.get("recording") or {}
    if not isinstance(rec_data, Mapping):
        raise ParameterError("recording", "must be a mapping", source)
    bad = sorted(set(rec_data) - {"enabled", "output_dir", "topics"})
    if bad:
        raise ParameterError(f"recording.{bad[0]}",
                             "unknown field (valid: enabled, output_dir, topics)", source)
    enabled = rec_data.get("enabled", True)
    if not isinstance(enabled, bool):
        raise ParameterError("recording.enabled", "must be true or false", source)
    output_dir = _string(rec_data, "output_dir", "runs", source, "recording.")
    topics = rec_data.get("topics", "all")
    if topics != "all":
        if not isinstance(topics, (list, tuple)) or not topics or not all(
                isinstance(t, str) and t.startswith("/") for t in topics):
            raise ParameterError("recording.topics", f"must be 'all' or a list of topic names, "
                                                     f"got {describe(topics)}", source)
        topics = tuple(topics)

    controller = ControllerSpec.from_mapping(data.get("controller"), source)
    friction = data.get("road_friction_coefficient")
    if friction is not None:
        friction = _number(data, "road_friction_coefficient", 1.0, source)
    series = check_series(data.get("series"), maneuver, source)
    limits = (None if data.get("vehicle_limits") is None
              else vehicle_limits_from(data["vehicle_limits"], source))
    realtime = RealtimeDemand.from_mapping(data.get("realtime"), source)
    return Scenario(
        name=str(name), vehicle=str(vehicle), maneuver=maneuver, laws=tuple(laws_data),
        law_options={k: dict(v) for k, v in law_options.items()}, model=str(model), tire=tire,
        integrator=str(integrator), clock_mode=str(clock), integration_step_s=step,
        control_period_s=control, state_period_s=state, belief=belief,
        recording=RecordingSpec(enabled, str(output_dir), topics), controller=controller,
        description=description, road_friction_coefficient=friction, series=series,
        vehicle_limits=limits, realtime=realtime, source=source, unchecked_fields=unchecked)


def available_scenarios() -> list[str]:
    """Names (file stems) of the shipped scenario files."""
    return available_configs(SCENARIO_DIR)


def load_scenario(path_or_name: str | Path | Mapping[str, Any] = "default") -> Scenario:
    """Load and validate a scenario by name (``default``), YAML path or mapping."""
    if isinstance(path_or_name, Mapping):
        return scenario_from_mapping(path_or_name, "<inline scenario>")
    path = resolve_config_path("scenario", path_or_name, SCENARIO_DIR)
    return scenario_from_mapping(read_yaml(path), str(path), default_name=path.stem)


__all__ = ["BeliefSpec", "CLOCK_MODES", "RecordingSpec", "SCENARIO_DIR", "Scenario",
           "available_scenarios", "load_scenario", "scenario_from_mapping"]
