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

There is no other state: ROS nodes that keep one maneuver, one law and one actuator instance
per run and call them in this order on the same values reproduce this runner bit for bit
(message float64 fields carry Python floats unchanged).

The result holds, per tick ``k`` (``N`` ticks): ``time_s``, every ``VehicleState`` output ``y_k``
(wheel fields as ``(N, 4)`` arrays), the driver command ``d_k`` and the rear angles ``c_k``
(law) and ``delta_r_k`` (after the actuator), plus the final state after the last tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from fourws_sim.drivers import DriverCommand, N_WHEELS
from fourws_sim.errors import NonFiniteError, ParameterError
from fourws_sim.maneuvers import Maneuver, ManeuverSpec, make_maneuver
from fourws_sim.params import Vehicle

#: Relative tolerance for "control period is a whole multiple of the integration step".
_MULTIPLE_RTOL = 1e-9


def simulator_inputs(command: DriverCommand, rear_angle_rad: float) -> Any:
    """The :class:`fourws_sim.simulator.Inputs` of a driver command and a rear road-wheel
    angle (rad, after the actuator); the simulator maps them to its model's input order."""
    from fourws_sim.simulator import Inputs

    return Inputs(front_wheel_angle_rad=command.front_wheel_angle_rad,
                  rear_wheel_angle_rad=rear_angle_rad,
                  steering_torque_nm=command.steering_torque_nm,
                  drive_torque_nm=command.drive_torque_nm,
                  brake_torque_nm=command.brake_torque_nm)


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
        ``duration`` or the maneuver's abort reason.
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


def law_input_from(outputs: Mapping[str, Any], command: DriverCommand, t_s: float) -> Any:
    """The :class:`fourws_control.LawInput` of tick ``t_s`` (step 4 of the module docstring)."""
    from fourws_control import LawInput

    return LawInput(delta_f_rad=float(command.front_wheel_angle_rad),
                    speed_mps=float(outputs["speed_mps"]),
                    yaw_rate_radps=float(outputs["yaw_rate_radps"]),
                    roll_rad=float(outputs["roll_rad"]),
                    roll_rate_radps=float(outputs["roll_rate_radps"]),
                    lateral_velocity_mps=float(outputs["lateral_velocity_mps"]),
                    time_s=float(t_s))


def run_closed_loop(vehicle: Vehicle, maneuver: Maneuver | ManeuverSpec | str | Mapping[str, Any],
                    law_name: str, model: str = "8dof", dt_s: float = 1e-3,
                    control_period_s: float = 0.01, belief_vehicle: Vehicle | None = None,
                    integrator: str = "rk4", law_options: Mapping[str, Any] | None = None,
                    tire: str | None = None, max_ticks: int | None = None) -> ClosedLoopResult:
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

    Returns
    -------
    ClosedLoopResult

    Raises
    ------
    ParameterError
        Non-positive periods, or a control period that is not a whole multiple of ``dt_s``.
    UnknownNameError
        Unknown law, model or integrator.
    NonFiniteError
        The simulation diverged (raised by the simulator or the law).
    """
    from fourws_control import RearSteerActuator, make_loop_law
    from fourws_sim.simulator import Simulator

    for key, value in (("dt_s", dt_s), ("control_period_s", control_period_s)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
            raise ParameterError(key, f"must be a finite number > 0, got {value!r}")
    ratio = control_period_s / dt_s
    n_sub = int(round(ratio))
    if n_sub < 1 or abs(ratio - n_sub) > _MULTIPLE_RTOL * ratio:
        raise ParameterError("control_period_s",
                             f"must be a whole multiple of dt_s ({dt_s} s), got "
                             f"{control_period_s} s")
    belief = vehicle if belief_vehicle is None else belief_vehicle
    man = maneuver if isinstance(maneuver, Maneuver) else make_maneuver(maneuver, vehicle)

    sim = Simulator(vehicle, model=model, integrator=integrator, dt_s=dt_s, tire=tire)
    sim.reset(speed_mps=man.initial_speed_mps)
    law = make_loop_law(law_name, belief, control_period_s, law_options)
    actuator = RearSteerActuator(belief)

    times: list[float] = []
    rows: list[Mapping[str, Any]] = []
    commands: list[DriverCommand] = []
    law_cmds: list[float] = []
    rear: list[float] = []
    phases: list[str] = []
    end_reason = "duration"
    limit = max_ticks if max_ticks is not None else int(
        math.ceil(man.duration_s / control_period_s)) + 1
    y = sim.outputs()
    for _ in range(limit):
        t = float(y["sim_time_s"]) if "sim_time_s" in y else float(sim.time_s)
        if man.done(t, y):
            end_reason = man.abort_reason or "duration"
            break
        d = man.command(t, y)
        c = law.rear_angle(law_input_from(y, d, t))
        delta_r = actuator.apply(c, control_period_s)
        times.append(t)
        rows.append({key: (np.array(v) if isinstance(v, np.ndarray) else v)
                     for key, v in y.items()})
        commands.append(d)
        law_cmds.append(c)
        rear.append(delta_r)
        phases.append(man.phase(t))
        sim.step(simulator_inputs(d, delta_r), n_steps=n_sub)
        y = sim.outputs()
    else:
        end_reason = "max_ticks"

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
    if not all(np.all(np.isfinite(v)) for v in outputs.values()):
        raise NonFiniteError(f"closed loop {law_name}/{man.name}: non-finite output")
    config = {
        "vehicle": vehicle.to_dict(), "belief_vehicle": belief.name, "maneuver": man.to_dict(),
        "law": law_name, "law_options": dict(law_options or {}), "model": model, "tire": tire,
        "integrator": integrator, "integration_step_s": dt_s,
        "control_period_s": control_period_s,
    }
    return ClosedLoopResult(
        time_s=np.asarray(times), outputs=outputs, driver=driver,
        rear_law_rad=np.asarray(law_cmds), rear_angle_rad=np.asarray(rear), phase=phases,
        final_outputs=dict(y), law=law_name, model=model, vehicle=vehicle.name,
        maneuver=man.name, end_reason=end_reason, config=config)


def run_scenario(scenario: Any, law_name: str | None = None) -> ClosedLoopResult:
    """Run one law of a :class:`fourws_sim.scenario.Scenario` offline (its first law by
    default): the reference a lockstep run of the node graph with the same scenario matches.

    Raises
    ------
    ParameterError
        ``law_name`` is not one of the scenario's laws.
    """
    law = scenario.laws[0] if law_name is None else law_name
    if law not in scenario.laws:
        raise ParameterError("law", f"{law!r} is not in the scenario's laws "
                             f"({', '.join(scenario.laws)})", scenario.source or scenario.name)
    vehicle = scenario.build_vehicle()
    return run_closed_loop(vehicle, scenario.maneuver, law, model=scenario.model,
                           dt_s=scenario.integration_step_s,
                           control_period_s=scenario.control_period_s,
                           belief_vehicle=scenario.build_belief(vehicle),
                           integrator=scenario.integrator,
                           law_options=scenario.law_options.get(law))


__all__ = ["ClosedLoopResult", "law_input_from", "run_closed_loop", "run_scenario",
           "simulator_inputs"]
