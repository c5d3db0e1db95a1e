# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Maneuver files: validation of a mapping into a :class:`~.base.ManeuverSpec`, loading by
name or path, and :func:`make_maneuver` (the spec's class from the registry, bound to a
vehicle)."""

from __future__ import annotations

import math
from pathlib import Path as FilePath
from typing import Any, Mapping

from fourws_sim.drivers import (PathDriverSpec, SpeedHoldSpec, TrackingDriverSpec,
                                path_driver_spec_from, speed_hold_spec_from,
                                tracking_driver_spec_from)
from fourws_sim.errors import ParameterError, UnknownNameError, describe
from fourws_sim.maneuvers.base import (MAX_DURATION_S, MAX_HAND_WHEEL_ANGLE_RAD,
                                       MAX_ROAD_WHEEL_ANGLE_RAD, STEER_INPUTS, Maneuver,
                                       ManeuverSpec, peak_input)
from fourws_sim.maneuvers.registry import DRIVER_KEYS, MANEUVER_CLASSES
from fourws_sim.models import FREE_STEERING_MODELS
from fourws_sim.outcome import VehicleLimits, vehicle_limits_from
from fourws_sim.params import (CONFIG_DIR, MAX_SPEED_MPS, UNCHECKED_KEY, Vehicle, _from_mapping,
                               available_configs, bounded_fields, check_plausible,
                               name_and_description, read_yaml, resolve_config_path,
                               unchecked_fields_from)

MANEUVER_DIR = CONFIG_DIR / "maneuvers"
#: Fields every maneuver file may have besides its type's fields.
COMMON_FIELDS = ("name", "type", "description", "initial_speed_mps", "duration_s",
                 "steer_input", "speed_hold", "vehicle_limits", *DRIVER_KEYS, UNCHECKED_KEY)
#: Plausibility bounds of the fields every maneuver has.
COMMON_BOUNDS = {"initial_speed_mps": (0.0, MAX_SPEED_MPS), "duration_s": (1e-3, MAX_DURATION_S)}
_DRIVER_SPECS = {"path_driver": path_driver_spec_from,
                 "tracking_driver": tracking_driver_spec_from}


def available_maneuvers() -> list[str]:
    """Names (file stems) of the shipped maneuver files."""
    return available_configs(MANEUVER_DIR)


def maneuver_class(kind: Any, source: str | None = None) -> type[Maneuver]:
    """The class of maneuver type ``kind``.

    Raises
    ------
    UnknownNameError
        ``kind`` is not a registered type (the message lists them and names ``source``).
    """
    if not isinstance(kind, str) or kind not in MANEUVER_CLASSES:
        raise UnknownNameError("maneuver type", kind, list(MANEUVER_CLASSES), source)
    return MANEUVER_CLASSES[kind]


def _bounded_fields(params_cls: type) -> set[str]:
    """Names ``unchecked_fields`` of a maneuver of this parameter class may list."""
    return {*COMMON_BOUNDS, *bounded_fields(params_cls),
            *bounded_fields(SpeedHoldSpec, "speed_hold."),
            *bounded_fields(VehicleLimits, "vehicle_limits."),
            *bounded_fields(PathDriverSpec, "path_driver."),
            *bounded_fields(TrackingDriverSpec, "tracking_driver.")}


def _check_peak_input(params: Any, steer_input: str, source: str | None,
                      unchecked: frozenset[str]) -> None:
    """Refuse an open-loop input angle beyond the plausible road- or hand-wheel angle."""
    peak = peak_input(params)
    if peak is None or peak[0] in unchecked:
        return
    limit, what = ((MAX_ROAD_WHEEL_ANGLE_RAD, "road-wheel") if steer_input == "road_wheel"
                   else (MAX_HAND_WHEEL_ANGLE_RAD, "hand-wheel"))
    if peak[1] > limit:
        raise ParameterError(peak[0], f"asks for a {what} angle of {peak[1]:.4g} rad, beyond the "
                             f"plausible {limit:.4g} rad (list it under {UNCHECKED_KEY} to "
                             "accept it)", source)


def maneuver_spec_from_mapping(data: Any, source: str = "<mapping>",
                               default_name: str = "maneuver") -> ManeuverSpec:
    """Validate a maneuver mapping and build a :class:`ManeuverSpec`.

    Raises
    ------
    UnknownNameError
        ``type`` is not a registered maneuver type.
    ParameterError
        A field is missing, unknown, of the wrong type, out of range or outside its
        plausibility bounds (names field and file).
    """
    if not isinstance(data, Mapping):
        raise ParameterError("<root>", f"maneuver must be a mapping, got {describe(data)}",
                             source)
    if "type" not in data:
        raise ParameterError("type", f"missing required field (valid: "
                             f"{', '.join(sorted(MANEUVER_CLASSES))})", source)
    kind = data["type"]
    cls = maneuver_class(kind, source)
    name, description = name_and_description(data, source, default_name)
    unchecked = unchecked_fields_from(data, _bounded_fields(cls.Params), source)
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
    for key, bounds in COMMON_BOUNDS.items():
        check_plausible(key, common[key], bounds, source, unchecked)
    steer_input = data.get("steer_input", cls.default_steer_input)
    if steer_input not in STEER_INPUTS:
        raise ParameterError("steer_input", f"must be one of {', '.join(STEER_INPUTS)}, "
                                            f"got {describe(steer_input)}", source)
    if cls.fixed_steer_input and steer_input != cls.default_steer_input:
        raise ParameterError("steer_input", f"{kind} is defined in {cls.default_steer_input} "
                             f"angles; got {steer_input!r}", source)
    for key in DRIVER_KEYS:
        if key in data and cls.driver_key != key:
            types = [k for k, c in MANEUVER_CLASSES.items() if c.driver_key == key]
            raise ParameterError(key, f"only for {', '.join(types)}", source)
    type_fields = {k: v for k, v in data.items() if k not in COMMON_FIELDS}
    params = _from_mapping(cls.Params, type_fields, source, "", unchecked)
    cls.check_spec(params, common, source)
    for key in getattr(cls.Params, "event_fields", ()):
        if getattr(params, key) >= common["duration_s"]:
            raise ParameterError(key, f"{getattr(params, key):g} s is not before the end of the "
                                 f"run (duration_s {common['duration_s']:g} s): the input "
                                 "would never be applied", source)
    _check_peak_input(params, steer_input, source, unchecked)
    speed_hold = speed_hold_spec_from(data.get("speed_hold"), source, unchecked=unchecked)
    limits = vehicle_limits_from(data.get("vehicle_limits"), source, unchecked=unchecked)
    drivers = {key: (_DRIVER_SPECS[key](data.get(key), source, unchecked=unchecked)
                     if cls.driver_key == key else None) for key in DRIVER_KEYS}
    return ManeuverSpec(
        name=name, type=kind, params=params, steer_input=steer_input,
        description=description, speed_hold=speed_hold, vehicle_limits=limits, source=source,
        unchecked_fields=unchecked, **drivers, **common)


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


def check_model(spec: ManeuverSpec, model: str, source: str | None = None) -> None:
    """Check that maneuver ``spec`` can steer model ``model``: a torque-input type needs a
    model with a steering system (:data:`fourws_sim.models.FREE_STEERING_MODELS`), an angle
    type one without (that model would ignore the angle and drive straight on).

    Raises
    ------
    ParameterError
        (field ``model``) otherwise, naming the models that fit.
    """
    control = maneuver_class(spec.type).steering_control
    free = model in FREE_STEERING_MODELS
    if control == "torque" and not free:
        raise ParameterError("model", f"maneuver {spec.name!r} ({spec.type}) steers with a "
                             f"torque: it needs a model with a steering system "
                             f"({', '.join(FREE_STEERING_MODELS)}), got {model!r}",
                             source or spec.source or spec.name)
    if control == "angle" and free:
        raise ParameterError("model", f"model {model!r} is steered by the driver's torque "
                             f"(free control); maneuver {spec.name!r} ({spec.type}) steers by "
                             f"angle: use a torque-input maneuver or a fixed-control model",
                             source or spec.source or spec.name)


def make_maneuver(spec_or_name: ManeuverSpec | str | FilePath | Mapping[str, Any],
                  vehicle: Vehicle) -> Maneuver:
    """Build a runnable :class:`Maneuver` of the spec's type for ``vehicle`` from a spec,
    name, path or mapping."""
    spec = (spec_or_name if isinstance(spec_or_name, ManeuverSpec)
            else load_maneuver_spec(spec_or_name))
    return maneuver_class(spec.type)(spec, vehicle)


__all__ = ["COMMON_BOUNDS", "COMMON_FIELDS", "MANEUVER_DIR", "available_maneuvers",
           "check_model", "check_sampling", "load_maneuver_spec",
           "make_maneuver", "maneuver_class", "maneuver_spec_from_mapping",
           "resolve_maneuver_path"]
