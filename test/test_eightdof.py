# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Nonlinear 8-DOF model (ch. 8) and its default vehicle table_8_1.

Sources of the numbers asserted here:

* agreement between model levels: at small lateral acceleration the 8-DOF reduces to the linear
  2-DOF (no roll steer) and 3-DOF (with roll steer) built from the cornering stiffness the
  8-DOF's STI tires have at their static loads; with the tires' aligning moments on, to the
  steady-state gain U/(L + K U^2) whose K includes their pneumatic trail;
* symmetry (left/right steer mirror), conservation (no input: straight line, constant speed;
  at rest: stays at rest), Coulomb friction (locked-wheel deceleration = mu_locked g);
* the two implementations (NumPy reference and numba kernels) agree to round-off;
* the imperial values of Tables 8.1/C.2 and the mass 89 slug = 1298.9 kg of Table 5.1.

Measured on table_8_1 (85 km/h, 1 mrad front road-wheel angle): 8-DOF yaw-rate gain
20.1 1/s with aligning moments, 22.5 1/s without; 3-DOF 22.6 1/s (difference 0.2 %);
with roll steer off the 8-DOF and 2-DOF agree to 0.01 %. The STI tire's cornering stiffness
at static load is 1.70 (front) and 1.62 (rear) times Table 5.1's Cf, Cr.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from fourws_sim.errors import ParameterError, UnknownNameError
from fourws_sim.models import eightdof, get_model, linear2dof, roll3dof
from fourws_sim.models.eightdof import INPUT, STATE
from fourws_sim.params import GRAVITY_MPS2, Vehicle, load_vehicle, vehicle_from_mapping
from fourws_sim.simulator import Inputs, Simulator
from fourws_sim.tires import cornering_stiffness

SPEED_85_MPS = 85.0 / 3.6  # the paper's chapter-8 speed
SLUG_KG = 14.5939029
FT_M = 0.3048
SLUGFT2_KGM2 = 1.35581795  # also ft lb -> N m


@pytest.fixture(scope="module")
def vehicle() -> Vehicle:
    return load_vehicle("table_8_1")


def variant(v: Vehicle, **changes: Any) -> Vehicle:
    """Copy of ``v`` with ``subsystem__field=value`` changes (``sti__g1`` for tire.sti); the
    changed fields are exempt from the plausibility bounds (a variant may be deliberately
    unreal, e.g. a roll arm of 0.1 mm to remove roll)."""
    d = v.to_dict()
    lifted = set(d.get("unchecked_fields", []))
    for path, value in changes.items():
        sub, key = path.split("__")
        if sub == "sti":
            d["tire"]["sti"][key] = value
        else:
            d[sub][key] = value
        lifted.add(f"tire.sti.{key}" if sub == "sti" else f"{sub}.{key}")
    d["unchecked_fields"] = sorted(lifted)
    return vehicle_from_mapping(d, f"{v.name} variant")


def static_loads(v: Vehicle) -> tuple[float, float]:
    """Static normal load of one front and one rear tire, N."""
    c = v.chassis
    w = c.mass_kg * GRAVITY_MPS2 / (2.0 * c.wheelbase_m)
    return w * c.cg_to_rear_axle_m, w * c.cg_to_front_axle_m


def linear_reference(v: Vehicle) -> Vehicle:
    """``v`` with per-axle cornering stiffness = 2 x the STI tire's at static load."""
    p = eightdof.params_for(v)
    fzf, fzr = static_loads(v)
    d = v.to_dict()
    d["axle_tires"] = {
        "cornering_stiffness_front_n_per_rad":
            2.0 * cornering_stiffness(p.tire_name, p.coeffs_front, fzf),
        "cornering_stiffness_rear_n_per_rad":
            2.0 * cornering_stiffness(p.tire_name, p.coeffs_rear, fzr),
    }
    return vehicle_from_mapping(d, "linear reference")


def steady_yaw_gain(v: Vehicle, delta_rad: float = 1.0e-3,
                    seconds: float = 8.0) -> tuple[float, float, dict[str, Any]]:
    """8-DOF yaw-rate gain r/delta_f (1/s) after a step steer at 85 km/h, and the speed then."""
    sim = Simulator(v)
    sim.reset(speed_mps=SPEED_85_MPS)
    sim.step(Inputs(front_wheel_angle_rad=delta_rad), int(round(seconds / sim.dt_s)))
    y = sim.outputs()
    return y["yaw_rate_radps"] / delta_rad, y["speed_mps"], y


def linear_gain(model: Any, v: Vehicle, speed: float) -> float:
    """Steady-state yaw-rate gain of a linear model, -(A^-1 B) for the front input."""
    A, B = model.matrices(v, speed)
    x = -np.linalg.solve(A, B[:, model.INPUT.DELTA_F])
    return float(x[model.STATE.R])


# ------------------------------------------------------------------------ vehicle data
def test_table_8_1_values_are_the_papers_converted(vehicle: Vehicle) -> None:
    """Every converted field of table_8_1 against Table 8.1/C.2's imperial value."""
    rl, bd, c = vehicle.roll, vehicle.body, vehicle.chassis
    assert rl is not None and bd is not None and vehicle.steering is not None
    expected = {
        c.mass_kg: 89.0 * SLUG_KG,
        rl.sprung_mass_kg: 80.0 * SLUG_KG,
        rl.roll_inertia_kgm2: 368.0 * SLUGFT2_KGM2,
        bd.wheel_spin_inertia_kgm2: 1.5 * SLUGFT2_KGM2,
        rl.roll_stiffness_front_nm_per_rad: 27511.0 * SLUGFT2_KGM2,
        rl.roll_stiffness_rear_nm_per_rad: 22495.0 * SLUGFT2_KGM2,
        rl.roll_damping_nms_per_rad: 2590.0 * SLUGFT2_KGM2,
        rl.roll_arm_m: 1.5 * FT_M,
        bd.roll_centre_height_front_m: 1.0 * FT_M,
        vehicle.steering.ratio: 16.3,
    }
    for got, want in expected.items():
        assert got == pytest.approx(want, rel=2e-5)
    # Table 5.1 gives the same car as 1298.9 kg
    assert c.mass_kg == pytest.approx(1298.9, rel=1e-4)
    # roll steer: the paper's (-0.2, +0.2) with the roll sign flipped (see the YAML header)
    assert (rl.roll_steer_front, rl.roll_steer_rear) == (0.2, -0.2)
    # the total CG height stated in the file is the mass-weighted one of its parts
    mu = c.mass_kg - rl.sprung_mass_kg
    h_cg = (rl.sprung_mass_kg * (bd.roll_centre_height_front_m + rl.roll_arm_m)
            + mu * bd.unsprung_cg_height_m) / c.mass_kg
    assert bd.cg_height_m == pytest.approx(h_cg, abs=5e-4)


def test_table_5_1_stiffness_is_understeer_as_the_paper_says(vehicle: Vehicle) -> None:
    """Section 5.5.1: the Table 5.1 car is understeer (K_us > 0 with its Cf, Cr)."""
    assert vehicle.understeer_gradient_rad_per_mps2 == pytest.approx(2.009e-3, rel=1e-3)


def test_steering_ratio_maps_steering_wheel_to_road_wheel(vehicle: Vehicle) -> None:
    """Eq. 8.32: delta_f = delta_sw / K_sr with K_sr = 16.3 (Table 8.1)."""
    sw = math.radians(90.0)
    assert eightdof.road_wheel_angle(sw, vehicle) == pytest.approx(sw / 16.3, rel=1e-15)
    assert eightdof.steering_wheel_angle(eightdof.road_wheel_angle(sw, vehicle),
                                         vehicle) == pytest.approx(sw, rel=1e-15)


def test_registry_and_bad_input(vehicle: Vehicle) -> None:
    """``8dof`` is registered; missing subsystems and unknown tires name the problem."""
    assert get_model("8dof") is eightdof
    with pytest.raises(UnknownNameError, match="sti"):
        eightdof.params_for(vehicle, tire="no_such_tire")
    bare = load_vehicle("table_5_1")
    with pytest.raises(ParameterError, match="roll"):
        eightdof.params_for(bare)
    with pytest.raises(ParameterError, match="v_min_mps"):
        eightdof.params_for(vehicle, v_min_mps=0.0)


# ------------------------------------------------------------------------ implementations
@pytest.mark.parametrize("sigma", [(0.414, 0.414), (0.0, 0.0), (0.23, 0.13), (0.0, 0.3)])
def test_compiled_kernel_matches_numpy_reference(vehicle: Vehicle,
                                                 sigma: tuple[float, float]) -> None:
    """The numba right-hand side equals the NumPy ``derivatives`` to round-off (relaxation
    lengths front, rear in m: equal, none, per axle, rear only)."""
    v = variant(vehicle, tire__relaxation_length_front_m=sigma[0],
                tire__relaxation_length_rear_m=sigma[1], roll__roll_yaw_product_kgm2=50.0,
                tire__rolling_resistance=0.015)
    p = eightdof.params_for(v)
    k = eightdof.kernels_for(p.tire_name)
    rng = np.random.default_rng(8)
    dx = np.zeros(eightdof.N_STATE)
    aux = np.zeros(eightdof.N_AUX)
    worst = 0.0
    for _ in range(200):
        x = np.zeros(eightdof.N_STATE)
        x[STATE.U] = rng.uniform(-5.0, 40.0)
        x[STATE.V] = rng.uniform(-2.0, 2.0)
        x[STATE.R] = rng.uniform(-0.6, 0.6)
        x[STATE.PHI] = rng.uniform(-0.06, 0.06)
        x[STATE.P] = rng.uniform(-0.3, 0.3)
        x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1] = x[STATE.U] / 0.29 * rng.uniform(0.6, 1.3, 4)
        x[STATE.X:STATE.PSI + 1] = rng.uniform(-50.0, 50.0, 3)
        x[STATE.AX_LT:STATE.AY_LT + 1] = rng.uniform(-6.0, 6.0, 2)
        x[STATE.ALPHA_FL:STATE.ALPHA_RR + 1] = rng.uniform(-0.1, 0.1, 4)
        u = np.zeros(eightdof.N_INPUT)
        u[INPUT.DELTA_F] = rng.uniform(-0.1, 0.1)
        u[INPUT.DELTA_R] = rng.uniform(-0.05, 0.05)
        u[INPUT.DRIVE_FL:INPUT.DRIVE_RR + 1] = rng.uniform(-300.0, 300.0, 4)
        u[INPUT.BRAKE_FL:INPUT.BRAKE_RR + 1] = rng.uniform(0.0, 1500.0, 4)
        ref, ref_aux = eightdof.evaluate(0.0, x, u, p)
        k.rhs(x, u, p.arr, p.coeffs_front, p.coeffs_rear, dx, aux)
        worst = max(worst, float(np.max(np.abs(dx - ref) / (1.0 + np.abs(ref)))))
        got_aux = eightdof.aux_from_array(aux)
        np.testing.assert_allclose(got_aux.fy_n, ref_aux.fy_n, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(got_aux.fz_n, ref_aux.fz_n, rtol=1e-12, atol=1e-9)
        assert got_aux.slip_rate_per_s == pytest.approx(ref_aux.slip_rate_per_s, rel=1e-12)
    assert worst < 1e-12


# ------------------------------------------------------------------------ conservation
def test_at_rest_with_no_input_stays_at_rest(vehicle: Vehicle) -> None:
    """Conservation: a car at rest with no input does not move (10 s, RK4 1 ms)."""
    sim = Simulator(vehicle)
    sim.reset(speed_mps=0.0)
    sim.step(Inputs(), 10000)
    assert np.all(sim.state == 0.0)


def test_straight_line_at_constant_speed(vehicle: Vehicle) -> None:
    """Conservation: no input and no rolling resistance -> straight line, constant speed."""
    sim = Simulator(vehicle)
    sim.reset(speed_mps=SPEED_85_MPS)
    sim.step(Inputs(), 10000)
    x = sim.state
    assert x[STATE.U] == pytest.approx(SPEED_85_MPS, abs=1e-9)
    assert x[STATE.X] == pytest.approx(SPEED_85_MPS * 10.0, abs=1e-6)
    for s in (STATE.V, STATE.R, STATE.PHI, STATE.P, STATE.Y, STATE.PSI):
        assert abs(x[s]) < 1e-12  # round-off of the wheel-by-wheel sums only


def test_rolling_resistance_decelerates_by_fr_g(vehicle: Vehicle) -> None:
    """With f_r the free-rolling car decelerates at f_r m g / (m + 4 I_w / R^2): the rolling
    resistance torque also decelerates the four wheels' spin inertia (momentum balance)."""
    fr = 0.015
    sim = Simulator(variant(vehicle, tire__rolling_resistance=fr))
    sim.reset(speed_mps=SPEED_85_MPS)
    sim.step(Inputs(), 1000)
    u1 = sim.state[STATE.U]
    sim.step(Inputs(), 2000)
    decel = (u1 - sim.state[STATE.U]) / 2.0
    bd, m = vehicle.body, vehicle.chassis.mass_kg
    assert bd is not None
    m_eff = m + 4.0 * bd.wheel_spin_inertia_kgm2 / bd.wheel_radius_m ** 2
    assert decel == pytest.approx(fr * m * GRAVITY_MPS2 / m_eff, rel=1e-3)


def test_left_right_steer_is_mirror_symmetric(vehicle: Vehicle) -> None:
    """Symmetry: steering -delta mirrors the response to +delta (to round-off)."""
    runs = []
    for sign in (1.0, -1.0):
        sim = Simulator(vehicle)
        sim.reset(speed_mps=SPEED_85_MPS)
        drive = (0.0, 0.0, 40.0, 40.0)
        sim.step(Inputs(front_wheel_angle_rad=sign * 0.02,
                        rear_wheel_angle_rad=sign * 0.004, drive_torque_nm=drive), 3000)
        runs.append(sim.state)
    a, b = runs
    odd = [STATE.V, STATE.R, STATE.PHI, STATE.P, STATE.Y, STATE.PSI, STATE.AY_LT]
    even = [STATE.U, STATE.X, STATE.AX_LT]
    scale = np.maximum(np.abs(a), 1.0)
    assert np.all(np.abs(a[odd] + b[odd]) <= 1e-9 * scale[odd])
    assert np.all(np.abs(a[even] - b[even]) <= 1e-9 * scale[even])
    swap = [STATE.OMEGA_FR, STATE.OMEGA_FL, STATE.OMEGA_RR, STATE.OMEGA_RL]
    omega = slice(STATE.OMEGA_FL, STATE.OMEGA_RR + 1)
    assert np.allclose(a[omega], b[swap], rtol=1e-11, atol=0.0)
    lag = slice(STATE.ALPHA_FL, STATE.ALPHA_RR + 1)
    lag_swap = [STATE.ALPHA_FR, STATE.ALPHA_FL, STATE.ALPHA_RR, STATE.ALPHA_RL]
    assert np.allclose(a[lag], -b[lag_swap], rtol=1e-9, atol=1e-15)
    assert abs(a[STATE.R]) > 0.1  # it did turn (0.4 rad/s)


# ------------------------------------------------------------------------ model levels
def test_small_steer_matches_linear_2dof_without_roll_steer(vehicle: Vehicle) -> None:
    """Model levels: no roll steer, no aligning moment -> the 2-DOF gain U/(L + K U^2)."""
    v = variant(vehicle, sti__g1=0.0, sti__k1=0.0, roll__roll_steer_front=0.0,
                roll__roll_steer_rear=0.0)
    gain, speed, y = steady_yaw_gain(v)
    assert abs(y["lateral_accel_mps2"]) < 0.5
    ref = linear_gain(linear2dof, linear_reference(v), speed)
    lin = linear_reference(v)
    L = lin.chassis.wheelbase_m
    assert ref == pytest.approx(speed / (L + lin.understeer_gradient_rad_per_mps2 * speed ** 2),
                                rel=1e-12)
    assert gain == pytest.approx(ref, rel=0.01)  # measured 0.01 %


def test_small_steer_matches_linear_3dof_with_roll_steer(vehicle: Vehicle) -> None:
    """Model levels: with table_8_1's roll steer the 8-DOF gain is the 3-DOF's."""
    v = variant(vehicle, sti__g1=0.0, sti__k1=0.0)
    gain, speed, y = steady_yaw_gain(v)
    assert abs(y["lateral_accel_mps2"]) < 0.6
    ref = linear_gain(roll3dof, linear_reference(v), speed)
    assert gain == pytest.approx(ref, rel=0.01)  # measured 0.2 %


def test_table_8_1_gain_with_aligning_moments(vehicle: Vehicle) -> None:
    """table_8_1 as shipped: gain U/(L + K U^2) with K from the tires' stiffness and trail,
    roll gradient and roll steer (linear steady state of the same vehicle) within 5 %."""
    gain, speed, y = steady_yaw_gain(vehicle)
    assert abs(y["lateral_accel_mps2"]) < 0.5
    p = eightdof.params_for(vehicle)
    c, rl = vehicle.chassis, vehicle.roll
    assert rl is not None
    a, b, L, m = c.cg_to_front_axle_m, c.cg_to_rear_axle_m, c.wheelbase_m, c.mass_kg
    fzf, fzr = static_loads(vehicle)
    small = 1.0e-4

    def trail(coeffs: np.ndarray, fz: float) -> float:
        _, fy, mz = p.tire.forces(fz, small, 0.0, speed, 1.0, coeffs)
        return -mz / fy

    tf, tr = trail(p.coeffs_front, fzf), trail(p.coeffs_rear, fzr)
    cf = 2.0 * cornering_stiffness("sti", p.coeffs_front, fzf)
    cr = 2.0 * cornering_stiffness("sti", p.coeffs_rear, fzr)
    roll_gradient = rl.sprung_mass_kg * rl.roll_arm_m / (
        rl.roll_stiffness_nm_per_rad - rl.sprung_mass_kg * GRAVITY_MPS2 * rl.roll_arm_m)
    k_us = (m / (L + tr - tf) * ((b + tr) / cf - (a - tf) / cr)
            - (rl.roll_steer_front - rl.roll_steer_rear) * roll_gradient)
    assert k_us < 0.0  # the complete car is oversteer (see the YAML header)
    assert gain == pytest.approx(speed / (L + k_us * speed ** 2), rel=0.05)  # measured 0.5 %


def test_step_steer_at_85_kmh_settles(vehicle: Vehicle) -> None:
    """Figures 8.5-8.12: the FWS car's step response at 85 km/h settles (stable), here with
    the speed held by a proportional rear-drive torque."""
    sim = Simulator(vehicle)
    sim.reset(speed_mps=SPEED_85_MPS)
    gain_nm_per_mps = 2000.0
    yaw = []
    for _ in range(600):  # 6 s in 10-ms ticks
        torque = gain_nm_per_mps * (SPEED_85_MPS - sim.state[STATE.U])
        sim.step(Inputs(front_wheel_angle_rad=math.radians(1.0),
                        drive_torque_nm=(0.0, 0.0, torque, torque)), 10)
        yaw.append(sim.state[STATE.R])
    y = sim.outputs()
    assert y["lateral_accel_mps2"] > 3.0  # ~0.5 g: well into the nonlinear range
    assert y["speed_mps"] == pytest.approx(SPEED_85_MPS, rel=0.01)
    assert yaw[-1] == pytest.approx(yaw[-101], rel=1e-3)  # last second: steady


# ------------------------------------------------------------------------ low speed, braking
@pytest.mark.parametrize("brake", [0.0, 800.0])
def test_standstill_no_nan(vehicle: Vehicle, brake: float) -> None:
    """At rest with steer (and brake): 10 s without NaN and without moving."""
    sim = Simulator(vehicle)
    sim.reset(speed_mps=0.0)
    sim.step(Inputs(front_wheel_angle_rad=0.3, rear_wheel_angle_rad=-0.05,
                    brake_torque_nm=(brake,) * 4), 10000)
    x = sim.state
    assert np.all(np.isfinite(x))
    assert np.max(np.abs(x)) == 0.0


def test_rolling_to_a_stop_under_brake(vehicle: Vehicle) -> None:
    """From 2 m/s, braked with steer: comes to rest, wheels held, nothing diverges."""
    sim = Simulator(vehicle)
    sim.reset(speed_mps=2.0)
    u = Inputs(front_wheel_angle_rad=0.1, brake_torque_nm=(1500.0,) * 4)
    omega_min = np.inf
    speed_min = np.inf
    for _ in range(1000):  # 10 s in 10-ms ticks
        sim.step(u, 10)
        x = sim.state
        omega_min = min(omega_min, float(np.min(x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1])))
        speed_min = min(speed_min, float(x[STATE.U]))
    assert np.all(np.isfinite(x))
    assert omega_min >= 0.0  # held wheels never turn backwards
    # the stopped car rocks on the tires' lateral compliance (relaxation length: a spring
    # C/sigma at rest) by a few cm/s, then settles
    assert speed_min > -0.05
    assert np.max(np.abs(x[[STATE.U, STATE.V, STATE.R, STATE.P]])) < 1e-6
    assert np.all(np.abs(x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1])
                  <= eightdof.HELD_SPIN_FLOOR_RADPS)  # locked


def test_creep_from_rest_with_drive_torque(vehicle: Vehicle) -> None:
    """Pulling away from rest at full lock: finite, moves forward, turns left."""
    sim = Simulator(vehicle)
    sim.reset(speed_mps=0.0)
    sim.step(Inputs(front_wheel_angle_rad=0.5, drive_torque_nm=(0.0, 0.0, 150.0, 150.0)),
             10000)
    y = sim.outputs()
    assert np.isfinite(sim.state).all()
    assert y["speed_mps"] > 0.5 and y["yaw_rate_radps"] > 0.0


def test_hard_braking_locks_wheels_at_mu_g(vehicle: Vehicle) -> None:
    """Braking to lock: slip -> -1 and deceleration = locked friction x g (Coulomb)."""
    sim = Simulator(vehicle)
    sim.reset(speed_mps=20.0)
    u = Inputs(brake_torque_nm=(3000.0,) * 4)
    p = eightdof.params_for(vehicle)
    fzf, _ = static_loads(vehicle)
    samples = []
    for _ in range(150):  # 1.5 s in 10-ms ticks
        sim.step(u, 10)
        y = sim.outputs()
        if sim.time_s >= 0.3:
            samples.append((y["longitudinal_accel_mps2"], y["slip_ratio"].copy(),
                            y["wheel_speed_radps"].copy(), y["speed_mps"]))
    ax = np.array([s[0] for s in samples])
    kappa = np.array([s[1] for s in samples])
    omega = np.array([s[2] for s in samples])
    assert kappa.max() < -0.95  # locked: slip ratio near -1
    assert omega.min() >= 0.0  # the brake never spins a wheel backwards
    assert np.all(np.abs(np.diff(omega, axis=0)) < 0.5)  # no chatter
    mu_locked = -p.tire.forces(fzf, 0.0, float(kappa.mean()), 15.0, 1.0,
                               p.coeffs_front)[0] / fzf
    assert float(ax.mean()) == pytest.approx(-mu_locked * GRAVITY_MPS2, rel=0.03)


def test_rk4_matches_solve_ivp_reference(vehicle: Vehicle) -> None:
    """RK4 at 1 ms (compiled) vs SciPy DOP853 at 1e-10 (NumPy model): 1 s of step steer
    with braking."""
    u = Inputs(front_wheel_angle_rad=0.02, brake_torque_nm=(300.0, 300.0, 200.0, 200.0))
    states = []
    for integ in ("rk4", "solve_ivp"):
        sim = Simulator(vehicle, integrator=integ)
        sim.reset(speed_mps=SPEED_85_MPS)
        sim.step(u, 500)
        states.append(sim.state)
    a, b = states
    scale = np.maximum(np.abs(b), 1e-3)
    assert np.max(np.abs(a - b) / scale) < 1e-6


def test_brake_holds_a_car_at_rest_against_a_smaller_drive_torque(vehicle: Vehicle) -> None:
    """Static friction of the brake: on the driven (rear) wheels, a drive torque below the
    brake torque leaves the car exactly at rest; above it the wheels break loose and the car
    moves off with the difference (Coulomb friction)."""
    for drive, moves in ((600.0, False), (1400.0, True)):
        sim = Simulator(vehicle)
        sim.reset(speed_mps=0.0)
        sim.step(Inputs(drive_torque_nm=(0.0, 0.0, drive, drive),
                        brake_torque_nm=(0.0, 0.0, 1000.0, 1000.0)), 3000)
        x = sim.state
        if moves:
            # net 2 x 400 N m at the rear wheels: about 800 / (R m) = 2.1 m/s^2 for 3 s
            assert x[STATE.U] > 4.0
        else:
            assert np.all(x == 0.0)


def test_linear_tire_variant_matches_the_2dof_with_table_5_1_stiffness(
        vehicle: Vehicle) -> None:
    """Tire override: with the linear tire (Table 5.1's Cf, Cr) and no roll steer the 8-DOF
    gives the 2-DOF gain of those stiffnesses -- also proves the per-tire compiled variants
    do not share code."""
    v = variant(vehicle, roll__roll_steer_front=0.0, roll__roll_steer_rear=0.0)
    sim = Simulator(v, tire="linear")
    sim.reset(speed_mps=SPEED_85_MPS)
    sim.step(Inputs(front_wheel_angle_rad=1.0e-3), 8000)
    y = sim.outputs()
    ref = linear_gain(linear2dof, v, y["speed_mps"])
    assert y["yaw_rate_radps"] / 1.0e-3 == pytest.approx(ref, rel=0.01)
    sti_gain, _, _ = steady_yaw_gain(variant(v, sti__g1=0.0, sti__k1=0.0))
    assert abs(sti_gain / ref - 1.0) > 0.05  # the STI tire is a different tire
