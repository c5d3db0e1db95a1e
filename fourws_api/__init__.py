# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""fourws from Python, without ROS: for notebooks and scripts.

Five lines from a vehicle to the numbers of ``fourws analyze``::

    import fourws_api as fw
    car = fw.load_vehicle("table_8_1")
    run = fw.simulate(car, "step_steer_85kmh", law="sol1")
    run.history["yaw_rate_radps"]            # time history over run.time_s
    run.metrics["iso7401_step"]              # the metrics fourws analyze gives

:func:`simulate` runs the offline twin of the lockstep node graph
(:func:`fourws_run.closed_loop.run_closed_loop`: the same tick sequence, so a graph run of the
same configuration records the same states) and analyzes the run as ``fourws analyze`` analyzes
its bag (:func:`fourws_analysis.compare.analyze_run` on the states and driver inputs the bag
would hold, stamped to the ns as the recorder stamps them).

Why not ``fourws``: that name is the generated ROS interface package (``fourws.msg``, built by
``make setup`` from ``msg/``); a second ``fourws`` Python package would shadow it or be shadowed
by it depending on the import path.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from fourws_analysis.bag import RunData, TopicArrays, resample
from fourws_run import interface
from fourws_run.closed_loop import ClosedLoopResult, run_closed_loop
from fourws_sim.maneuvers import ManeuverSpec, load_maneuver_spec
from fourws_sim.params import Vehicle, load_vehicle


@dataclass
class Simulation:
    """One simulated run: its time histories and its metrics.

    Attributes
    ----------
    time_s : numpy.ndarray
        Tick times (the control period apart), s.
    history : dict of str to numpy.ndarray
        Every ``VehicleState`` output (``yaw_rate_radps``, ``lateral_accel_mps2``,
        ``sideslip_rad``, ``front_wheel_angle_rad``, ``rear_wheel_angle_rad``, ...; per wheel
        ``(N, 4)``) and the driver's and controller's commands (``steering_wheel_angle_rad``,
        ``front_wheel_angle_cmd_rad``, ``rear_command_rad``), one row per tick.
    metrics : dict
        What ``fourws analyze --json`` gives for the run's bag (ISO 7401, ISO 4138, ISO 3888,
        frequency response, eigenvalues, ... as the maneuver allows).
    result : ClosedLoopResult
        The twin's whole result (final state, phases, end reason).
    """

    time_s: np.ndarray
    history: dict[str, np.ndarray]
    metrics: dict[str, Any]
    result: ClosedLoopResult = field(repr=False)


def as_run_data(result: ClosedLoopResult, name: str = "run") -> RunData:
    """The run as its bag would hold it: the states (every tick and the final one) and the
    driver inputs answering them, stamped to the ns like the recorder's log times."""
    final = result.final_outputs
    states = {key: np.concatenate([values, np.asarray([final[key]], dtype=np.float64)])
              for key, values in result.outputs.items() if key in final}
    t = np.concatenate([result.time_s, [float(final.get("sim_time_s", np.nan))]])
    stamps = interface.times_to_ns(t) / interface.NS_PER_S
    n = result.time_s.size
    topics = {interface.STATE: TopicArrays(stamps, states),
              interface.DRIVER_INPUT: TopicArrays(stamps[:n], dict(result.driver))}
    return RunData(path=name, config=result.config, topics=topics, complete=True)


def simulate(vehicle: Vehicle | str, maneuver: str | Mapping[str, Any] | ManeuverSpec,
             law: str = "fws", *, model: str = "8dof", analyze: bool = True,
             **options: Any) -> Simulation:
    """Run ``maneuver`` with rear-steer ``law`` on ``vehicle`` (the offline twin) and analyze
    it like ``fourws analyze``.

    Parameters
    ----------
    vehicle : Vehicle or str
        A vehicle, or a name of ``config/vehicles`` or a YAML path.
    maneuver : str, mapping or ManeuverSpec
        A name of ``config/maneuvers``, a YAML path or a maneuver mapping.
    law : str
        A rear-steer law (``fourws_control`` registry: ``fws``, ``sol1``, ``lqr``, ...).
    model : str
        Vehicle model (``8dof``, ``3dof``, ``2dof``, ...).
    analyze : bool
        Compute :attr:`Simulation.metrics` (about a second: eigenvalues over speed included).
    **options
        Passed to :func:`fourws_run.closed_loop.run_closed_loop` (``dt_s``,
        ``control_period_s``, ``belief_vehicle``, ``law_options``, ``tire``, ...).

    Raises
    ------
    fourws_sim.errors.FourwsError
        An unknown name or an invalid value (the message names the field and the file).
    """
    car = load_vehicle(vehicle) if isinstance(vehicle, str) else vehicle
    spec = maneuver if isinstance(maneuver, ManeuverSpec) else load_maneuver_spec(maneuver)
    result = run_closed_loop(car, spec, law, model=model, **options)
    history = {**result.outputs,
               "steering_wheel_angle_rad": result.driver["steering_wheel_angle_rad"],
               "front_wheel_angle_cmd_rad": result.driver["front_wheel_angle_rad"],
               "rear_command_rad": result.rear_angle_rad}
    metrics: dict[str, Any] = {}
    if analyze:
        # scipy and python-control: only when metrics are asked for
        from fourws_analysis.compare import analyze_run

        metrics = analyze_run(resample(as_run_data(result))).metrics()
    return Simulation(result.time_s, history, metrics, result)


__all__ = ["Simulation", "as_run_data", "load_vehicle", "simulate"]
