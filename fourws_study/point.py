# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""What one study point computes: its run, the metrics of ``fourws analyze``, how far it went,
its status, and the linear closed-loop eigenvalues at its speed.

A point's row (:func:`run_point`) holds, besides its number, sample, seed and axis values:

* the metrics ``fourws analyze`` gives for its maneuver -- the same function,
  :func:`fourws_analysis.compare.analyze_run` on the run's tick arrays (without the model
  overlays): ISO 7401 step metrics and steady-state gains (``iso7401.*``), ISO 4138
  gradients (``iso4138.*``), ISO 3888-2 clearance and pass/fail (``iso3888.*``); every
  metric of the analysis, frequency responses included, is also in ``metrics_json``;
* :class:`fourws_analysis.extremes.RunExtremes`: peak |sideslip|, |yaw rate|, |a_y|, |roll|
  and the time the rear actuator spent at its angle and at its rate limit;
* ``status``: ``ok``; ``spun`` (the car spun or drove backwards) or ``diverged`` (its roll
  left the model's range, or the state became non-finite), by the run maneuver's
  :class:`~fourws_sim.outcome.VehicleLimits` -- the rule that ends a graph run and the twin
  ``spun``/``diverged``, applied to the run's states (:func:`status_of`); each with
  ``status_reason`` and ``status_time_s``; or ``error`` with the message (a point that cannot
  be built or run never stops the study). The run itself ends at that state on every path
  (the compiled loop as the twin), and ``fourws analyze`` reports no ISO metrics of a run
  past its limits: a spun or diverged point's ``iso7401.*``, ``iso4138.*`` and ``iso3888.*``
  columns are absent (null in the table; ``metrics_json`` says why under ``unavailable``);
* the law closed on the 8-DOF linearized at straight running at the point's speed
  (:func:`fourws_analysis.compare.eightdof_linear_system`) and on the matching linear model
  (the 3-DOF when the vehicle has roll data, else the 2-DOF,
  :func:`fourws_analysis.linear.closed_loop`), both with the belief's gains on the true car:
  their eigenvalues (1/s), the largest real part and whether it is stable.

Column names and types are fixed per study (:func:`columns`), so every block of results has
the same schema.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
import types
import typing
from typing import Any, Iterable, Mapping

import numpy as np

from fourws_analysis import compare, iso4138, iso7401, lane_change, linear
from fourws_analysis.bag import (STATE_CHANNELS, RunData, TopicArrays, UniformRun,
                                 resample, stamp_seconds)
from fourws_analysis.extremes import RunExtremes, run_extremes
from fourws_control import Law, RearSteerActuator
from fourws_run import interface
from fourws_run.config import RunConfig
from fourws_sim.errors import FourwsError
from fourws_study.kernel import (LoopRecord, Prepared, build_law, prepare_compiled,
                                 run_compiled_block, run_interpreted)
from fourws_study.spec import Point, Study

#: Eigenvalues closer to 0 than this (1/s) are the 8-DOF's coasting-speed and wheel-spin
#: modes at a trim without drag (and position and heading): the steer does not reach them,
#: so they take no part in the stability verdict (as in the analysis' lateral modes).
ZERO_MODE_PER_S = 1e-6
#: Statuses of a point.
STATUSES = ("ok", "spun", "diverged", "error")
#: Response channels of the ISO 7401 step metrics (those ``analyze_run`` passes).
STEP_CHANNELS = ("yaw_rate_radps", "lateral_accel_mps2")
#: Laws built in this process, by law, belief, period and options (laws are stateless; the
#: points of one belief share one, e.g. an lqr design of a second).
_LAWS: dict[str, Law] = {}
_LAW_CACHE_SIZE = 64


def _flatten(prefix: str, value: Any, out: dict[str, Any]) -> None:
    """Numeric and boolean leaves of a metrics mapping as dotted columns (lists and texts
    stay in ``metrics_json``)."""
    if isinstance(value, Mapping):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}", v, out)
    elif value is None or isinstance(value, (bool, int, float)):
        out[prefix] = value


def _placeholder_value(hint: Any) -> Any:
    """A value of type ``hint``: True, 0, 0.0, '', an empty list or dict, a tuple of such;
    ``X | None`` gives X's (the column's type is X's)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (types.UnionType, typing.Union):
        return _placeholder_value(next(a for a in args if a is not type(None)))
    if origin is tuple:
        return tuple(_placeholder_value(a) for a in args)
    simple = {bool: True, int: 0, float: 0.0, str: ""}
    if hint in simple:
        return simple[hint]
    if (origin or hint) in (list, dict):
        return (origin or hint)()
    raise TypeError(f"no placeholder for a field of type {hint!r}")


def _placeholder(cls: type, **given: Any) -> Any:
    """An instance of the dataclass ``cls`` built from its definition: the fields in
    ``given`` with those values, every other field a value of its declared type
    (:func:`_placeholder_value`). A field added to a result class needs no change here."""
    hints = typing.get_type_hints(cls)
    return cls(**{f.name: given[f.name] if f.name in given else _placeholder_value(hints[f.name])
                  for f in dataclasses.fields(cls)})


def _metric_templates() -> dict[str, Any]:
    """Every flattened metric column with a value of its type: the analysis results built
    from their definitions with placeholder values (:func:`_placeholder`), so the column
    names and types are the analysis' own."""
    step = _placeholder(iso7401.StepResult, responses={
        ch: _placeholder(iso7401.StepMetrics, channel=ch) for ch in STEP_CHANNELS})
    steady = _placeholder(iso4138.SteadyStateHandling)
    lane = _placeholder(lane_change.LaneChangeResult)
    out: dict[str, Any] = {}
    for prefix, result in (("iso7401", step), ("iso4138", steady), ("iso3888", lane)):
        _flatten(prefix, result.to_dict(), out)
    return out


_EXTREMES = tuple(f for f in RunExtremes.__dataclass_fields__)


def columns(study: Study) -> list[tuple[str, str]]:
    """The result table's columns of ``study`` as (name, type): ``int64``, ``float64``,
    ``bool``, ``string`` or ``list<float64>``."""
    cols = [("point", "int64"), ("sample", "int64"), ("seed", "int64"), ("law", "string"),
            ("speed_mps", "float64")]
    have = {c for c, _ in cols}
    for axis in study.axes:
        if axis.key not in have:
            cols.append((axis.key, "float64" if axis.numeric else "string"))
            have.add(axis.key)
    cols += [("status", "string"), ("status_reason", "string"), ("status_time_s", "float64"),
             ("engine", "string"), ("fallback", "string"), ("end_reason", "string"),
             ("duration_s", "float64"), ("vehicle_steps", "int64")]
    cols += [(name, "float64") for name in _EXTREMES]
    for name, value in _metric_templates().items():
        kind = "bool" if isinstance(value, bool) else (
            "int64" if isinstance(value, int) else "float64")
        cols.append((name, kind))
    cols += [("linear_model", "string"),
             ("eig_max_real_8dof_lin_per_s", "float64"), ("stable_8dof_lin", "bool"),
             ("eig_8dof_lin_re_per_s", "list<float64>"),
             ("eig_8dof_lin_im_per_s", "list<float64>"),
             ("eig_max_real_linear_per_s", "float64"), ("stable_linear", "bool"),
             ("eig_linear_re_per_s", "list<float64>"), ("eig_linear_im_per_s", "list<float64>"),
             ("linear_notes", "string"), ("metrics_json", "string"), ("wall_time_s", "float64")]
    return cols


def law_for(config: RunConfig) -> Law:
    """The run's law (:func:`fourws_study.kernel.build_law`), shared by the points of this
    process with the same law, belief, period and options."""
    key = json.dumps([config.law, config.belief.cache_key(), config.controller_period_s,
                      dict(config.law_options)], sort_keys=True, default=str)
    law = _LAWS.get(key)
    if law is None:
        if len(_LAWS) >= _LAW_CACHE_SIZE:
            _LAWS.pop(next(iter(_LAWS)))
        law = _LAWS[key] = build_law(config)
    return law


def _with_final(record: LoopRecord) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Tick times and state channels with the final state appended (what a bag records)."""
    if record.final is None:
        return record.time_s, record.channels
    ch = dict(record.channels)
    for name, value in record.final.items():
        ch[name] = np.append(ch[name], value)
    return ch["sim_time_s"], ch


def uniform_run(record: LoopRecord, config: RunConfig, name: str = "point",
                config_dict: dict[str, Any] | None = None) -> UniformRun:
    """The run as ``fourws analyze`` reads its bag: the states the simulator publishes (the
    ticks and the final state) and the driver inputs answering them, stamped to the ns as the
    bag stamps them, put on the analysis grid by :func:`fourws_analysis.bag.resample`
    (``config_dict``: ``config.to_dict()`` when the caller has it)."""
    t, full = _with_final(record)
    ns = interface.times_to_ns(t)
    stamps = stamp_seconds(ns // interface.NS_PER_S, ns % interface.NS_PER_S)
    n = record.time_s.size
    state = TopicArrays(stamps, {k: np.asarray(v, dtype=np.float64) for k, v in full.items()
                                 if k in STATE_CHANNELS})
    driver = TopicArrays(stamps[:n], {
        "steering_wheel_angle_rad": record.channels["steering_wheel_angle_rad"],
        "front_wheel_angle_rad": record.channels["front_wheel_angle_cmd_rad"]})
    run = RunData(path=name,
                  config=config.to_dict() if config_dict is None else config_dict,
                  topics={interface.STATE: state, interface.DRIVER_INPUT: driver})
    return resample(run)


def analysis_metrics(run: UniformRun) -> tuple[dict[str, Any], dict[str, Any]]:
    """``(columns, everything)``: the metrics of ``fourws analyze`` for the run
    (:func:`fourws_analysis.compare.analyze_run` without model overlays), flattened to the
    columns of :func:`columns`, and the whole metrics mapping."""
    everything = compare.analyze_run(run, eig_sweep=False, models=False).metrics()
    flat: dict[str, Any] = {}
    for prefix, key in (("iso7401", "iso7401_step"), ("iso4138", "iso4138_steady_state"),
                        ("iso3888", "iso3888_lane_change")):
        if key in everything:
            _flatten(prefix, everything[key], flat)
    return flat, everything


def status_of(record: LoopRecord, config: RunConfig) -> tuple[str, str, float | None]:
    """``(status, reason, time)`` of a run (module docstring): ``diverged`` with the twin's
    reason if the state became non-finite, else the first of its states (the final one
    included) past the maneuver's vehicle limits
    (:meth:`fourws_sim.outcome.VehicleLimits.first_violation`: ``spun`` or ``diverged``
    with its reason and time), else ``ok``."""
    t = record.time_s
    if record.diverged:
        return "diverged", record.end_reason, float(t[-1]) if t.size else None
    t_all, ch = _with_final(record)
    breach = config.maneuver.vehicle_limits.first_violation(
        t_all, ch["sideslip_rad"], ch["speed_mps"], ch["roll_rad"])
    if breach is not None:
        return breach.kind, breach.reason, breach.time_s
    return "ok", "", None


def extremes_of(record: LoopRecord, config: RunConfig) -> RunExtremes:
    """:func:`fourws_analysis.extremes.run_extremes` of a run, with its actuator's limits
    (the controller's, from the belief vehicle) and its maneuver's vehicle limits."""
    t, ch = _with_final(record)
    act = RearSteerActuator(config.belief)
    return run_extremes(t, ch["sideslip_rad"], ch["yaw_rate_radps"],
                        ch["lateral_accel_mps2"], ch["roll_rad"],
                        record.channels["rear_command_rad"],
                        float(config.controller_period_s), act.angle_limit_rad,
                        act.rate_limit_rad_per_s, config.maneuver.vehicle_limits,
                        ch["speed_mps"])


def _modes(eigenvalues: Iterable[complex]) -> np.ndarray:
    eig = np.asarray(list(eigenvalues), dtype=complex)
    eig = eig[np.isfinite(eig) & (np.abs(eig) > ZERO_MODE_PER_S)]
    return eig[np.lexsort((eig.imag, -eig.real))]


def linear_model_of(config: RunConfig) -> str:
    """The linear model matching the run's vehicle: ``3dof`` with roll data, else ``2dof``."""
    return "3dof" if config.vehicle.roll is not None else "2dof"


def linear_stability(config: RunConfig, law: Law) -> dict[str, Any]:
    """Eigenvalues of the law closed on the 8-DOF linearized at the point's speed and on the
    matching linear model (module docstring); a model that cannot be built leaves its
    columns empty and says why in ``linear_notes``."""
    out: dict[str, Any] = {"linear_model": linear_model_of(config)}
    notes = []
    speed = config.speed_mps
    if config.vehicle.body is not None and config.vehicle.roll is not None:
        try:
            a8 = compare.eightdof_closed_matrices(config.vehicle, speed, law, config.belief,
                                                  config.law_options)[0]
            eig = _modes(np.linalg.eigvals(a8))
            out.update(_eig_columns("8dof_lin", eig))
        except (FourwsError, np.linalg.LinAlgError) as exc:
            notes.append(f"8dof linearized: {exc}")
    else:
        notes.append("8dof linearized: the vehicle has no roll and body data")
    try:
        a_lin = linear.closed_loop_matrices(out["linear_model"], config.vehicle, law, speed)[0]
        out.update(_eig_columns("linear", _modes(np.linalg.eigvals(a_lin))))
    except (FourwsError, np.linalg.LinAlgError) as exc:
        notes.append(f"{out['linear_model']}: {exc}")
    out["linear_notes"] = "; ".join(notes)
    return out


def _eig_columns(name: str, eig: np.ndarray) -> dict[str, Any]:
    top = float(np.max(eig.real)) if eig.size else math.nan
    return {f"eig_max_real_{name}_per_s": top,
            f"stable_{name}": bool(eig.size and top < -linear.MARGINAL_TOL_PER_S),
            f"eig_{name}_re_per_s": [float(e.real) for e in eig],
            f"eig_{name}_im_per_s": [float(e.imag) for e in eig]}


def _json_default(obj: Any) -> Any:
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    return str(obj)


def point_row(study: Study, point: Point) -> dict[str, Any]:
    """The identifying columns of a point: number, sample, seed, axis values, law."""
    row: dict[str, Any] = {"point": point.index, "sample": point.sample, "seed": point.seed}
    row.update(point.values)
    row["law"] = study.base.law if "law" not in row else row["law"]
    row["status_reason"] = ""
    return row


def evaluate(row: dict[str, Any], study: Study, config: RunConfig, law: Law,
             record: LoopRecord, config_dict: dict[str, Any] | None = None) -> dict[str, Any]:
    """Fill ``row`` with what a run gives (metrics, extremes, status, linear eigenvalues):
    the same for the offline run of a point and for its rerun through the node graph
    (``config_dict``: ``config.to_dict()`` when the caller has it)."""
    steps = int(round(config.controller_period_s / config.integration_step_s))
    row.update(speed_mps=config.speed_mps, engine=record.engine, fallback=record.fallback,
               end_reason=record.end_reason,
               duration_s=float(record.time_s[-1] - record.time_s[0]),
               vehicle_steps=int(record.time_s.size) * steps)
    extremes = extremes_of(record, config)
    row.update(extremes.to_dict())
    flat, everything = analysis_metrics(uniform_run(record, config,
                                                    config_dict=config_dict))
    row.update(flat)
    everything["extremes"] = extremes.to_dict()
    status, reason, at = status_of(record, config)
    row.update(status=status, status_reason=reason, status_time_s=at)
    row.update(linear_stability(config, law))
    row["metrics_json"] = json.dumps(everything, default=_json_default, sort_keys=True)
    return row


def run_point(study: Study, index: int, compiled: bool = True) -> dict[str, Any]:
    """The result row of point ``index`` of ``study`` (module docstring); never raises for
    what the point does (a failing point is ``status`` ``error``).

    Parameters
    ----------
    study : Study
    index : int
    compiled : bool
        Take the compiled path where it applies (False: the interpreted twin for every
        point; the rows are the same).
    """
    return run_points(study, [index], compiled)[0]


def run_points(study: Study, indices: Iterable[int], compiled: bool = True
               ) -> list[dict[str, Any]]:
    """The result rows of points ``indices`` (one block of a study): their compiled runs in
    one call of the batch kernel (:func:`fourws_study.kernel.run_compiled_block`), the
    interpreted twin for the others; each row as :func:`run_point` gives it."""
    rows: list[dict[str, Any]] = []
    runs: list[tuple[RunConfig, Law] | None] = []
    seconds: list[float] = []
    preps: list[Prepared] = []
    prepared: dict[int, int] = {}  # row -> its position in preps
    fallback: dict[int, str] = {}
    for n, index in enumerate(indices):
        t0 = time.perf_counter()
        point = study.point(index)
        row = point_row(study, point)
        rows.append(row)
        runs.append(None)
        try:
            config = study.config(point)
            row["speed_mps"] = config.speed_mps
            law = law_for(config)
            prep = (prepare_compiled(config, law) if compiled
                    else "compiled path not asked for")
        except (FourwsError, np.linalg.LinAlgError) as exc:
            _failed(row, exc)
        else:
            runs[n] = (config, law)
            if isinstance(prep, str):
                fallback[n] = prep
            else:
                prepared[n] = len(preps)
                preps.append(prep)
        seconds.append(time.perf_counter() - t0)
    records = run_compiled_block(preps) if preps else []
    for n, row in enumerate(rows):
        t0 = time.perf_counter()
        run = runs[n]
        if run is not None:
            config, law = run
            try:
                record = records[prepared[n]] if n in prepared else fallback[n]
                if isinstance(record, str):
                    record = run_interpreted(config, fallback=record)
                else:
                    seconds[n] += record.loop_seconds
                evaluate(row, study, config, law, record)
            except (FourwsError, np.linalg.LinAlgError) as exc:
                _failed(row, exc)
        row["wall_time_s"] = seconds[n] + (time.perf_counter() - t0)
    return rows


def _failed(row: dict[str, Any], exc: Exception) -> None:
    """Mark ``row`` as an ``error`` point with the message (a point never stops a study)."""
    reason = (f"linear algebra failed: {exc}" if isinstance(exc, np.linalg.LinAlgError)
              else str(exc))
    row.update(status="error", status_reason=reason)


__all__ = ["STATUSES", "ZERO_MODE_PER_S", "analysis_metrics", "columns", "evaluate",
           "extremes_of", "law_for", "linear_model_of", "linear_stability", "point_row",
           "run_point", "run_points", "status_of", "uniform_run"]
