# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A study point again, through the real node graph: its run description, the row of its bag,
and how that row compares with the study's.

``fourws study rerun DIR --point ID`` (:mod:`fourws_cli.cmd_study`) loads the study of
``DIR`` (:func:`study_of`), runs the point's :class:`~fourws_run.config.RunConfig` through
:func:`fourws_ros.graph_run.run_graph` into a bag, and computes the point's row from the bag
(:func:`bag_row`) with the functions the study used (:func:`fourws_study.point.evaluate`):
the recorded ticks -- every state the maneuver and the controller answered, its driver input
and rear-steer command -- are the arrays the offline twin produces, so the two rows agree
(:func:`compare_rows`; ``test/test_study.py`` checks it on a recorded point).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pyarrow.compute as pc

from fourws_analysis.bag import load_bag
from fourws_run import interface
from fourws_run.config import RunConfig
from fourws_sim.errors import ParameterError
from fourws_study.kernel import DURATION, LoopRecord
from fourws_study.point import evaluate, law_for, point_row
from fourws_study.spec import Study, load_study
from fourws_study.store import MANIFEST, read_results, study_hash

#: Columns of a row that describe the computation, not the run (left out of comparisons).
NOT_COMPARED = ("engine", "fallback", "wall_time_s", "metrics_json", "end_reason")


def study_of(root: str | Path) -> Study:
    """The study of the folder ``root`` (its ``study.yaml``), checked against the manifest.

    Raises
    ------
    ParameterError
        Not a study folder, or the study (file, scenario or vehicle) changed since it ran.
    """
    root = Path(root)
    manifest = root / MANIFEST
    if not manifest.is_file():
        raise ParameterError("DIR", f"{root} is not a study folder (no {MANIFEST})")
    study = load_study(root / "study.yaml")
    if json.loads(manifest.read_text()).get("hash") != study_hash(study):
        raise ParameterError("DIR", f"the study in {root} no longer resolves to the runs it "
                             "ran (its scenario, vehicle or maneuver files changed)")
    return study


def study_row(root: str | Path, study: Study, point: int) -> dict[str, Any]:
    """The row of ``point`` of ``study`` in its folder ``root``.

    Raises
    ------
    ParameterError
        The point has not been run, or a block file is damaged.
    """
    table = read_results(root, study)
    rows = table.filter(pc.equal(table.column("point"), point)).to_pylist()
    if not rows:
        raise ParameterError("--point", f"point {point} is not in the results of {root}")
    return rows[0]


def _stamp_ns(fields: dict[str, np.ndarray]) -> np.ndarray:
    return (fields["header.stamp.sec"].astype(np.int64) * 1_000_000_000
            + fields["header.stamp.nanosec"].astype(np.int64))


def record_from_bag(path: str | Path, end_reason: str = DURATION) -> LoopRecord:
    """The tick arrays of a recorded run: every state the maneuver and the controller
    answered, with the driver input stamped with it and the rear-steer command naming its
    step (:class:`~fourws_study.kernel.LoopRecord`, engine ``graph``).

    Raises
    ------
    BagError
        The bag cannot be read or lacks the state, driver or command stream.
    """
    # numba: loop_kernels compiles the loop; only a bag's record needs its channel names
    from fourws_study.loop_kernels import CHANNELS, STATE_CHANNELS

    run = load_bag(path)
    state = run.require(interface.STATE, "sim_time_s")
    driver = run.require(interface.DRIVER_INPUT, "front_wheel_angle_rad")
    command = run.require(interface.REAR_STEER_CMD, "angle_rad")
    order = np.argsort(state.fields["step"], kind="stable")
    s_stamp = _stamp_ns(state.fields)[order]
    d_index = {int(ns): i for i, ns in enumerate(_stamp_ns(driver.fields))}
    c_index = {int(step): i for i, step in enumerate(command.fields["state_step"])}
    steps = state.fields["step"][order]
    ticks = [k for k in range(order.size)
             if int(s_stamp[k]) in d_index and int(steps[k]) in c_index]
    sel = order[ticks]
    d_sel = np.array([d_index[int(s_stamp[k])] for k in ticks], dtype=np.int64)
    c_sel = np.array([c_index[int(steps[k])] for k in ticks], dtype=np.int64)
    channels: dict[str, np.ndarray] = {}
    for name in CHANNELS:
        if name in state.fields and state.fields[name].ndim == 1:
            channels[name] = state.fields[name].astype(np.float64)[sel]
    channels["steering_wheel_angle_rad"] = driver.fields["steering_wheel_angle_rad"][d_sel]
    channels["front_wheel_angle_cmd_rad"] = driver.fields["front_wheel_angle_rad"][d_sel]
    channels["rear_command_rad"] = command.fields["angle_rad"][c_sel]
    channels["rear_law_rad"] = np.full(sel.size, math.nan)  # the law's own output is not sent
    channels["drive_torque_total_nm"] = driver.fields["drive_torque_nm"][d_sel].sum(axis=1)
    channels["brake_torque_total_nm"] = driver.fields["brake_torque_nm"][d_sel].sum(axis=1)
    final = None
    if ticks and ticks[-1] + 1 < order.size and not end_reason.startswith(
            "the simulation diverged"):
        last = order[ticks[-1] + 1]  # the state after the last answered tick
        final = {name: float(state.fields[name][last]) for name in STATE_CHANNELS}
    return LoopRecord(channels["sim_time_s"], channels, end_reason, "graph", final=final)


def bag_row(study: Study, index: int, config: RunConfig, bag: str | Path,
            end_reason: str = DURATION) -> dict[str, Any]:
    """The row of point ``index`` computed from its recorded bag (as the study computes it
    from the offline run)."""
    row = point_row(study, study.point(index))
    row["speed_mps"] = config.speed_mps
    return evaluate(row, study, config, law_for(config), record_from_bag(bag, end_reason))


def compare_rows(study_row: dict[str, Any], graph_row: dict[str, Any],
                 columns: Sequence[str] | None = None) -> list[tuple[str, Any, Any, float]]:
    """``(column, study value, graph value, relative difference)`` of the numeric and
    boolean columns both rows have (``NOT_COMPARED`` left out); the difference is 0 for equal
    values, inf for a value only one side has or unequal booleans and texts."""
    out = []
    for col in (columns if columns is not None else study_row):
        if col in NOT_COMPARED or col not in graph_row:
            continue
        a, b = study_row.get(col), graph_row.get(col)
        if isinstance(a, list) or isinstance(b, list):
            a_arr, b_arr = np.asarray(a or [], float), np.asarray(b or [], float)
            if a_arr.shape != b_arr.shape:
                out.append((col, a, b, math.inf))
                continue
            scale = max(float(np.max(np.abs(a_arr), initial=0.0)), 1e-300)
            out.append((col, a, b, float(np.max(np.abs(a_arr - b_arr), initial=0.0)) / scale))
        elif isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str) \
                or isinstance(b, str) or a is None or b is None:
            out.append((col, a, b, 0.0 if a == b else math.inf))
        else:
            fa, fb = float(a), float(b)
            if fa == fb or (math.isnan(fa) and math.isnan(fb)):
                out.append((col, a, b, 0.0))
            else:
                out.append((col, a, b, abs(fa - fb) / max(abs(fa), abs(fb), 1e-300)))
    return out


__all__ = ["NOT_COMPARED", "bag_row", "compare_rows", "record_from_bag", "study_of",
           "study_row"]
