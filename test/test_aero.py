# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Aerodynamic drag and lift of the 8-DOF model (``aero:`` in the vehicle file).

Sources of the numbers asserted here:

* the coast-down's closed form: the car's momentum balance with the four wheels' spin
  inertia (m_eff = m + 4 I_w / R^2, as ``test_eightdof``'s rolling-resistance test),
  m_eff dU/dt = -c U^2 - f_r m g with c = 0.5 rho C_d A. Without rolling resistance
  U(t) = U0 / (1 + k U0 t), k = c / m_eff; with it
  U(t) = sqrt(a/b) tan(atan(U0 sqrt(b/a)) - sqrt(a b) t), a = f_r m g / m_eff, b = k;
* hand computations written in the tests: the lift 0.5 rho C_l,i A U^2 of an axle taken off
  its two wheels, the drag's deceleration D/m and its load transfer D h_cg / L at a trim;
* the NumPy reference ``eightdof.evaluate`` (the test oracle) against the compiled kernels,
  to round-off; the offline twin against the study's compiled loop, bit for bit;
* the model without ``aero``: an ``aero`` block of zeros gives its trajectory bit for bit.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from compiled_twin import compiled_and_twin
from fourws_sim.errors import ParameterError
from fourws_sim.models import eightdof
from fourws_sim.models.eightdof import INPUT, STATE
from fourws_sim.params import (AIR_DENSITY_KGPM3, GRAVITY_MPS2, Vehicle, load_vehicle,
                               vehicle_from_mapping)
from fourws_sim.simulator import Inputs, Simulator
from fourws_study.spec import load_study

#: A sedan's drag area (C_d 0.30 x 2.3 m^2 frontal area), m^2.
SEDAN_CDA_M2 = 0.69
SPEED_MPS = 30.0


@pytest.fixture(scope="module")
def vehicle() -> Vehicle:
    return load_vehicle("table_8_1")


def with_aero(v: Vehicle, source: str = "aero variant", **aero: Any) -> Vehicle:
    """Copy of ``v`` with the ``aero`` block ``aero`` (and any ``tire__field`` changes)."""
    d = v.to_dict()
    for key in [k for k in aero if k.startswith("tire__")]:
        d["tire"][key.split("__")[1]] = aero.pop(key)
    d["aero"] = dict(aero)
    return vehicle_from_mapping(d, source)


def m_eff(v: Vehicle) -> float:
    """Mass with the four wheels' spin inertia (kg): the coast-down's momentum balance."""
    bd = v.body
    assert bd is not None
    return v.chassis.mass_kg + 4.0 * bd.wheel_spin_inertia_kgm2 / bd.wheel_radius_m ** 2


def coast(v: Vehicle, u0: float, seconds: float, every_s: float = 5.0) -> tuple[
        np.ndarray, np.ndarray]:
    """Coast-down (no drive, no brake, no steer) from ``u0`` m/s: times and speeds."""
    sim = Simulator(v)
    sim.reset(speed_mps=u0)
    n = int(round(every_s / sim.dt_s))
    times, speeds = [0.0], [u0]
    for _ in range(int(round(seconds / every_s))):
        sim.step(Inputs(), n)
        times.append(sim.time_s)
        speeds.append(float(sim.state[STATE.U]))
    return np.array(times), np.array(speeds)


# ------------------------------------------------------------------------ the file block
def test_aero_block_defaults_and_coefficients(vehicle: Vehicle) -> None:
    """Air density defaults to ISO 2533's sea level 1.225 kg/m^3; 0.5 rho C A by hand."""
    v = with_aero(vehicle, drag_area_m2=SEDAN_CDA_M2, lift_area_front_m2=0.1)
    assert v.aero is not None
    assert v.aero.air_density_kgpm3 == AIR_DENSITY_KGPM3 == 1.225
    assert v.aero.drag_coefficient_kg_per_m == pytest.approx(0.5 * 1.225 * 0.69)
    assert v.aero.lift_coefficients_kg_per_m() == pytest.approx((0.5 * 1.225 * 0.1, 0.0))
    # the block travels with the vehicle into run records and reloads
    assert vehicle_from_mapping(v.to_dict(), "again") == v
    assert "aero" not in vehicle.to_dict()


@pytest.mark.parametrize("field, value, needle", [
    ("drag_area_m2", -0.1, "must be >= 0"),
    ("drag_area_m2", 50.0, "outside the plausible range"),
    ("air_density_kgpm3", 0.0, "must be > 0"),
    ("lift_area_rear_m2", "x", "must be a number"),
    ("frontal_area_m2", 2.0, "unknown field"),
])
def test_bad_aero_values_name_the_field(vehicle: Vehicle, field: str, value: Any,
                                        needle: str) -> None:
    with pytest.raises(ParameterError) as err:
        with_aero(vehicle, **{field: value})
    assert f"aero.{field}" in str(err.value) and needle in str(err.value)


# ------------------------------------------------------------------------ coast-down
def test_coast_down_on_drag_alone_follows_the_closed_form(vehicle: Vehicle) -> None:
    """m_eff dU/dt = -c U^2: U(t) = U0 / (1 + k U0 t), k = c / m_eff, within 0.1 % over
    60 s from 30 m/s (to 19.4 m/s)."""
    v = with_aero(vehicle, drag_area_m2=SEDAN_CDA_M2)
    t, u = coast(v, SPEED_MPS, 60.0)
    k = 0.5 * AIR_DENSITY_KGPM3 * SEDAN_CDA_M2 / m_eff(v)
    want = SPEED_MPS / (1.0 + k * SPEED_MPS * t)
    assert want[-1] < 0.7 * SPEED_MPS  # the drag acts: the test could fail
    np.testing.assert_allclose(u, want, rtol=1e-3)


def test_coast_down_with_rolling_resistance_follows_the_closed_form(vehicle: Vehicle) -> None:
    """m_eff dU/dt = -(f_r m g + c U^2): the tangent closed form, within 0.1 % over 60 s."""
    fr = 0.012
    v = with_aero(vehicle, drag_area_m2=SEDAN_CDA_M2, tire__rolling_resistance=fr)
    t, u = coast(v, SPEED_MPS, 60.0)
    a = fr * v.chassis.mass_kg * GRAVITY_MPS2 / m_eff(v)
    b = 0.5 * AIR_DENSITY_KGPM3 * SEDAN_CDA_M2 / m_eff(v)
    want = math.sqrt(a / b) * np.tan(math.atan(SPEED_MPS * math.sqrt(b / a))
                                     - math.sqrt(a * b) * t)
    assert want[-1] < 0.5 * SPEED_MPS
    np.testing.assert_allclose(u, want, rtol=1e-3)


# ------------------------------------------------------------------------ loads and forces
def _rhs(v: Vehicle, x: np.ndarray, u: np.ndarray | None = None) -> tuple[np.ndarray, Any]:
    p = eightdof.params_for(v)
    u = np.zeros(eightdof.N_INPUT) if u is None else u
    dx = np.zeros(eightdof.N_STATE)
    aux = np.zeros(eightdof.N_AUX)
    eightdof.kernels_for(p.tire_name).rhs(x, u, p.arr, p.coeffs_front, p.coeffs_rear, dx, aux)
    return dx, eightdof.aux_from_array(aux)


def test_lift_takes_the_hand_computed_load_off_each_axle(vehicle: Vehicle) -> None:
    """Front lift C_l,f A = 0.3 m^2 and rear downforce C_l,r A = -0.5 m^2 at 40 m/s, straight
    running, no drag: each front wheel carries 0.25 x 1.225 x 0.3 x 40^2 = 147.0 N less and
    each rear wheel 0.25 x 1.225 x 0.5 x 40^2 = 245.0 N more than without aero."""
    v = with_aero(vehicle, lift_area_front_m2=0.3, lift_area_rear_m2=-0.5)
    p = eightdof.params_for(v)
    x = eightdof.initial_state(p, 40.0)
    _, base = _rhs(vehicle, x)
    _, lifted = _rhs(v, x)
    np.testing.assert_allclose(lifted.fz_n - base.fz_n, [-147.0, -147.0, 245.0, 245.0],
                               rtol=1e-12)
    # the axles' sum: 0.5 rho (C_l,f + C_l,r) A U^2 = -196 N of load gained
    assert float(np.sum(lifted.fz_n - base.fz_n)) == pytest.approx(196.0, rel=1e-12)
    ref, ref_aux = eightdof.evaluate(0.0, x, np.zeros(eightdof.N_INPUT), p)
    np.testing.assert_allclose(ref_aux.fz_n, lifted.fz_n, rtol=1e-13)


def test_drag_decelerates_by_d_over_m_and_transfers_d_h_over_l(vehicle: Vehicle) -> None:
    """Free rolling (omega = U/R, no tire force) at 30 m/s: dU/dt = -D/m with
    D = 0.5 x 1.225 x 0.69 x 30^2 = 380.36 N; at the trim (lagged a_x = 0: a drive force D at
    the ground holds the speed) the drag at CG height lifts each front wheel by D h/(2L) and
    loads each rear one as much; coasting (a_x = -D/m) it transfers nothing."""
    v = with_aero(vehicle, drag_area_m2=SEDAN_CDA_M2)
    p = eightdof.params_for(v)
    x = eightdof.initial_state(p, SPEED_MPS)
    drag = 0.5 * 1.225 * SEDAN_CDA_M2 * SPEED_MPS ** 2
    assert drag == pytest.approx(380.3625)
    dx, aux = _rhs(v, x)
    assert dx[STATE.U] == pytest.approx(-drag / v.chassis.mass_kg, rel=1e-12)
    _, base = _rhs(vehicle, x)
    bd = v.body
    assert bd is not None
    shift = drag * bd.cg_height_m / (2.0 * v.chassis.wheelbase_m)
    np.testing.assert_allclose(aux.fz_n - base.fz_n, [-shift, -shift, shift, shift],
                               rtol=1e-9)
    x[STATE.AX_LT] = -drag / v.chassis.mass_kg
    _, coasting = _rhs(v, x)
    _, static = _rhs(vehicle, eightdof.initial_state(p, SPEED_MPS))
    np.testing.assert_allclose(coasting.fz_n, static.fz_n, rtol=1e-12)
    # reversing, the drag pushes forward (D = c U |U|)
    x = eightdof.initial_state(p, -10.0)
    dx, _ = _rhs(v, x)
    assert dx[STATE.U] == pytest.approx(0.5 * 1.225 * SEDAN_CDA_M2 * 100.0
                                        / v.chassis.mass_kg, rel=1e-12)


def test_compiled_kernel_with_aero_matches_numpy_reference(vehicle: Vehicle) -> None:
    """The compiled right-hand side with drag, lift and downforce equals ``evaluate``."""
    v = with_aero(vehicle, drag_area_m2=0.8, lift_area_front_m2=0.4, lift_area_rear_m2=-1.2,
                  air_density_kgpm3=1.1, tire__rolling_resistance=0.015)
    p = eightdof.params_for(v)
    rng = np.random.default_rng(23)
    worst = 0.0
    for _ in range(200):
        x = np.zeros(eightdof.N_STATE)
        x[STATE.U] = rng.uniform(-5.0, 60.0)
        x[STATE.V] = rng.uniform(-2.0, 2.0)
        x[STATE.R] = rng.uniform(-0.6, 0.6)
        x[STATE.PHI] = rng.uniform(-0.06, 0.06)
        x[STATE.P] = rng.uniform(-0.3, 0.3)
        x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1] = x[STATE.U] / 0.29 * rng.uniform(0.6, 1.3, 4)
        x[STATE.AX_LT:STATE.AY_LT + 1] = rng.uniform(-6.0, 6.0, 2)
        x[STATE.ALPHA_FL:STATE.ALPHA_RR + 1] = rng.uniform(-0.1, 0.1, 4)
        u = np.zeros(eightdof.N_INPUT)
        u[INPUT.DELTA_F] = rng.uniform(-0.1, 0.1)
        u[INPUT.DRIVE_FL:INPUT.DRIVE_RR + 1] = rng.uniform(-300.0, 300.0, 4)
        u[INPUT.BRAKE_FL:INPUT.BRAKE_RR + 1] = rng.uniform(0.0, 1500.0, 4)
        ref, ref_aux = eightdof.evaluate(0.0, x, u, p)
        dx, aux = _rhs(v, x, u)
        worst = max(worst, float(np.max(np.abs(dx - ref) / (1.0 + np.abs(ref)))))
        np.testing.assert_allclose(aux.fz_n, ref_aux.fz_n, rtol=1e-12, atol=1e-9)
    assert worst < 1e-12


# ------------------------------------------------------------------------ defaults
def test_an_aero_block_of_zeros_is_the_model_without_aero_bit_for_bit(vehicle: Vehicle) -> None:
    """Drag and lift 0 (the block given, all zero): a step steer with braking at the end
    gives the states of the vehicle without ``aero`` to the last bit."""
    runs = []
    for v in (vehicle, with_aero(vehicle, drag_area_m2=0.0)):
        sim = Simulator(v)
        sim.reset(speed_mps=SPEED_MPS)
        sim.step(Inputs(front_wheel_angle_rad=0.02, drive_torque_nm=(0.0, 0.0, 150.0, 150.0)),
                 1500)
        sim.step(Inputs(front_wheel_angle_rad=0.02, brake_torque_nm=(900.0,) * 4), 1500)
        runs.append(sim.state.tobytes())
    assert runs[0] == runs[1]


# ------------------------------------------------------------------------ the loops
def _aero_study_config(tmp_path: Path, vehicle: Vehicle) -> Any:
    vfile = tmp_path / "aero_car.yaml"
    d = with_aero(vehicle, drag_area_m2=SEDAN_CDA_M2, lift_area_front_m2=0.2,
                  lift_area_rear_m2=-0.3).to_dict()
    d["name"] = "aero_car"
    vfile.write_text(yaml.safe_dump(d, sort_keys=False))
    step = {"name": "step_3s", "type": "step_steer", "initial_speed_mps": 33.0,
            "duration_s": 3.0, "amplitude_rad": 0.02, "start_s": 0.5, "ramp_time_s": 0.1}
    study = {"name": "aero", "scenario": {"name": "aero", "vehicle": str(vfile),
                                          "maneuver": step, "laws": ["sol1"], "model": "8dof"},
             "grid": {"belief.cornering_stiffness_scale": [0.7]}}
    path = tmp_path / "aero_study.yaml"
    path.write_text(yaml.safe_dump(study, sort_keys=False))
    (point,) = load_study(path).points()
    return load_study(path).config(point)


def test_study_loop_with_aero_equals_the_twin_bit_for_bit(tmp_path: Path,
                                                          vehicle: Vehicle) -> None:
    """The study's compiled loop (scalar kernel and the lane block) takes drag and lift from
    the same equations and the speed-hold driver's drag feed-forward from the same function
    as the offline twin: every recorded channel to the last bit; the driver holds the speed
    against 0.5 x 1.225 x 0.69 x 33^2 = 460 N of drag (its drive torque grows by about
    D R = 133 N m)."""
    config = _aero_study_config(tmp_path, vehicle)
    single, block, twin, _ = compiled_and_twin(config)
    for name in ("speed_mps", "yaw_rate_radps", "lateral_accel_mps2", "roll_rad"):
        assert single.channels[name].tobytes() == twin[name].tobytes(), name
        assert block.channels[name].tobytes() == twin[name].tobytes(), name
    drive = single.channels["drive_torque_total_nm"]
    drag = 0.5 * 1.225 * SEDAN_CDA_M2 * 33.0 ** 2
    bd = vehicle.body
    assert bd is not None
    assert drive[0] == pytest.approx(drag * bd.wheel_radius_m, rel=1e-6)  # at the target
    assert abs(float(twin["speed_mps"][-1]) - 33.0) < 0.3
