# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Simulator: the VehicleState contract, inputs, errors, and the linear models through it.

Sources: msg/VehicleState.msg (the output fields), statics (normal loads at rest), the 2-DOF
steady state r/delta = U/(L + K U^2) and a_y = U r, kinematics (straight line X = U t).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fourws_sim.errors import NonFiniteError, ParameterError, UnknownNameError
from fourws_sim.models.eightdof import INPUT, STATE
from fourws_sim.params import GRAVITY_MPS2, load_vehicle
from fourws_sim.simulator import Inputs, Simulator

MSG = Path(__file__).resolve().parent.parent / "msg" / "VehicleState.msg"
SPEED_MPS = 85.0 / 3.6


def msg_fields() -> dict[str, str]:
    """Field name -> type of VehicleState.msg, without the header."""
    fields = {}
    for line in MSG.read_text().splitlines():
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        kind, name = text.split()[:2]
        if name != "header":
            fields[name] = kind
    return fields


@pytest.fixture(scope="module")
def sim8() -> Simulator:
    return Simulator("table_8_1")


def test_outputs_have_exactly_the_vehicle_state_fields(sim8: Simulator) -> None:
    sim8.reset(speed_mps=SPEED_MPS)
    sim8.step(Inputs(front_wheel_angle_rad=0.01), 10)
    out = sim8.outputs()
    fields = msg_fields()
    assert set(out) == set(fields)
    for name, kind in fields.items():
        if kind.endswith("[4]"):
            assert np.asarray(out[name]).shape == (4,)
            assert np.all(np.isfinite(out[name]))
        elif kind == "string":
            assert out[name] == "8dof"
        else:
            assert math.isfinite(float(out[name]))
    assert out["step"] == 10 and out["sim_time_s"] == pytest.approx(0.01, abs=1e-15)


def test_reset_spins_the_wheels_at_the_speed(sim8: Simulator) -> None:
    """Free rolling: omega = U / R for every wheel, zero slip."""
    sim8.reset(speed_mps=20.0)
    out = sim8.outputs()
    radius = sim8.vehicle.body.wheel_radius_m  # type: ignore[union-attr]
    assert np.allclose(out["wheel_speed_radps"], 20.0 / radius, rtol=1e-15)
    assert np.all(np.abs(out["slip_ratio"]) < 1e-14)
    assert sim8.time_s == 0.0 and out["step"] == 0


def test_static_loads_at_rest(sim8: Simulator) -> None:
    """Statics: loads sum to m g and split b/L front, a/L rear."""
    sim8.reset(speed_mps=0.0)
    fz = sim8.outputs()["normal_load_n"]
    c = sim8.vehicle.chassis
    weight = c.mass_kg * GRAVITY_MPS2
    assert fz.sum() == pytest.approx(weight, rel=1e-12)
    assert fz[0] + fz[1] == pytest.approx(weight * c.cg_to_rear_axle_m / c.wheelbase_m,
                                          rel=1e-12)


def test_steady_turn_lateral_acceleration_is_u_r(sim8: Simulator) -> None:
    """Kinematics of a steady turn: a_y = U r (V' = 0)."""
    sim8.reset(speed_mps=SPEED_MPS)
    sim8.step(Inputs(front_wheel_angle_rad=0.005), 6000)
    out = sim8.outputs()
    assert out["lateral_accel_mps2"] == pytest.approx(
        out["speed_mps"] * out["yaw_rate_radps"], rel=2e-3)
    assert out["front_wheel_angle_rad"] == pytest.approx(
        0.005 + sim8.vehicle.roll.roll_steer_front * out["roll_rad"],  # type: ignore
        rel=1e-12)


def test_inputs_and_vector_give_the_same_result(sim8: Simulator) -> None:
    u = Inputs(front_wheel_angle_rad=0.01, rear_wheel_angle_rad=-0.002,
               drive_torque_nm=(10.0, 20.0, 30.0, 40.0), brake_torque_nm=(0.0, 5.0, 0.0, 1.0))
    vec = np.zeros(len(INPUT))
    vec[INPUT.DELTA_F], vec[INPUT.DELTA_R] = 0.01, -0.002
    vec[INPUT.DRIVE_FL:INPUT.DRIVE_RR + 1] = (10.0, 20.0, 30.0, 40.0)
    vec[INPUT.BRAKE_FL:INPUT.BRAKE_RR + 1] = (0.0, 5.0, 0.0, 1.0)
    assert np.array_equal(sim8.input_vector(u), vec)
    states = []
    for given in (u, vec):
        sim8.reset(speed_mps=10.0)
        sim8.step(given, 100)
        states.append(sim8.state)
    assert np.array_equal(states[0], states[1])


@pytest.mark.parametrize("u, name", [
    (Inputs(front_wheel_angle_rad=float("nan")), "front_wheel_angle_rad"),
    (Inputs(brake_torque_nm=(0.0, 0.0, float("inf"), 0.0)), r"brake_torque_nm\[RL\]"),
    (Inputs(drive_torque_nm=(0.0, float("nan"), 0.0, 0.0)), r"drive_torque_nm\[FR\]"),
])
def test_non_finite_input_names_the_input(sim8: Simulator, u: Inputs, name: str) -> None:
    sim8.reset(speed_mps=10.0)
    before = sim8.state
    with pytest.raises(NonFiniteError, match=name):
        sim8.step(u, 10)
    assert np.array_equal(sim8.state, before)


def test_negative_brake_and_bad_vector_are_rejected(sim8: Simulator) -> None:
    with pytest.raises(ParameterError, match=r"brake_torque_nm\[FR\]"):
        sim8.step(Inputs(brake_torque_nm=(0.0, -1.0, 0.0, 0.0)))
    with pytest.raises(ParameterError, match="11 components"):
        sim8.step(np.zeros(3))
    with pytest.raises(ParameterError, match="drive_torque_nm"):
        sim8.step(Inputs(drive_torque_nm=(1.0, 2.0)))
    with pytest.raises(ParameterError, match="n_steps"):
        sim8.step(Inputs(), -1)


def test_non_finite_state_raises_and_keeps_the_last_finite_state(sim8: Simulator) -> None:
    """A diverging state raises NonFiniteError naming a component; nothing non-finite stays."""
    sim8.reset(speed_mps=10.0)
    x = sim8.state
    x[STATE.R] = 1e200  # r^2 overflows in the first step
    sim8.state = x
    with pytest.raises(NonFiniteError, match="state [A-Z_]+ became non-finite"):
        sim8.step(Inputs(), 10)
    assert np.all(np.isfinite(sim8.state))
    assert sim8.state[STATE.R] == 1e200
    out = sim8.outputs()
    assert out["step"] == 0


def test_bad_construction() -> None:
    with pytest.raises(UnknownNameError, match="8dof"):
        Simulator("table_8_1", model="9dof")
    with pytest.raises(UnknownNameError, match="rk4"):
        Simulator("table_8_1", integrator="heun")
    with pytest.raises(ParameterError, match="dt_s"):
        Simulator("table_8_1", dt_s=0.0)
    with pytest.raises(ParameterError, match="tire"):
        Simulator("table_4_1_set_1", model="2dof", tire="sti")
    with pytest.raises(ParameterError, match="roll"):
        Simulator("table_5_1")  # 8-DOF needs roll and body data


def test_linear_2dof_through_the_simulator() -> None:
    """2-DOF at 85 km/h: steady yaw rate U/(L + K U^2) delta, a_y = U r, pose from r."""
    v = load_vehicle("table_4_1_set_1")
    sim = Simulator(v, model="2dof")
    sim.reset(speed_mps=SPEED_MPS)
    delta = 0.01
    sim.step(Inputs(front_wheel_angle_rad=delta), 8000)
    out = sim.outputs()
    L, K = v.chassis.wheelbase_m, v.understeer_gradient_rad_per_mps2
    r_ss = SPEED_MPS / (L + K * SPEED_MPS ** 2) * delta
    assert out["yaw_rate_radps"] == pytest.approx(r_ss, rel=1e-6)
    assert out["lateral_accel_mps2"] == pytest.approx(SPEED_MPS * r_ss, rel=1e-6)
    assert out["speed_mps"] == SPEED_MPS and out["model"] == "2dof"
    assert out["heading_rad"] == pytest.approx(r_ss * 8.0, rel=0.05)  # r settles in < 0.5 s
    assert np.all(out["normal_load_n"] == 0.0)


def test_linear_straight_line_pose() -> None:
    """No input: X = U t, Y = 0 (kinematics)."""
    sim = Simulator("table_4_1_set_1", model="3dof", speed_mps=20.0)
    sim.step(Inputs(), 2500)
    out = sim.outputs()
    assert out["x_m"] == pytest.approx(50.0, rel=1e-12)
    assert out["y_m"] == 0.0 and out["roll_rad"] == 0.0


def test_free_control_model_reports_its_front_angle_state() -> None:
    """2-DOF free control: the front road-wheel angle is a state, driven by the torque."""
    sim = Simulator("table_4_4", model="2dof-free", speed_mps=SPEED_MPS)
    sim.step(Inputs(steering_torque_nm=5.0), 2000)
    out = sim.outputs()
    assert out["front_wheel_angle_rad"] == pytest.approx(
        sim.state[sim.model.STATE.DELTA_F], rel=1e-15)
    assert out["front_wheel_angle_rad"] != 0.0
