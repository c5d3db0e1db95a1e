# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Driveline of the 8-DOF model (``driveline:`` in the vehicle file): driven axles, torque
split and open, locked or limited-slip differentials.

Sources of the numbers asserted here:

* hand computations written in the tests: the locking torque T_lock = c_v dw + k_b |T| s / 2
  (k_b = (TBR - 1)/(TBR + 1)) of each differential at a given wheel speed difference, the
  torques it leaves each wheel, and the yaw moment those torques exert through the tires at
  steady spin, (T_r/2)(T_RR - T_RL)/R;
* the wheel spin equation (eqs. 8.5-8.8): with no brake and no rolling resistance,
  I_w domega/dt = T - R F_x for each wheel, so the compiled right-hand side's spin
  accelerations give back the torques the differential delivered;
* the NumPy reference ``eightdof.evaluate`` (the test oracle) against the compiled kernels;
* the model without ``driveline``: a block naming today's routing (rear drive, open
  differentials) gives its trajectory bit for bit.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from compiled_twin import compiled_and_twin

from fourws_sim.drivers import SpeedHoldDriver, SpeedHoldSpec, drive_fractions
from fourws_sim.errors import ParameterError
from fourws_sim.models import eightdof
from fourws_sim.models.eightdof import INPUT, STATE
from fourws_sim.params import Vehicle, load_vehicle, vehicle_from_mapping
from fourws_sim.simulator import Inputs, Simulator
from fourws_study.spec import load_study

SPEED_MPS = 20.0
#: Rear-left wheel spinning faster than the rear-right one by this much, rad/s (the unloaded
#: inner wheel of a left turn under drive).
DW_RADPS = 2.0
#: Drive torque on each rear wheel from the open split, N m (800 N m on the axle).
HALF_NM = 400.0


@pytest.fixture(scope="module")
def vehicle() -> Vehicle:
    return load_vehicle("table_8_1")


def with_driveline(v: Vehicle, **driveline: Any) -> Vehicle:
    d = v.to_dict()
    d["driveline"] = dict(driveline)
    return vehicle_from_mapping(d, "driveline variant")


def delivered(v: Vehicle) -> tuple[np.ndarray, np.ndarray, Any]:
    """Wheel torques the rear differential delivers at straight running at 20 m/s with the
    rear-left wheel DW_RADPS faster than the rear-right one and HALF_NM on each rear wheel:
    (from aux, from the spin equation I_w domega/dt + R F_x, the oracle's aux)."""
    p = eightdof.params_for(v)
    x = eightdof.initial_state(p, SPEED_MPS)
    x[STATE.OMEGA_RL] += 0.5 * DW_RADPS
    x[STATE.OMEGA_RR] -= 0.5 * DW_RADPS
    u = np.zeros(eightdof.N_INPUT)
    u[INPUT.DRIVE_RL] = u[INPUT.DRIVE_RR] = HALF_NM
    dx = np.zeros(eightdof.N_STATE)
    aux = np.zeros(eightdof.N_AUX)
    eightdof.kernels_for(p.tire_name).rhs(x, u, p.arr, p.coeffs_front, p.coeffs_rear, dx, aux)
    got = eightdof.aux_from_array(aux)
    bd = v.body
    assert bd is not None
    spin = (bd.wheel_spin_inertia_kgm2 * dx[STATE.OMEGA_FL:STATE.OMEGA_RR + 1]
            + bd.wheel_radius_m * got.fx_n)
    _, ref = eightdof.evaluate(0.0, x, u, p)
    return got.drive_nm, spin, ref


def yaw_moment_nm(v: Vehicle, drive: np.ndarray) -> float:
    """Yaw moment (N m, positive left) of the rear wheels' drive forces T/R at steady spin."""
    bd = v.body
    assert bd is not None
    return 0.5 * bd.track_rear_m * (drive[3] - drive[2]) / bd.wheel_radius_m


@pytest.mark.parametrize("driveline, lock_nm", [
    ({}, 0.0),  # open: equal torques
    ({"differential_rear": "limited_slip", "viscous_coupling_rear_nms_per_rad": 50.0},
     50.0 * DW_RADPS),  # c_v dw = 100 N m
    # TBR 3: k_b = 0.5, dw beyond the 0.5 rad/s band: 0.5 x 0.5 x 800 = 200 N m, the slower
    # wheel gets 600 = 3 x 200 N m
    ({"differential_rear": "limited_slip", "torque_bias_ratio_rear": 3.0}, 200.0),
    # locked: c_v = I_w / (2 x 1 ms) = 2.0337 / 0.002 = 1016.85 N m s/rad, x 2 rad/s
    ({"differential_rear": "locked"}, 2.0337 / 0.002 * DW_RADPS),
])
def test_differential_torques_and_yaw_moment_by_hand(vehicle: Vehicle, driveline: dict,
                                                     lock_nm: float) -> None:
    """At 2 rad/s of rear wheel speed difference (left faster) and 800 N m on the axle: the
    open differential gives both wheels 400 N m and no yaw moment; a limited-slip or locked
    one moves T_lock to the slower right wheel, a yaw moment (1.41/2) 2 T_lock / 0.29 to the
    left (into a left turn)."""
    v = with_driveline(vehicle, **driveline)
    drive, spin, ref = delivered(v)
    want = np.array([0.0, 0.0, HALF_NM - lock_nm, HALF_NM + lock_nm])
    np.testing.assert_allclose(drive, want, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(spin, want, rtol=1e-9, atol=1e-6)  # the spin equation's
    np.testing.assert_allclose(ref.drive_nm, want, rtol=1e-12, atol=1e-9)
    moment = yaw_moment_nm(v, drive)
    assert moment == pytest.approx(0.5 * 1.41 * 2.0 * lock_nm / 0.29, rel=1e-12, abs=1e-9)
    assert moment >= 0.0


def test_ordering_open_limited_slip_locked(vehicle: Vehicle) -> None:
    """Sign and size: open 0 < viscous 486 N m < locked 9888 N m of yaw moment here."""
    moments = [yaw_moment_nm(v, delivered(v)[0]) for v in (
        vehicle,
        with_driveline(vehicle, differential_rear="limited_slip",
                       viscous_coupling_rear_nms_per_rad=50.0),
        with_driveline(vehicle, differential_rear="locked"))]
    assert moments[0] == 0.0
    assert moments[1] == pytest.approx(0.5 * 1.41 * 200.0 / 0.29)  # 486.2 N m
    assert moments[2] == pytest.approx(0.5 * 1.41 * 2.0 * 2033.7 / 0.29, rel=1e-4)
    assert moments[0] < moments[1] < moments[2]


def test_locked_differential_holds_the_wheels_together(vehicle: Vehicle) -> None:
    """Coasting at 20 m/s with 2 rad/s between the rear wheels: after 10 ms (ten time
    constants of the lock, e^-10 = 4.5e-5; RK4 at 1 ms damps the 1000/s mode by 0.375 a
    step, 0.375^10 = 5.5e-5) the locked axle keeps less than 1e-4 of the difference, the
    open axle, whose wheels only the tires pull together, far more."""
    left = {}
    for name, v in (("open", vehicle), ("locked", with_driveline(
            vehicle, differential_rear="locked"))):
        sim = Simulator(v)
        sim.reset(speed_mps=SPEED_MPS)
        x = sim.state.copy()
        x[STATE.OMEGA_RL] += 0.5 * DW_RADPS
        x[STATE.OMEGA_RR] -= 0.5 * DW_RADPS
        sim.state = x
        sim.step(Inputs(), 10)
        left[name] = abs(sim.state[STATE.OMEGA_RL] - sim.state[STATE.OMEGA_RR])
    assert left["locked"] < 1e-4 * DW_RADPS
    assert left["open"] > 10.0 * left["locked"]


def test_compiled_kernel_with_differentials_matches_numpy_reference(vehicle: Vehicle) -> None:
    v = with_driveline(vehicle, drive="all", front_torque_fraction=0.4,
                       differential_front="limited_slip", torque_bias_ratio_front=2.5,
                       viscous_coupling_front_nms_per_rad=20.0, differential_rear="locked")
    p = eightdof.params_for(v)
    k = eightdof.kernels_for(p.tire_name)
    rng = np.random.default_rng(31)
    dx = np.zeros(eightdof.N_STATE)
    aux = np.zeros(eightdof.N_AUX)
    worst = 0.0
    for _ in range(200):
        x = eightdof.initial_state(p, rng.uniform(2.0, 40.0))
        x[STATE.V] = rng.uniform(-1.0, 1.0)
        x[STATE.R] = rng.uniform(-0.4, 0.4)
        x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1] *= rng.uniform(0.8, 1.2, 4)
        u = np.zeros(eightdof.N_INPUT)
        u[INPUT.DELTA_F] = rng.uniform(-0.05, 0.05)
        u[INPUT.DRIVE_FL:INPUT.DRIVE_RR + 1] = rng.uniform(0.0, 600.0, 4)
        ref, ref_aux = eightdof.evaluate(0.0, x, u, p)
        k.rhs(x, u, p.arr, p.coeffs_front, p.coeffs_rear, dx, aux)
        worst = max(worst, float(np.max(np.abs(dx - ref) / (1.0 + np.abs(ref)))))
        got = eightdof.aux_from_array(aux)
        np.testing.assert_allclose(got.drive_nm, ref_aux.drive_nm, rtol=1e-12, atol=1e-9)
        assert got.slip_rate_per_s == pytest.approx(ref_aux.slip_rate_per_s, rel=1e-12)
    assert worst < 1e-12


# ------------------------------------------------------------------------ split and defaults
def test_speed_hold_driver_drives_through_the_driveline_split(vehicle: Vehicle) -> None:
    """All-wheel drive with 40 % front: FL, FR get 0.2 T and RL, RR 0.3 T of the driver's
    total torque; without a driveline the maneuver's driven axle decides (rear: T/2 each,
    all: T/4 each), as before."""
    awd = with_driveline(vehicle, drive="all", front_torque_fraction=0.4)
    assert drive_fractions("rear", awd) == pytest.approx((0.2, 0.2, 0.3, 0.3))
    assert drive_fractions("rear", vehicle) == (0.0, 0.0, 0.5, 0.5)
    assert drive_fractions("all", vehicle) == (0.25, 0.25, 0.25, 0.25)
    assert drive_fractions("front", with_driveline(vehicle, drive="front")) == (
        0.5, 0.5, 0.0, 0.0)
    driver = SpeedHoldDriver(SpeedHoldSpec(), awd)
    driver.command(0.0, 20.0, 20.0)
    drive, brake = driver.command(0.1, 19.0, 20.0)
    total = sum(drive)
    assert total > 0.0 and brake == (0.0, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(np.array(drive) / total, [0.2, 0.2, 0.3, 0.3], rtol=1e-12)


def test_todays_routing_as_a_driveline_block_is_bit_identical(vehicle: Vehicle) -> None:
    """``drive: rear`` with open differentials (the block spelling out the default) gives a
    step steer under drive the states of the vehicle without the block, to the last bit."""
    runs = []
    for v in (vehicle, with_driveline(vehicle, drive="rear", differential_rear="open")):
        sim = Simulator(v)
        sim.reset(speed_mps=SPEED_MPS)
        sim.step(Inputs(front_wheel_angle_rad=0.03, drive_torque_nm=(0.0, 0.0, 300.0, 300.0)),
                 2000)
        runs.append(sim.state.tobytes())
    assert runs[0] == runs[1]


@pytest.mark.parametrize("driveline, field", [
    ({"drive": "middle"}, "driveline.drive"),
    ({"differential_rear": "spool"}, "driveline.differential_rear"),
    ({"viscous_coupling_front_nms_per_rad": 10.0}, "driveline.differential_front"),
    ({"differential_rear": "limited_slip", "torque_bias_ratio_rear": 0.5},
     "driveline.torque_bias_ratio_rear"),
])
def test_bad_driveline_names_the_field(vehicle: Vehicle, driveline: dict, field: str) -> None:
    with pytest.raises(ParameterError) as err:
        with_driveline(vehicle, **driveline)
    assert field in str(err.value)


def test_study_loop_with_a_driveline_equals_the_twin_bit_for_bit(tmp_path: Path,
                                                                 vehicle: Vehicle) -> None:
    """All-wheel drive 40/60 with a limited-slip front (viscous) and rear (TBR 2)
    differential through a sine at 90 km/h: the study's compiled loop (scalar kernel and
    the lane block) gives the offline twin's channels to the last bit, its driver the twin's
    split (front 40 % of the total at every tick)."""
    d = with_driveline(vehicle, drive="all", front_torque_fraction=0.4,
                       differential_front="limited_slip",
                       viscous_coupling_front_nms_per_rad=30.0,
                       differential_rear="limited_slip", torque_bias_ratio_rear=2.0).to_dict()
    d["name"] = "awd_car"
    vfile = tmp_path / "awd_car.yaml"
    vfile.write_text(yaml.safe_dump(d, sort_keys=False))
    sine = {"name": "sine_2s", "type": "sine", "initial_speed_mps": 25.0, "duration_s": 2.0,
            "amplitude_rad": 0.03, "frequency_hz": 1.0, "start_s": 0.3}
    study = {"name": "awd", "scenario": {"name": "awd", "vehicle": str(vfile),
                                         "maneuver": sine, "laws": ["sol1"], "model": "8dof"},
             "grid": {"belief.cornering_stiffness_scale": [0.7]}}
    path = tmp_path / "awd_study.yaml"
    path.write_text(yaml.safe_dump(study, sort_keys=False))
    spec = load_study(path)
    (point,) = spec.points()
    config = spec.config(point)
    single, block, twin, _ = compiled_and_twin(config)
    for name in ("speed_mps", "yaw_rate_radps", "lateral_accel_mps2", "roll_rad"):
        assert single.channels[name].tobytes() == twin[name].tobytes(), name
        assert block.channels[name].tobytes() == twin[name].tobytes(), name
    torques = twin.driver["drive_torque_nm"]
    total = torques.sum(axis=1)
    driving = total > 1.0
    assert np.count_nonzero(driving) > 10
    np.testing.assert_allclose((torques[driving, 0] + torques[driving, 1]) / total[driving],
                               0.4, rtol=1e-12)
