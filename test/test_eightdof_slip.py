# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Slips of the 8-DOF model with light and heavy wheels, and the F1TENTH scale car.

Sources of the numbers asserted here:

* model levels: at small steer the 8-DOF's steady yaw-rate gain and 90 % yaw response time
  are those of the linear 2-DOF model with lagged tire force (ch. 5, ``2dof-lagged``) plus the
  wheels' spin inertia (:func:`wheel_reference`), for wheel spin inertias 0.01-5 kg m^2 and
  speeds 2-40 m/s. "Plus the wheels' spin inertia": linearized about straight free rolling,
  each wheel i at lateral offset y_i rolls at U - r y_i, so a yaw rate needs the left and
  right wheels to spin at different speeds; the tire's longitudinal slip
  kappa_i = (R dw_i - dU + r y_i)/U makes the force C_s kappa_i that spins them up
  (I_w dw_i' = -R F_x,i) and acts back on the yaw, -y_i F_x,i, and on the speed. For
  table_8_1 this adds up to I_w (T_f^2 + T_r^2)/(2 R^2) = 49 kg m^2 of yaw inertia (3 % of
  Iz) when the wheels follow quickly; for I_w = 5 kg m^2 at 40 m/s the wheels lag the yaw
  (their slip mode, R^2 C_s/(I_w U) = 9.5 1/s, is as slow as the yaw mode), which the
  reference carries as four wheel-spin states. The 2-DOF cannot have roll: table_8_1 runs
  with its roll dynamics but without roll steer and aligning moment; its roll coupling
  accounts for the 0.6-1.5 % that remain in the response time (0.2 % with the roll arm
  removed, also tested).
* the bicycle-model gain U/(L + K_us U^2) of the F1TENTH car's cornering stiffnesses
  (f1tenth_gym's parameters, ``config/vehicles/f1tenth.yaml``);
* the momentum balance of a driven light wheel (acceleration 2T/(R (m + 4 I_w/R^2)), wheel
  slip F_x/C_s on the exact kinematic slip);
* the sub-step contract: a step taken in n sub-steps equals n steps of dt/n.

Measured (this file's grids, errors of the 8-DOF against the reference): table_8_1 gain
within 0.13 %, response time -0.57 to -1.45 %; F1TENTH car gain within 0.08 %, response time
within 0.32 %; bicycle gain of the F1TENTH file within 0.003 %.
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np
import pytest
from scipy.optimize import brentq

from fourws_sim.errors import ParameterError
from fourws_sim.models import eightdof, lagged2dof
from fourws_sim.models.eightdof import INPUT, PARAM, STATE
from fourws_sim.params import GRAVITY_MPS2, VEHICLE_DIR, Vehicle, load_vehicle, \
    vehicle_from_mapping
from fourws_sim.simulator import Simulator
from fourws_sim.tires import cornering_stiffness

#: Road-wheel step angle of the small-steer comparisons, rad (0.4 m/s^2 at 40 m/s).
STEP_RAD = 1.0e-3
#: Slip step of the longitudinal-stiffness central difference.
SLIP_STEP = 1.0e-5


def variant(v: Vehicle, **changes: Any) -> Vehicle:
    """Copy of ``v`` with ``subsystem__field=value`` changes (``sti__g1`` for tire.sti); the
    changed fields are exempt from the plausibility bounds (a variant may be deliberately
    unreal, e.g. a roll arm of 0.1 mm to remove roll, a 1e-12 kg m^2 wheel)."""
    d = v.to_dict()
    lifted = set(d.get("unchecked_fields", []))
    for path, value in changes.items():
        sub, key = path.split("__")
        (d["tire"]["sti"] if sub == "sti" else d[sub])[key] = value
        lifted.add(f"tire.sti.{key}" if sub == "sti" else f"{sub}.{key}")
    d["unchecked_fields"] = sorted(lifted)
    return vehicle_from_mapping(d, f"{v.name} variant")


def without_roll_steer_and_aligning_moment(v: Vehicle) -> Vehicle:
    """``v`` as far as a 2-DOF can describe it: no roll steer, no aligning moment (the STI
    tire's trail G1 and K1 set to 0; the linear tire has none)."""
    changes: dict[str, Any] = {"roll__roll_steer_front": 0.0, "roll__roll_steer_rear": 0.0}
    if v.tire is not None and v.tire.model == "sti":
        changes.update(sti__g1=0.0, sti__k1=0.0)
    return variant(v, **changes)


def static_loads(v: Vehicle) -> tuple[float, float]:
    """Static normal load of one front and one rear tire, N."""
    c = v.chassis
    w = c.mass_kg * GRAVITY_MPS2 / (2.0 * c.wheelbase_m)
    return w * c.cg_to_rear_axle_m, w * c.cg_to_front_axle_m


def wheel_reference(v: Vehicle, speed: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear reference ``(A, b)`` of the 8-DOF at ``speed`` (m/s) for a front steer input:
    the ``2dof-lagged`` model with the tires' stiffness at static load (states V, r, Fyf, Fyr)
    plus the four wheel spins and the speed, linearized about free rolling (see the module
    docstring)."""
    p = eightdof.params_for(v)
    fzf, fzr = static_loads(v)
    d = v.to_dict()
    d["axle_tires"] = {
        "cornering_stiffness_front_n_per_rad":
            2.0 * cornering_stiffness(p.tire_name, p.coeffs_front, fzf),
        "cornering_stiffness_rear_n_per_rad":
            2.0 * cornering_stiffness(p.tire_name, p.coeffs_rear, fzr)}
    A2, B2 = lagged2dof.matrices(vehicle_from_mapping(d, "reference"), speed)

    def c_s(coeffs: np.ndarray, fz: float) -> float:
        f = [p.tire.forces(fz, 0.0, s, speed, p[PARAM.MU], coeffs)[0]
             for s in (SLIP_STEP, -SLIP_STEP)]
        return (f[0] - f[1]) / (2.0 * SLIP_STEP)

    bd, c = v.body, v.chassis
    assert bd is not None
    cs = [c_s(p.coeffs_front, fzf)] * 2 + [c_s(p.coeffs_rear, fzr)] * 2
    y = [0.5 * bd.track_front_m, -0.5 * bd.track_front_m,
         0.5 * bd.track_rear_m, -0.5 * bd.track_rear_m]
    r_w, i_w = bd.wheel_radius_m, bd.wheel_spin_inertia_kgm2
    R_ = lagged2dof.STATE.R
    n = 4 + 4 + 1  # 2dof-lagged, wheel spins (deviation from U/R), speed deviation
    i_u = 8
    A = np.zeros((n, n))
    A[:4, :4] = A2
    b = np.zeros(n)
    b[:4] = B2[:, lagged2dof.INPUT.DELTA_F]
    for i in range(4):
        kappa = np.zeros(n)  # slip of wheel i per state
        kappa[4 + i] = r_w / speed
        kappa[i_u] = -1.0 / speed
        kappa[R_] = y[i] / speed
        fx = cs[i] * kappa
        A[4 + i] -= r_w * fx / i_w
        A[i_u] += fx / c.mass_kg
        A[R_] -= y[i] * fx / c.yaw_inertia_kgm2
    return A, b


def step_response(A: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """Steady yaw-rate gain (1/s), 90 % response time (s) and slowest decay rate (1/s) of the
    step response of ``x' = A x + b`` (the reference's speed mode is neutral: eigenvalue 0,
    not excited by steer at first order)."""
    x_ss = -np.linalg.lstsq(A, b, rcond=None)[0]
    w, V = np.linalg.eig(A)
    coef = np.linalg.solve(V, x_ss)
    moving = np.abs(w) > 1e-9
    R_ = lagged2dof.STATE.R

    def r(t: float) -> float:  # x(t) = x_ss - sum_k V_k coef_k exp(w_k t) over moving modes
        return float(x_ss[R_] - np.real(np.sum((V[R_] * coef * np.exp(w * t))[moving])))

    slowest = float(np.min(-w.real[moving]))
    ts = np.linspace(0.0, 10.0 / slowest, 20001)
    above = np.array([r(t) for t in ts]) >= 0.9 * x_ss[R_]
    k = int(np.argmax(above))
    t90 = brentq(lambda t: r(t) - 0.9 * x_ss[R_], ts[k - 1], ts[k], xtol=1e-9)
    return float(x_ss[R_]), t90, slowest


def eightdof_step(v: Vehicle, speed: float, seconds: float) -> tuple[float, float, float]:
    """8-DOF (RK4 1 ms) step steer of :data:`STEP_RAD` from straight running at ``speed``:
    final yaw-rate gain (1/s), 90 % response time (s, interpolated), final speed (m/s)."""
    sim = Simulator(v)
    sim.reset(speed_mps=speed)
    u = np.zeros(len(INPUT))
    u[INPUT.DELTA_F] = STEP_RAD
    n = int(round(seconds / sim.dt_s))
    r = np.zeros(n + 1)
    for k in range(1, n + 1):
        sim.step(u, 1)
        r[k] = sim.state[STATE.R]
    k = int(np.argmax(r >= 0.9 * r[-1]))
    t90 = sim.dt_s * (k - 1 + (0.9 * r[-1] - r[k - 1]) / (r[k] - r[k - 1]))
    return r[-1] / STEP_RAD, t90, float(sim.state[STATE.U])


def compare(v: Vehicle, speed: float) -> tuple[float, float]:
    """Relative errors of the 8-DOF's steady gain and 90 % response time against
    :func:`wheel_reference` (run until the reference's slowest mode has decayed to e^-8)."""
    gain_ref, t90_ref, slowest = step_response(*wheel_reference(v, speed))
    gain, t90, final_speed = eightdof_step(v, speed, max(1.0, 8.0 / slowest))
    assert abs(final_speed / speed - 1.0) < 2e-4  # induced drag only: free rolling
    gain_final = step_response(*wheel_reference(v, final_speed))[0]
    return gain / gain_final - 1.0, t90 / t90_ref - 1.0


@pytest.fixture(scope="module")
def table_8_1() -> Vehicle:
    return without_roll_steer_and_aligning_moment(load_vehicle("table_8_1"))


@pytest.fixture(scope="module")
def f1tenth() -> Vehicle:
    return load_vehicle("f1tenth")


# ------------------------------------------------------------------------ model levels
@pytest.mark.parametrize("inertia", [0.01, 2.0337, 5.0])
@pytest.mark.parametrize("speed", [2.0, 10.0, 40.0])
def test_table_8_1_matches_lagged_2dof_plus_wheel_spin(table_8_1: Vehicle, inertia: float,
                                                       speed: float) -> None:
    """Wheel spin inertia 0.01 kg m^2 (200 times lighter than the car's own 2.03, 190
    sub-steps per 1-ms step at standstill) to 5: the slips are exact and the yaw response is
    the reference's within 2 % (roll coupling included)."""
    gain_err, t90_err = compare(variant(table_8_1, body__wheel_spin_inertia_kgm2=inertia),
                                speed)
    assert abs(gain_err) < 0.02  # measured <= 0.13 %
    assert abs(t90_err) < 0.02  # measured -0.57 to -1.45 % (roll coupling)


@pytest.mark.parametrize(("inertia", "speed"), [(0.01, 2.0), (5.0, 40.0)])
def test_without_roll_the_8dof_is_the_reference(table_8_1: Vehicle, inertia: float,
                                                speed: float) -> None:
    """With the roll arm removed (1e-4 m) the 8-DOF's remaining dynamics are the reference's:
    the response time agrees to 0.3 % at both corners of the grid (the stiffest wheel at the
    lowest speed and the heaviest at the highest, where the wheels' lag shows most)."""
    v = variant(table_8_1, body__wheel_spin_inertia_kgm2=inertia, roll__roll_arm_m=1.0e-4)
    gain_err, t90_err = compare(v, speed)
    assert abs(gain_err) < 0.003  # measured 0.015 %, -0.09 %
    assert abs(t90_err) < 0.003  # measured 0.01 %, -0.18 %


@pytest.mark.parametrize("inertia", [1.4e-4, 0.01])
@pytest.mark.parametrize("speed", [2.0, 8.0, 20.0])
def test_f1tenth_matches_lagged_2dof_plus_wheel_spin(f1tenth: Vehicle, inertia: float,
                                                     speed: float) -> None:
    """The scale car with its own wheels (1.4e-4 kg m^2: the wheels add 8 % to the yaw
    inertia) and with 0.01 kg m^2 (the bottom of the sedan grid; 5 kg m^2 would be a
    flywheel 10^5 times the car's wheels), up to its top speed of 20 m/s (f1tenth_gym)."""
    v = variant(without_roll_steer_and_aligning_moment(f1tenth),
                body__wheel_spin_inertia_kgm2=inertia)
    gain_err, t90_err = compare(v, speed)
    assert abs(gain_err) < 0.02  # measured <= 0.08 %
    assert abs(t90_err) < 0.02  # measured <= 0.32 %


# ------------------------------------------------------------------------ the scale car
def test_f1tenth_file_values_are_its_sources() -> None:
    """Cornering stiffness = f1tenth_gym's mu C_S x static axle load (g = 9.81 there), tracks
    and wheel radius from its URDF; every value carries a source comment."""
    v = load_vehicle("f1tenth")
    c, t, bd = v.chassis, v.axle_tires, v.body
    assert bd is not None and v.tire is not None
    mu, m, lf, lr = 1.0489, 3.74, 0.15875, 0.17145
    assert (c.mass_kg, c.yaw_inertia_kgm2, c.cg_to_front_axle_m, c.cg_to_rear_axle_m) == \
        (m, 0.04712, lf, lr)
    assert t.cornering_stiffness_front_n_per_rad == pytest.approx(
        mu * 4.718 * m * 9.81 * lr / (lf + lr), abs=5e-4)
    assert t.cornering_stiffness_rear_n_per_rad == pytest.approx(
        mu * 5.4562 * m * 9.81 * lf / (lf + lr), abs=5e-4)
    assert bd.track_front_m == pytest.approx(0.132904 + 0.131600, abs=1e-4)
    assert bd.track_rear_m == pytest.approx(0.130772 + 0.132075, abs=1e-4)
    assert v.tire.friction_coefficient == mu and bd.cg_height_m == 0.074
    # the stated roll gradient of 3 deg/g and the sprung-CG height follow from the values
    rl = v.roll
    assert rl is not None
    msgh = rl.sprung_mass_kg * GRAVITY_MPS2 * rl.roll_arm_m
    gradient = msgh / (rl.roll_stiffness_nm_per_rad - msgh)  # rad per g
    assert math.degrees(gradient) == pytest.approx(3.0, abs=0.01)
    h_sprung = (m * bd.cg_height_m - (m - rl.sprung_mass_kg) * bd.unsprung_cg_height_m) \
        / rl.sprung_mass_kg
    assert rl.roll_arm_m + bd.roll_centre_height_front_m == pytest.approx(h_sprung, abs=1e-4)
    text = (VEHICLE_DIR / "f1tenth.yaml").read_text()
    for line in text.splitlines():
        if re.match(r"^\s+\w+:\s*-?[0-9.e-]+\s*(#.*)?$", line):
            assert "#" in line, f"value without a source comment: {line.strip()}"


@pytest.mark.parametrize("speed", [2.0, 10.0, 20.0])
def test_f1tenth_reproduces_the_bicycle_gain_at_1_khz(f1tenth: Vehicle, speed: float) -> None:
    """The shipped file at 1 kHz, small steer: steady yaw-rate gain U/(L + K_us U^2) with the
    file's cornering stiffnesses within 1 % (measured <= 0.003 %)."""
    sim = Simulator(f1tenth, dt_s=1.0e-3)
    sim.reset(speed_mps=speed)
    u = np.zeros(len(INPUT))
    u[INPUT.DELTA_F] = STEP_RAD
    sim.step(u, 5000)
    y = sim.outputs()
    L, k_us = f1tenth.chassis.wheelbase_m, f1tenth.understeer_gradient_rad_per_mps2
    assert k_us == pytest.approx(2.787e-3, rel=1e-3)  # understeer, as the file header says
    bicycle = y["speed_mps"] / (L + k_us * y["speed_mps"] ** 2)
    assert y["yaw_rate_radps"] / STEP_RAD == pytest.approx(bicycle, rel=0.01)


# ------------------------------------------------------------------------ exact slips
def test_light_driven_wheel_slips_exactly(table_8_1: Vehicle) -> None:
    """table_8_1 with 0.01 kg m^2 wheels (10 sub-steps per step at 20 m/s), 200 N m on each
    rear wheel: the car accelerates at 2T / (R (m + 4 I_w/R^2)) (momentum balance) and each
    rear wheel runs at the slip at which its tire gives the force F_x = (T - I_w a/R)/R, on
    the exact slip (omega R - v_x)/v_x (a slip floor raised to the step's needs, 190 m/s,
    had made the wheel slip 9.5 times too much)."""
    iw, torque = 0.01, 200.0
    v = variant(table_8_1, body__wheel_spin_inertia_kgm2=iw)
    sim = Simulator(v)
    sim.reset(speed_mps=20.0)
    u = np.zeros(len(INPUT))
    u[INPUT.DRIVE_RL] = u[INPUT.DRIVE_RR] = torque
    sim.step(u, 500)
    u0 = sim.state[STATE.U]
    sim.step(u, 500)
    x = sim.state
    bd, m = v.body, v.chassis.mass_kg
    assert bd is not None
    r_w = bd.wheel_radius_m
    accel = (x[STATE.U] - u0) / 0.5
    assert accel == pytest.approx(2.0 * torque / (r_w * (m + 4.0 * iw / r_w ** 2)), rel=1e-3)
    p = eightdof.params_for(v)
    fx = (torque - iw * accel / r_w) / r_w
    fz_rear = static_loads(v)[1] + 0.5 * m * accel * bd.cg_height_m / v.chassis.wheelbase_m
    kappa = brentq(lambda k: p.tire.forces(fz_rear, 0.0, k, 20.0, 1.0, p.coeffs_rear)[0] - fx,
                   0.0, 0.5, xtol=1e-12)
    slip = x[STATE.OMEGA_RL] * r_w / x[STATE.U] - 1.0
    assert kappa > 0.03  # 3-4 % drive slip
    assert slip == pytest.approx(kappa, rel=1e-3)
    # straight running: every wheel's slip denominator is U, so the spin rate is K_SPIN / U
    rate = eightdof.evaluate(0.0, x, u, p)[1].slip_rate_per_s
    assert rate == pytest.approx(p[PARAM.K_SPIN] / x[STATE.U], rel=1e-12)
    assert eightdof.substeps(rate, sim.dt_s) == math.ceil(rate * sim.dt_s
                                                          / eightdof.RK4_RATE_BOUND)


@pytest.mark.parametrize("integrator", ["rk4", "euler", "semi_implicit_euler"])
def test_a_step_in_sub_steps_equals_that_many_short_steps(table_8_1: Vehicle,
                                                          integrator: str) -> None:
    """The compiled loops split a step into ``eightdof.substeps(rate, dt)`` equal sub-steps:
    one 1-ms step of a light-wheeled car at 3 m/s is bit for bit n steps of 1/n ms (each of
    which needs no further split)."""
    v = variant(table_8_1, body__wheel_spin_inertia_kgm2=0.01)
    start = Simulator(v, integrator=integrator)
    start.reset(speed_mps=3.0)
    u = np.zeros(len(INPUT))
    u[INPUT.DELTA_F] = 0.02
    u[INPUT.BRAKE_FL:INPUT.BRAKE_RR + 1] = 30.0
    start.step(u, 20)
    x = start.state
    rate = eightdof.evaluate(0.0, x, u, eightdof.params_for(v))[1].slip_rate_per_s
    n = eightdof.substeps(rate, 1.0e-3, integrator)
    assert 20 < n < eightdof.MAX_SUBSTEPS  # a real split (table_8_1's tires: ~60 at 3 m/s)
    one = Simulator(v, integrator=integrator)
    one.state = x
    one.step(u, 1)
    many = Simulator(v, integrator=integrator, dt_s=1.0e-3 / n)
    many.state = x
    many.step(u, n)
    assert np.array_equal(one.state, many.state)


@pytest.mark.parametrize("inertia", [1.0e-12, 1.0e-300])
def test_a_wheel_too_light_for_the_step_is_a_one_line_error(inertia: float) -> None:
    """Beyond MAX_SUBSTEPS sub-steps at standstill the simulator refuses the vehicle with one
    line naming the step and the wheel inertia, and how to fix it (a 1e-12 kg m^2 wheel used
    to crash with a math domain error)."""
    v = variant(load_vehicle("table_8_1"), body__wheel_spin_inertia_kgm2=inertia)
    with pytest.raises(ParameterError) as info:
        Simulator(v)
    msg = str(info.value)
    assert info.value.field == "body.wheel_spin_inertia_kgm2"
    assert "dt_s = 0.001 s" in msg and f"{inertia:.3g} kg m^2" in msg and "\n" not in msg
    # the remedies it names do work: the largest step, and the lightest inertia at 1 ms
    iw_ok = float(re.search(r"inertia >= ([0-9.e+-]+) kg", msg).group(1))
    assert Simulator(variant(v, body__wheel_spin_inertia_kgm2=1.01 * iw_ok)).dt_s == 1e-3


def test_light_wheels_brake_to_rest_without_nan(table_8_1: Vehicle) -> None:
    """0.01 kg m^2 wheels from 2 m/s, braked with steer: at rest within 1 s, the wheels held
    (never turning backwards), every state finite (190 sub-steps per step below 1 m/s)."""
    sim = Simulator(variant(table_8_1, body__wheel_spin_inertia_kgm2=0.01))
    sim.reset(speed_mps=2.0)
    u = np.zeros(len(INPUT))
    u[INPUT.DELTA_F] = 0.1
    u[INPUT.BRAKE_FL:INPUT.BRAKE_RR + 1] = 1500.0
    omega_min = np.inf
    for _ in range(100):
        sim.step(u, 10)
        omega_min = min(omega_min, float(sim.state[STATE.OMEGA_FL:STATE.OMEGA_RR + 1].min()))
    x = sim.state
    assert np.all(np.isfinite(x))
    assert omega_min >= 0.0
    assert abs(x[STATE.U]) < 0.05 and np.all(np.abs(x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1])
                                             <= eightdof.HELD_SPIN_FLOOR_RADPS)
