"""The 8-DOF's free steering system (model ``8dof-free``), the torque-input maneuvers and the
free-control analysis.

Sources of the numbers: analytic solutions of the steering system at standstill (no tire
force), the NumPy reference model (the compiled kernel equals it to round-off), the
paper's 2-DOF free-control model (eq. 4.53, ``2dof-free``; Table 4.4's car loses stability at
67.6 m/s, section 4.4.3) which the 8-DOF must reduce to, the linearization of the 8-DOF itself
(the free oscillation of a small pulse), symmetry and conservation.
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import numpy as np
import pytest

from fourws_analysis import free_control, linearize
from fourws_analysis.iso17288 import pulse_metrics, release_metrics
from fourws_analysis.linear import critical_speed
from fourws_cli.main import main
from fourws_control import make_law
from fourws_run.closed_loop import run_closed_loop
from fourws_run.scenario import scenario_from_mapping
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers import check_model, load_maneuver_spec
from fourws_sim.models import eightdof, get_model
from fourws_sim.models.eightdof import INPUT, PARAM, STATE
from fourws_sim.params import Body, Roll, Tire, Vehicle, load_vehicle
from fourws_sim.simulator import Inputs, Simulator

SPEED_100_MPS = 100.0 / 3.6  # ISO 17288's standard speed


def _table_8_1(**steering: Any) -> Vehicle:
    """table_8_1 with its steering system's fields changed."""
    v = load_vehicle("table_8_1")
    return dataclasses.replace(v, steering=dataclasses.replace(v.steering, **steering))


def _settle_analytic(torque_nm: float, nu: float, j: float, t: float) -> float:
    """Angle (rad) of J x'' + nu x' = torque from rest: (T/nu)(t - (J/nu)(1 - e^(-nu t/J)))."""
    return torque_nm / nu * (t - j / nu * (1.0 - math.exp(-nu * t / j)))


# ------------------------------------------------------------------------ the model
def test_at_standstill_the_steering_system_follows_its_analytic_solution() -> None:
    """At rest the tires carry no force, so with no friction J delta'' = N T - nu delta':
    the angle after 1 s equals the closed form (RK4 1 ms; rate nu/J = 8.6 1/s), the rate tends
    to N T / nu, and the applied front angle is the system's angle (no roll)."""
    v = _table_8_1(coulomb_friction_nm=0.0)
    st = v.steering
    sim = Simulator(v, model="8dof-free")
    sim.reset(speed_mps=0.0)
    torque = 0.2  # N m at the steering wheel
    sim.step(Inputs(steering_torque_nm=torque), 1000)
    expected = _settle_analytic(st.ratio * torque, st.damping_nms_per_rad, st.inertia_kgm2, 1.0)
    assert sim.state[STATE.DELTA_S] == pytest.approx(expected, rel=1e-7)
    assert sim.state[STATE.DELTA_S_RATE] == pytest.approx(
        st.ratio * torque / st.damping_nms_per_rad
        * (1.0 - math.exp(-st.damping_nms_per_rad / st.inertia_kgm2)), rel=1e-7)
    assert sim.outputs()["front_wheel_angle_rad"] == sim.state[STATE.DELTA_S]
    assert sim.state[STATE.U] == 0.0 and sim.state[STATE.R] == 0.0  # the car stays put


def test_coulomb_friction_holds_below_breakaway_and_slides_above_it() -> None:
    """Below the breakaway torque (N T < T_c) the wheel does not move at all; above it the
    friction is a constant torque against the motion: the closed form with N T - T_c."""
    v = load_vehicle("table_8_1")
    st = v.steering
    breakaway = st.coulomb_friction_nm / st.ratio  # 1 N m at the steering wheel
    sim = Simulator(v, model="8dof-free")
    sim.reset(speed_mps=0.0)
    sim.step(Inputs(steering_torque_nm=0.9 * breakaway), 1000)
    assert sim.state[STATE.DELTA_S] == 0.0 and sim.state[STATE.DELTA_S_RATE] == 0.0
    sim.reset(speed_mps=0.0)
    torque = 3.0 * breakaway
    sim.step(Inputs(steering_torque_nm=torque), 1000)
    net = st.ratio * torque - st.coulomb_friction_nm
    expected = _settle_analytic(net, st.damping_nms_per_rad, st.inertia_kgm2, 1.0)
    # the first step starts in the stuck band: it breaks loose with the same acceleration
    assert sim.state[STATE.DELTA_S] == pytest.approx(expected, rel=1e-5)


@pytest.mark.parametrize("friction", [0.0, 16.3])
def test_compiled_kernel_matches_the_numpy_reference_with_free_steering(friction: float
                                                                      ) -> None:
    """The numba right-hand side equals the NumPy ``evaluate`` to round-off with the free
    steering system on (random moving states, steering angles and rates, torques)."""
    v = _table_8_1(coulomb_friction_nm=friction)
    p = eightdof.params_for(v, free_steering=True)
    k = eightdof.kernels_for(p.tire_name)
    rng = np.random.default_rng(13)
    dx = np.zeros(eightdof.N_STATE)
    aux = np.zeros(eightdof.N_AUX)
    worst = 0.0
    for _ in range(200):
        x = np.zeros(eightdof.N_STATE)
        x[STATE.U] = rng.uniform(0.0, 40.0)
        x[STATE.V] = rng.uniform(-2.0, 2.0)
        x[STATE.R] = rng.uniform(-0.6, 0.6)
        x[STATE.PHI] = rng.uniform(-0.06, 0.06)
        x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1] = x[STATE.U] / 0.29 * rng.uniform(0.8, 1.2, 4)
        x[STATE.ALPHA_FL:STATE.ALPHA_RR + 1] = rng.uniform(-0.1, 0.1, 4)
        x[STATE.DELTA_S] = rng.uniform(-0.2, 0.2)
        x[STATE.DELTA_S_RATE] = rng.choice([0.0, 1e-4, rng.uniform(-3.0, 3.0)])
        u = np.zeros(eightdof.N_INPUT)
        u[INPUT.DELTA_F] = rng.uniform(-0.1, 0.1)  # not used with free steering
        u[INPUT.STEER_TORQUE] = rng.uniform(-20.0, 20.0)
        ref, ref_aux = eightdof.evaluate(0.0, x, u, p)
        k.rhs(x, u, p.arr, p.coeffs_front, p.coeffs_rear, dx, aux)
        worst = max(worst, float(np.max(np.abs(dx - ref) / (1.0 + np.abs(ref)))))
        assert ref_aux.delta_f_rad == pytest.approx(
            x[STATE.DELTA_S] + p.arr[PARAM.EPS_F] * x[STATE.PHI], rel=1e-15)
    assert worst < 1e-12


def test_fixed_control_leaves_the_steering_states_alone() -> None:
    """With fixed control (``8dof``) a steering torque does nothing and the steering states'
    derivatives are exactly 0: the model of ch. 8 is unchanged (its regression pins are in
    test_eightdof_regression)."""
    v = load_vehicle("table_8_1")
    p = eightdof.params_for(v)
    x = eightdof.initial_state(p, 20.0)
    x[STATE.DELTA_S], x[STATE.DELTA_S_RATE] = 0.1, 0.5
    u = np.zeros(eightdof.N_INPUT)
    u[INPUT.DELTA_F], u[INPUT.STEER_TORQUE] = 0.01, 50.0
    dx, aux = eightdof.evaluate(0.0, x, u, p)
    assert dx[STATE.DELTA_S] == 0.0 and dx[STATE.DELTA_S_RATE] == 0.0
    assert aux.delta_f_rad == 0.01


def test_free_model_needs_a_steering_inertia() -> None:
    v = _table_8_1(inertia_kgm2=0.0)
    with pytest.raises(ParameterError, match="steering.inertia_kgm2"):
        Simulator(v, model="8dof-free")


def test_torque_steps_left_and_right_are_mirror_images() -> None:
    """Symmetry: a torque step to the right gives the mirror image of the one to the left."""
    left = run_closed_loop(load_vehicle("table_8_1"), "steering_torque_step", "fws",
                           model="8dof-free")
    spec = load_maneuver_spec("steering_torque_step")
    spec = dataclasses.replace(spec, params=dataclasses.replace(
        spec.params, torque_nm=-spec.params.torque_nm))
    right = run_closed_loop(load_vehicle("table_8_1"), spec, "fws", model="8dof-free")
    for name in ("yaw_rate_radps", "lateral_accel_mps2", "front_wheel_angle_rad"):
        np.testing.assert_allclose(right[name], -left[name], atol=1e-12)
    assert np.max(left["yaw_rate_radps"]) > 0.02  # it steers left (0.2 g at 80 km/h)


# ------------------------------------------------------------------------ reduction to 2-DOF
def _reduced(v: Vehicle, inertia: float) -> Vehicle:
    """``v`` (a single-track data set) as an 8-DOF car whose roll and load transfer are off:
    roll arm 0 (roll decoupled), roll steer 0, every height 0 (no load transfer), a linear
    tire without aligning moment or lag (its trail is the steering's trail_m, as in the
    2-DOF), and a steering inertia ``inertia`` (kg m^2) without friction."""
    roll = Roll(sprung_mass_kg=v.chassis.mass_kg, roll_inertia_kgm2=400.0,
                roll_yaw_product_kgm2=0.0, roll_arm_m=0.0,
                roll_stiffness_front_nm_per_rad=4.0e4, roll_stiffness_rear_nm_per_rad=3.0e4,
                roll_damping_front_nms_per_rad=2.0e3, roll_damping_rear_nms_per_rad=2.0e3,
                roll_steer_front=0.0, roll_steer_rear=0.0)
    body = Body(track_front_m=1.5, track_rear_m=1.5, cg_height_m=0.0,
                roll_centre_height_front_m=0.0, roll_centre_height_rear_m=0.0,
                unsprung_cg_height_m=0.0, wheel_radius_m=0.3, wheel_spin_inertia_kgm2=1.0)
    return dataclasses.replace(v, roll=roll, body=body, tire=Tire(model="linear"),
                               steering=dataclasses.replace(v.steering, inertia_kgm2=inertia,
                                                            coulomb_friction_nm=0.0))


@pytest.mark.parametrize("speed", [20.0, 40.0, 60.0])
def test_eightdof_reduces_to_the_two_dof_free_model_eigenvalues(speed: float) -> None:
    """With roll and load transfer off and a small steering inertia (0.05 kg m^2, so the
    system is the highly damped one of eq. 4.53: nu^2 / (4 J eta C_f) = 30) the linearized
    8dof-free has the 2dof-free model's three eigenvalues within 5 % (Table 4.4's car); its
    other modes are the roll, wheel, load-transfer and steering-inertia ones."""
    v = _reduced(load_vehicle("table_4_4"), inertia=0.05)
    mod = get_model("8dof-free")
    p = mod.params_for(v)
    a, _ = linearize.jacobians(mod.derivatives, mod.initial_state(p, speed),
                               np.zeros(len(mod.INPUT)), p)
    full = np.linalg.eigvals(a)
    a2, _ = get_model("2dof-free").matrices(v, speed)
    for lam in np.linalg.eigvals(a2):
        nearest = full[np.argmin(np.abs(full - lam))]
        assert abs(nearest - lam) <= 0.05 * abs(lam), (lam, nearest)


def test_reduced_eightdof_free_critical_speed_is_the_papers_within_5_percent() -> None:
    """Table 4.4's car with steering dynamics loses stability at 67.6 m/s (section 4.4.3,
    the 2dof-free model); the reduced 8-DOF with its steering system within 5 %."""
    v = _reduced(load_vehicle("table_4_4"), inertia=0.05)
    two = critical_speed("2dof-free", v, "fws").critical_speed_mps
    assert two == pytest.approx(67.6, abs=0.1)
    eight = free_control.eightdof_free_critical_speed(v, "fws", speed_range_mps=(40.0, 90.0),
                                                      samples=12).critical_speed_mps
    assert eight == pytest.approx(two, rel=0.05)


def test_free_steering_removes_table_8_1s_oversteer_divergence() -> None:
    """table_8_1 (roll oversteer) diverges at 32.8 m/s with fixed control (its file says
    31-33 m/s); with the steering free the front wheels follow their slip and the car stays
    stable at that speed: its linearized 8dof-free has no mode right of the axis there."""
    v = load_vehicle("table_8_1")
    fixed = linearize.eightdof_loop(v, 34.0, "fws").lateral_eigenvalues()
    assert np.max(fixed.real) > 0.0
    assert free_control.eightdof_free_max_real_part(v, 34.0, "fws") < 0.0


def test_linear_cli_gives_the_eightdof_free_critical_speed_beside_the_two_dofs(capsys) -> None:
    """``fourws linear --model 2dof-free --critical-speed``: the 2-DOF's critical speed and the
    linearized 8-DOF's with its steering system (table_8_1: above the fixed-control 32.8 m/s,
    see above); a car without 8-DOF data says why."""
    rc = main(["linear", "--vehicle", "table_8_1", "--model", "2dof-free", "--law", "fws",
               "--speed-kmh", "80", "--critical-speed", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0
    free = out["critical_speed_8dof_free"]
    assert free["critical_speed_mps"] > 40.0 and free["unavailable"] is None
    assert out["critical_speed_mps"] == pytest.approx(
        critical_speed("2dof-free", load_vehicle("table_8_1"), "fws").critical_speed_mps)
    rc = main(["linear", "--vehicle", "table_4_4", "--model", "2dof-free", "--law", "fws",
               "--speed-kmh", "80", "--critical-speed", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert out["critical_speed_mps"] == pytest.approx(67.6, abs=0.1)
    assert "roll" in out["critical_speed_8dof_free"]["unavailable"]


# ------------------------------------------------------------------------ maneuvers and laws
def test_the_law_sees_the_free_front_angle() -> None:
    """Free control: the driver input reports the steering system's angle (applied angle less
    the roll steer, which is the state DELTA_S exactly), and the law's command is its gains
    applied to that angle and the state, as the paper's free-control laws take delta_f."""
    v = load_vehicle("table_8_1")
    res = run_closed_loop(v, "steering_torque_step", "sol1", model="8dof-free")
    eps_f = v.roll.roll_steer_front
    free = res["front_wheel_angle_rad"] - eps_f * res["roll_rad"]
    np.testing.assert_array_equal(res.driver["front_wheel_angle_rad"], free)
    assert np.max(np.abs(free)) > 1e-3
    law = make_law("sol1", v)
    for k in range(0, res.time_s.size, 37):
        g = law.gains(res["speed_mps"][k])
        expected = g[0] * free[k] + g[1] * res["yaw_rate_radps"][k]
        assert res.rear_law_rad[k] == pytest.approx(expected, rel=1e-12, abs=1e-15)
    # the reported angle is the state: a Simulator run of the same torque shows it
    sim = Simulator(v, model="8dof-free")
    sim.reset(speed_mps=20.0)
    sim.step(Inputs(steering_torque_nm=3.0), 300)
    out = sim.outputs()
    assert out["front_wheel_angle_rad"] - eps_f * out["roll_rad"] == pytest.approx(
        sim.state[STATE.DELTA_S], rel=1e-14)


def test_maneuvers_and_models_must_match_in_steering_control() -> None:
    """A torque input needs a steering system; an angle input on a free model would be
    ignored: both are refused, naming the model field."""
    with pytest.raises(ParameterError, match="steering system"):
        check_model(load_maneuver_spec("steering_release"), "8dof")
    with pytest.raises(ParameterError, match="free control"):
        check_model(load_maneuver_spec("step_steer_85kmh"), "8dof-free")
    with pytest.raises(ParameterError) as err:
        scenario_from_mapping({"vehicle": "table_8_1", "maneuver": "steering_pulse"})
    assert err.value.field == "model"
    check_model(load_maneuver_spec("steering_pulse"), "2dof-free")


def test_small_pulse_oscillates_as_the_linearized_free_car() -> None:
    """ISO 17288-2 pulse (0.5 N m, no friction, 100 km/h, fws): the yaw rate's free oscillation
    has the damping ratio and frequency of the least damped mode of the linearized 8dof-free
    (1.33 Hz, 0.154) within 2 %."""
    v = free_control.without_friction(load_vehicle("table_8_1"))
    spec = {"name": "p", "type": "steering_pulse", "initial_speed_mps": SPEED_100_MPS,
            "duration_s": 6.0, "torque_nm": 0.5, "width_s": 0.2, "start_s": 0.5}
    res = run_closed_loop(v, spec, "fws", model="8dof-free")
    m = pulse_metrics(res.time_s, res["yaw_rate_radps"], res["steering_wheel_angle_rad"],
                      0.5, 0.7)
    ev = linearize.eightdof_loop(v, SPEED_100_MPS, "fws", free_steering=True
                                 ).lateral_eigenvalues()
    osc = ev[ev.imag > 0.1]
    slow = osc[np.argmax(osc.real)]
    assert m.yaw.frequency_hz == pytest.approx(slow.imag / (2.0 * math.pi), rel=0.02)
    assert m.yaw.damping_ratio == pytest.approx(-slow.real / abs(slow), rel=0.02)


def test_steering_release_returns_and_friction_slows_the_return() -> None:
    """ISO 17288-1 on table_8_1 at 100 km/h: the hold reaches the steady 4 m/s^2 turn within
    1.5 % (SteeringReleaseParams' claim) and the torque is 0 after the release. Without
    steering friction the stable free car (its linearized 8dof-free has no unstable mode)
    returns to straight running: 5 s after the release the yaw rate is under 1 % of the
    initial one; the yaw oscillation of the return has the least damped mode's damping ratio
    (0.154) within 10 % (a large return, not a small signal). The 1 N m of friction takes the
    viscous damping away while the wheel sticks: the oscillation dies more slowly (smaller
    damping ratio, no settling within the record)."""
    rel = load_maneuver_spec("steering_release").params.release_s
    out = {}
    for friction in (0.0, 16.3):
        v = _table_8_1(coulomb_friction_nm=friction)
        res = run_closed_loop(v, "steering_release", "fws", model="8dof-free")
        out[friction] = release_metrics(res.time_s, res["yaw_rate_radps"],
                                        res["steering_wheel_angle_rad"], rel,
                                        res["lateral_accel_mps2"])
        assert out[friction].lateral_accel_initial_mps2 == pytest.approx(4.0, rel=0.015)
        assert res.driver["steering_torque_nm"][res.time_s >= rel].max() == 0.0
    free, held = out[0.0], out[16.3]
    assert abs(free.final_yaw_rate_radps) < 0.01 * free.yaw_rate_initial_radps
    assert free.settling_time_s is not None
    v = free_control.without_friction(load_vehicle("table_8_1"))
    ev = linearize.eightdof_loop(v, SPEED_100_MPS, "fws", free_steering=True
                                 ).lateral_eigenvalues()
    slow = ev[ev.imag > 0.1][np.argmax(ev[ev.imag > 0.1].real)]
    assert free.yaw.damping_ratio == pytest.approx(-slow.real / abs(slow), rel=0.10)
    assert held.yaw.damping_ratio < free.yaw.damping_ratio
    assert held.settling_time_s is None
    assert free.yaw_rate_overshoot > 0.0 and free.steering_wheel_overshoot > 0.0
