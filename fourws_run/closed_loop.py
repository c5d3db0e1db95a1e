# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Offline closed-loop runner: the exact twin of the lockstep ROS node graph.

:func:`run_closed_loop` runs one maneuver with one rear-steer law on one vehicle model without
ROS, and is the reference the end-to-end test compares the recorded graph with (yaw rate to
1e-9). The node graph in lockstep mode must therefore perform *the same float operations in the
same order*. The sequence, with ``Tc`` the control period, ``dt`` the integration step,
``n = round(Tc / dt)``:

0. Setup. ``sim = Simulator(vehicle, model, integrator, dt)``;
   ``sim.reset(speed_mps=maneuver.initial_speed_mps)``;
   ``law = make_loop_law(law_name, belief_vehicle, Tc, law_options)`` (the law is built for
   the loop's period ``Tc``);
   ``actuator = RearSteerActuator(belief_vehicle)`` (the controller owns the actuator model, so
   its limits come from the vehicle file the controller is given; the belief vehicle is the
   simulated one unless a scenario says otherwise); ``maneuver = make_maneuver(spec, vehicle)``
   (a fresh instance per run: its drivers start with empty integrators).
1. Tick ``k = 0, 1, 2, ...``: the simulator publishes its outputs ``y_k = sim.outputs()``
   (the fields of ``VehicleState.msg``). The tick time is ``t_k = y_k["sim_time_s"]`` — the
   exact float the simulator holds, never the ns-rounded header stamp.
2. If ``maneuver.done(t_k, y_k)``: the run ends (``y_k`` is kept as the final state).
3. The maneuver computes ``d_k = maneuver.command(t_k, y_k)`` (a :class:`DriverCommand`).
4. The controller computes the law's command from the state and the driver's front angle,
   ``c_k = law.rear_angle(LawInput(delta_f_rad=d_k.front_wheel_angle_rad,
   speed_mps=y_k["speed_mps"], yaw_rate_radps=y_k["yaw_rate_radps"],
   roll_rad=y_k["roll_rad"], roll_rate_radps=y_k["roll_rate_radps"],
   lateral_velocity_mps=y_k["lateral_velocity_mps"], time_s=t_k))``
   (every value a Python float taken from the dicts/messages), then applies the actuator,
   ``delta_r_k = actuator.apply(c_k, Tc)``.
5. The simulator integrates ``sim.step(u_k, n_steps=n)`` with
   ``u_k = simulator_inputs(d_k, delta_r_k)`` (a :class:`fourws_sim.simulator.Inputs`: front
   angle, rear angle, steering torque, drive and brake torques of ``d_k``) held over the ``n``
   steps, then goes to 1.

The sequence is run by the classes of :mod:`fourws_run.ticks` that the simulator node uses too
(:class:`~fourws_run.ticks.TickEngine` integrates, :class:`~fourws_run.ticks.LockstepAnswers`
accepts the answers of each tick with the same checks, so a driver input the simulator node
would refuse is refused here as well). There is no other state: ROS nodes that keep one
maneuver, one law and one actuator instance per run and call them in this order on the same
values reproduce this runner bit for bit (message float64 fields carry Python floats
unchanged).

The result holds, per tick ``k`` (``N`` ticks): ``time_s``, every ``VehicleState`` output ``y_k``
(wheel fields as ``(N, 4)`` arrays), the driver command ``d_k`` and the rear angles ``c_k``
(law) and ``delta_r_k`` (after the actuator), plus the final state after the last tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from fourws_control import RearSteerActuator, make_loop_law
from fourws_run.config import RunConfig
from fourws_run.ticks import (InputLimits, LockstepAnswers, TickEngine, law_input,
                              whole_multiple)
from fourws_sim.drivers import DriverCommand
from fourws_sim.errors import FourwsError, ParameterError
from fourws_sim.maneuvers import Maneuver, ManeuverSpec, check_model, make_maneuver
from fourws_sim.params import N_WHEELS, Vehicle
from fourws_sim.simulator import Simulator


@dataclass
class ClosedLoopResult:
    """Arrays of one closed-loop run, one row per control tick (see the module docstring).

    Attributes
    ----------
    time_s : numpy.ndarray
        Tick times t_k, s, shape (N,).
    outputs : dict of str to numpy.ndarray
        Every numeric ``VehicleState`` field at each tick (``(N,)``, or ``(N, 4)`` per wheel).
    driver : dict of str to numpy.ndarray
        The driver command fields (``DriverInput.msg`` names) at each tick.
    rear_law_rad : numpy.ndarray
        The law's rear-angle command c_k, rad.
    rear_angle_rad : numpy.ndarray
        The rear angle after the actuator delta_r_k (applied over the next period), rad.
    phase : list of str
        Maneuver phase at each tick.
    final_outputs : dict
        ``sim.outputs()`` after the last integrated period.
    law, model, vehicle, maneuver : str
        What ran.
    end_reason : str
        ``duration``, the maneuver's end or abort reason, ``max_ticks``, or ``the simulation
        diverged at t = ...`` (:attr:`diverged`).
    end_kind : str
        How the maneuver ended (:attr:`fourws_sim.maneuvers.Maneuver.end_kind`:
        ``completed``, ``end_condition``, ``aborted``, ``spun``, ``diverged``), ``diverged``
        when the simulation diverged, ``max_ticks`` when the guard stopped it.
    config : dict
        The run configuration (vehicle, maneuver mapping, law, rates).
    """

    time_s: np.ndarray
    outputs: dict[str, np.ndarray]
    driver: dict[str, np.ndarray]
    rear_law_rad: np.ndarray
    rear_angle_rad: np.ndarray
    phase: list[str]
    final_outputs: dict[str, Any]
    law: str
    model: str
    vehicle: str
    maneuver: str
    end_reason: str = "duration"
    config: dict[str, Any] = field(default_factory=dict)
    end_kind: str = "completed"

    @property
    def diverged(self) -> bool:
        """The simulation diverged (``end_reason`` says when and where)."""
        return self.end_reason.startswith("the simulation diverged")

    def __getitem__(self, name: str) -> np.ndarray:
        """An output or driver array by field name (``res["yaw_rate_radps"]``)."""
        if name in self.outputs:
            return self.outputs[name]
        if name in self.driver:
            return self.driver[name]
        raise KeyError(name)


def _numeric_fields(outputs: Mapping[str, Any]) -> list[str]:
    keys = []
    for key, value in outputs.items():
        if isinstance(value, bool) or isinstance(value, str):
            continue
        if isinstance(value, (int, float, np.floating, np.integer)):
            keys.append(key)
        elif isinstance(value, (list, tuple, np.ndarray)) and len(value) == N_WHEELS:
            keys.append(key)
    return keys


def run_closed_loop(vehicle: Vehicle, maneuver: Maneuver | ManeuverSpec | str | Mapping[str, Any],
                    law_name: str, model: str = "8dof", dt_s: float = 1e-3,
                    control_period_s: float = 0.01, belief_vehicle: Vehicle | None = None,
                    integrator: str = "rk4", law_options: Mapping[str, Any] | None = None,
                    tire: str | None = None, max_ticks: int | None = None,
                    driver_inputs: Sequence[DriverCommand] | None = None) -> ClosedLoopResult:
    """Run ``maneuver`` with rear-steer law ``law_name`` on ``vehicle`` (no ROS).

    Parameters
    ----------
    vehicle : Vehicle
        Simulated vehicle.
    maneuver : Maneuver, ManeuverSpec, str or mapping
        The maneuver; anything but a fresh :class:`Maneuver` is built for ``vehicle``.
    law_name : str
        A ``fourws_control`` law name (``fws`` for no rear steer).
    model : str
        Vehicle model name (``8dof``, ``2dof``, ``3dof``, ...).
    dt_s : float
        Integration step, s.
    control_period_s : float
        Control period Tc, s (a whole multiple of ``dt_s``).
    belief_vehicle : Vehicle, optional
        The controller's belief (gains and actuator limits); ``vehicle`` when omitted.
    integrator : str
        Integrator name (``rk4``).
    law_options : mapping, optional
        Options of the law (``make_loop_law``; not ``control_period_s``, which is the loop's).
    tire : str, optional
        Tire model overriding the vehicle's (8-DOF only).
    max_ticks : int, optional
        Stop after this many ticks (a guard for maneuvers that end on a condition).
    driver_inputs : sequence of DriverCommand, optional
        The driver's answers, one per tick, in place of the maneuver's (a run driven from
        outside, replayed from its bag's ``/fourws/driver_input``); the run ends after the
        last one (or when the maneuver is done). The maneuver still gives the initial speed,
        the duration and the end.

    Returns
    -------
    ClosedLoopResult

    Raises
    ------
    ParameterError
        Non-positive periods, a control period that is not a whole multiple of ``dt_s``, or a
        maneuver that cannot steer the model (a torque input on a fixed-control model or an
        angle input on a free one, :func:`fourws_sim.maneuvers.check_model`).
    UnknownNameError
        Unknown law, model or integrator.
    ParameterError
        The maneuver's driver input was refused by the simulator's input checks
        (:class:`fourws_run.ticks.InputLimits`), as the simulator node refuses it.

    A diverging simulation is not an error but the run's outcome: ``end_reason`` says where it
    diverged and the result holds every tick before.
    """
    whole_multiple(control_period_s, dt_s, "control_period_s")
    belief = vehicle if belief_vehicle is None else belief_vehicle
    man = maneuver if isinstance(maneuver, Maneuver) else make_maneuver(maneuver, vehicle)
    check_model(man.spec, model)

    sim = Simulator(vehicle, model=model, integrator=integrator, dt_s=dt_s, tire=tire)
    sim.reset(speed_mps=man.initial_speed_mps)
    engine = TickEngine(sim, control_period_s)
    answers = LockstepAnswers(InputLimits.for_vehicle(vehicle))
    law = make_loop_law(law_name, belief, control_period_s, law_options)
    actuator = RearSteerActuator(belief)

    times: list[float] = []
    rows: list[Mapping[str, Any]] = []
    commands: list[DriverCommand] = []
    law_cmds: list[float] = []
    rear: list[float] = []
    phases: list[str] = []
    end_reason = "duration"
    end_kind = "completed"
    limit = max_ticks if max_ticks is not None else int(
        math.ceil(man.duration_s / control_period_s)) + 1
    tick = engine.tick
    if driver_inputs is not None:
        limit = min(limit, len(driver_inputs) + 1)
    for k in range(limit):
        t, y = tick.t, tick.outputs
        if man.done(t, y) or (driver_inputs is not None and k == len(driver_inputs)):
            end_reason = man.abort_reason or "duration"
            end_kind = man.end_kind
            break
        answers.expect(tick)
        # the maneuver node's answer (or the outside driver's) ...
        d = man.command(t, y) if driver_inputs is None else driver_inputs[k]
        if not answers.offer_driver(tick.stamp_ns, d):
            raise ParameterError("maneuver", f"driver input refused at t = {t:.3f} s: "
                                 f"{answers.rejections.last}", man.spec.source or man.name)
        # ... and the controller node's (a law error leaves the tick without a command: zero
        # rear steer, as the simulator does when the controller does not answer)
        try:
            c = law.rear_angle(law_input(y, d.front_wheel_angle_rad))
            delta_r = actuator.apply(c, control_period_s)
            answers.offer_command(tick.step, tick.stamp_ns, delta_r)
        except FourwsError:
            c = math.nan
        d, applied, _timed_out = answers.close()
        times.append(t)
        rows.append({key: (np.array(v) if isinstance(v, np.ndarray) else v)
                     for key, v in y.items()})
        commands.append(d)
        law_cmds.append(c)
        rear.append(applied)
        phases.append(man.phase(t))
        if not engine.advance(d, applied):
            end_reason, end_kind = engine.diverged, "diverged"
            break
        tick = engine.tick
    else:
        end_reason = end_kind = "max_ticks"
    y = tick.outputs

    if not rows:
        raise ParameterError("duration_s", "the maneuver ended before the first tick",
                             man.spec.source or man.name)
    outputs = {key: np.asarray([row[key] for row in rows], dtype=float)
               for key in _numeric_fields(rows[0])}
    driver = {
        "steering_wheel_angle_rad": np.array([d.steering_wheel_angle_rad for d in commands]),
        "front_wheel_angle_rad": np.array([d.front_wheel_angle_rad for d in commands]),
        "steering_torque_nm": np.array([d.steering_torque_nm for d in commands]),
        "drive_torque_nm": np.array([d.drive_torque_nm for d in commands]),
        "brake_torque_nm": np.array([d.brake_torque_nm for d in commands]),
    }
    config = RunConfig(vehicle=vehicle, belief=belief, maneuver=man.spec, law=law_name,
                       law_options=dict(law_options or {}), model=model, tire=tire,
                       integrator=integrator, integration_step_s=dt_s,
                       control_period_s=control_period_s, state_period_s=control_period_s,
                       recorded_topics=()).to_dict()
    return ClosedLoopResult(
        time_s=np.asarray(times), outputs=outputs, driver=driver,
        rear_law_rad=np.asarray(law_cmds), rear_angle_rad=np.asarray(rear), phase=phases,
        final_outputs=dict(y), law=law_name, model=model, vehicle=vehicle.name,
        maneuver=man.name, end_reason=end_reason, config=config, end_kind=end_kind)


def run_twin(config: RunConfig, max_ticks: int | None = None) -> ClosedLoopResult:
    """The offline twin of the graph run ``config`` describes (:func:`run_closed_loop` with
    its vehicle, belief, maneuver, law, model, integrator and periods): what a lockstep graph
    run of the same :class:`~fourws_run.config.RunConfig` records, bit for bit."""
    return run_closed_loop(config.vehicle, config.maneuver, config.law, model=config.model,
                           dt_s=config.integration_step_s,
                           control_period_s=config.control_period_s,
                           belief_vehicle=config.belief, integrator=config.integrator,
                           law_options=config.law_options, max_ticks=max_ticks)


def run_scenario(scenario: Any, law_name: str | None = None) -> ClosedLoopResult:
    """Run one law of a :class:`fourws_run.scenario.Scenario` offline (its first law by
    default): the reference a lockstep run of the node graph with the same scenario matches
    (both go through :meth:`fourws_run.scenario.Scenario.run_config`, which also resolves a
    step steer to a target lateral acceleration for the law).

    Raises
    ------
    ParameterError
        ``law_name`` is not one of the scenario's laws, or the step target is not reached.
    """
    law = scenario.laws[0] if law_name is None else law_name
    if law not in scenario.laws:
        raise ParameterError("law", f"{law!r} is not in the scenario's laws "
                             f"({', '.join(scenario.laws)})", scenario.source or scenario.name)
    return run_twin(scenario.run_config(law))


__all__ = ["ClosedLoopResult", "run_closed_loop", "run_scenario", "run_twin"]
