# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Tests of the TMeasy tire (``fourws_sim/tires/tmeasy.py``).

Sources of the asserted numbers:

* hand computations of the published TMeasy formulas (Hirschberg, Rill, Weinfurter, VSD 45
  Suppl. 1, 2007; Rill, *Road Vehicle Dynamics*, 2012), written out step by step in the tests
  with the values of Chrono::Vehicle's HMMWV TMeasy file (the module's defaults,
  ``test/data/tmeasy/chrono_hmmwv_tmeasy.json``);
* the defining properties of the characteristic: ``F(s_M) = F_M`` is its maximum,
  ``F = F_S`` from ``s_S`` on, slope ``dF0`` at zero slip, no force without slip;
* mirror symmetry of combined slip;
* LFDM's own C++ TMeasy code, run to steady state at 462 slip points
  (``test/data/tmeasy/lfdm_sedan_steady_curves.csv``, its header says how): within 1 %;
* the 8-DOF's compiled variant against the Python tire function at the kernel's own slips.
"""

from __future__ import annotations

import csv
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from fourws_sim.errors import ParameterError
from fourws_sim.params import load_vehicle, vehicle_from_mapping
from fourws_sim.tires import cornering_stiffness, tmeasy as tm

DATA = Path(__file__).with_name("data") / "tmeasy"
CHRONO = DATA / "chrono_hmmwv_tmeasy.json"
LFDM = DATA / "lfdm_sedan_tmeasy.json"
PN = 7600.0  # the Chrono file's nominal load, N

BASE_VEHICLE = {
    "name": "tmeasy_test",
    "chassis": {"mass_kg": 1298.9, "yaw_inertia_kgm2": 1627.0, "cg_to_front_axle_m": 1.0,
                "cg_to_rear_axle_m": 1.45},
    "axle_tires": {"cornering_stiffness_front_n_per_rad": 65100.0,
                   "cornering_stiffness_rear_n_per_rad": 54100.0},
}


@pytest.fixture(scope="module")
def coeffs() -> np.ndarray:
    return tm.pack_mapping(tm.read_json(CHRONO))


def test_chrono_file_reads_to_the_defaults_and_lfdm_file_has_no_trail() -> None:
    chrono = tm.read_json(CHRONO)  # the file has // comments (Chrono's reader allows them)
    assert chrono["nominal_load_n"] == 7600.0 and chrono["maximum_load_n"] == 26600.0
    assert chrono["dfy0_p2n_n"] == 102058.29431565656 and chrono["syntoe_pn"] == \
        0.6792276290602397
    assert np.array_equal(tm.pack_mapping(chrono), tm.pack_mapping({}))
    lfdm = tm.read_json(LFDM)
    assert (lfdm["nominal_load_n"], lfdm["fym_p2n_n"], lfdm["vertical_stiffness_p2n_n_per_m"]) \
        == (8562.8266, 12509.947, 411121.0)
    c = tm.pack_mapping(lfdm)
    assert tm.forces(8000.0, 0.1, 0.05, 20.0, 1.0, c)[2] == 0.0  # LFDM has no aligning torque


def test_pure_lateral_point_by_hand(coeffs: np.ndarray) -> None:
    """Fz = F_z^N, s_y = 0.1 (alpha = -atan 0.1), free rolling."""
    dfx0, fxm, sxm = 157030.738840308, 6894.765328626913, 0.1337681868200464
    dfy0, fym, sym = 55087.49318774042, 5948.424247065884, 0.3794817785000966
    kx, ky = fxm / dfx0, fym / dfy0                                  # 0.043907, 0.107981
    hy = sym / (sxm + sym) + ky / (kx + ky)                          # 1.45030
    s = 0.1 / hy                                                     # generalized slip
    df0, fm, sm = dfy0 * hy, fym, sym / hy                           # phi = 90 deg
    sigma = s / sm                                                   # = s_y / s_y^M = 0.26352
    f = sm * df0 * sigma / (1.0 + sigma * (sigma + df0 * sm / fm - 2.0))
    assert f == pytest.approx(3751.3, abs=0.1)
    # trail: L = 2 sqrt(r0 Fz/c_z), w = s_y^0/s_y^E, t = s_y/s_y^0
    length = 2.0 * math.sqrt(0.464 * PN / 326332.4234)              # 0.20791 m
    sy0, sye = 0.3984558674251015, 0.6792276290602397
    w, t = sy0 / sye, 0.1 / sy0
    n_per_l = 0.13 * ((1 - w) * (1 - t) + w * (1 - (3 - 2 * t) * t * t))   # 0.10451
    fx, fy, mz = tm.forces(PN, -math.atan(0.1), 0.0, 20.0, 1.0, coeffs)
    assert fx == 0.0
    assert fy == pytest.approx(f, rel=1e-12)
    assert mz == pytest.approx(-length * n_per_l * f, rel=1e-12)
    assert mz == pytest.approx(-81.5, abs=0.1)


def test_combined_point_by_hand(coeffs: np.ndarray) -> None:
    """Fz = 1.5 F_z^N (quadratic and linear load interpolation), s_x = 0.05, s_y = 0.2."""
    x = 1.5

    def quad(y1: float, y2: float) -> float:
        return x * (2 * y1 - y2 / 2 - (y1 - y2 / 2) * x)

    def lin(y1: float, y2: float) -> float:
        return y1 + (y2 - y1) * (x - 1)

    dfx0 = quad(157030.738840308, 274685.069847482)
    fxm = quad(6894.765328626913, 11973.78061414796)
    fxs = quad(5692.145971941859, 10765.232472159529)
    sxm, sxs = lin(0.1337681868200464, 0.1634000724558567), lin(0.959999390695378,
                                                                0.9599349397154496)
    dfy0 = quad(55087.49318774042, 102058.29431565656)
    fym = quad(5948.424247065884, 11335.717829523435)
    fys = quad(5648.517057661229, 10693.243250366206)
    sym, sys = lin(0.3794817785000966, 0.3775168408962764), lin(0.925640996144482,
                                                                0.959833720945494)
    kx, ky = fxm / dfx0, fym / dfy0
    hx = sxm / (sxm + sym) + kx / (kx + ky)
    hy = sym / (sxm + sym) + ky / (kx + ky)
    assert hx + hy == pytest.approx(2.0)  # the two normalizing factors add up to 2
    sxn, syn = 0.05 / hx, 0.2 / hy
    s = math.hypot(sxn, syn)
    c, sn = sxn / s, syn / s
    df0 = math.hypot(dfx0 * hx * c, dfy0 * hy * sn)
    fm = math.hypot(fxm * c, fym * sn)
    sm = math.hypot(sxm / hx * c, sym / hy * sn)
    assert s < sm  # still below the maximum: the rational part
    sigma = s / sm
    f = sm * df0 * sigma / (1 + sigma * (sigma + df0 * sm / fm - 2))
    fx, fy, _ = tm.slip_forces(x * PN, 0.05, 0.2, 1.0, coeffs)
    assert (fx, fy) == pytest.approx((f * c, f * sn), rel=1e-12)
    del fxs, fys, sxs, sys
    # the fourws slips of that point: s_x = kappa/(1 + kappa), s_y = -tan(alpha)/(1 + kappa)
    kappa = 0.05 / 0.95
    alpha = -math.atan(0.2 * (1 + kappa))
    assert tm.forces(x * PN, alpha, kappa, 20.0, 1.0, coeffs)[:2] == pytest.approx(
        (fx, fy), rel=1e-12)


@pytest.mark.parametrize("fz", [0.5 * PN, PN, 2.0 * PN])
@pytest.mark.parametrize("axis", ["x", "y"])
def test_pure_slip_peak_at_sm_and_sliding_force_from_ss(coeffs: np.ndarray, fz: float,
                                                        axis: str) -> None:
    def force(s: float, mu: float = 1.0) -> float:
        out = tm.slip_forces(fz, s, 0.0, mu, coeffs) if axis == "x" else \
            tm.slip_forces(fz, 0.0, s, mu, coeffs)
        return out[0] if axis == "x" else out[1]

    fm, sm = tm.load_curve(coeffs, fz, f"f{axis}m"), tm.load_curve(coeffs, fz, f"s{axis}m")
    fs, ss = tm.load_curve(coeffs, fz, f"f{axis}s"), tm.load_curve(coeffs, fz, f"s{axis}s")
    assert force(sm) == pytest.approx(fm, rel=1e-12)
    grid = np.linspace(0.0, 2.0 * ss, 4001)
    values = np.array([force(float(s)) for s in grid])
    assert values.max() == pytest.approx(fm, rel=1e-6)
    assert abs(grid[values.argmax()] - sm) <= grid[1]
    assert np.all(values[grid >= ss] == pytest.approx(fs, rel=1e-12))
    assert np.all(np.diff(values[grid <= sm]) > 0.0)  # rises to the maximum
    assert np.all(np.diff(values[(grid >= sm) & (grid <= ss)]) <= 1e-9)  # then falls
    # friction 0.5: half the maximum at half the slip, the same initial slope
    assert force(0.5 * sm, 0.5) == pytest.approx(0.5 * fm, rel=1e-12)
    h = 1e-7
    assert force(h, 0.5) == pytest.approx(force(h, 1.0), rel=1e-5)


def test_zero_force_without_slip_or_load(coeffs: np.ndarray) -> None:
    for fz in (1e-6, 100.0, PN, 3.0 * PN, 5.0 * PN):
        for vx in (-5.0, 0.0, 20.0):
            assert tm.forces(fz, 0.0, 0.0, vx, 1.0, coeffs) == (0.0, 0.0, 0.0)
    assert tm.forces(0.0, 0.2, 0.1, 20.0, 1.0, coeffs) == (0.0, 0.0, 0.0)
    assert tm.forces(PN, 0.2, 0.1, 20.0, 0.0, coeffs) == (0.0, 0.0, 0.0)


def test_cornering_stiffness_is_the_lateral_initial_slope(coeffs: np.ndarray) -> None:
    # dF_y^0 at 1.5 F_z^N by the quadratic interpolation: 1.5 (2 Y1 - Y2/2 - (Y1 - Y2/2) 1.5)
    y1, y2 = 55087.49318774042, 102058.29431565656
    by_hand = 1.5 * (2 * y1 - y2 / 2 - (y1 - y2 / 2) * 1.5)
    assert by_hand == pytest.approx(79587.5, abs=0.1)
    h = 1e-7
    slope = -(tm.forces(1.5 * PN, h, 0.0, 20.0, 1.0, coeffs)[1]
              - tm.forces(1.5 * PN, -h, 0.0, 20.0, 1.0, coeffs)[1]) / (2 * h)
    assert slope == pytest.approx(by_hand, rel=1e-6)
    assert tm.cornering_stiffness_analytic(coeffs, 1.5 * PN) == pytest.approx(by_hand, rel=1e-12)
    assert cornering_stiffness("tmeasy", coeffs, 1.5 * PN) == pytest.approx(by_hand, rel=1e-4)
    # and dF_x^0 is the longitudinal slope (the 8-DOF's wheel-spin rate uses it)
    dfx0 = 1.5 * (2 * 157030.738840308 - 274685.069847482 / 2
                  - (157030.738840308 - 274685.069847482 / 2) * 1.5)
    fx = tm.forces(1.5 * PN, 0.0, h, 20.0, 1.0, coeffs)[0]
    assert fx / h == pytest.approx(dfx0, rel=1e-5)


def test_combined_slip_mirror_symmetry_and_loss(coeffs: np.ndarray) -> None:
    for fz in (0.7 * PN, 1.8 * PN):
        for alpha in np.radians([0.5, 3.0, 8.0, 20.0]):
            for kappa in (-0.3, -0.05, 0.0, 0.05, 0.3):
                fx, fy, mz = tm.forces(fz, float(alpha), kappa, 20.0, 1.0, coeffs)
                assert tm.forces(fz, -float(alpha), kappa, 20.0, 1.0, coeffs) == \
                    pytest.approx((fx, -fy, -mz), rel=1e-14, abs=1e-9)
                # the same slips mirrored in s_x
                gx, gy, _ = tm.slip_forces(fz, -kappa / (1 + kappa),
                                           -math.tan(alpha) / (1 + kappa), 1.0, coeffs)
                hx, hy, _ = tm.slip_forces(fz, kappa / (1 + kappa),
                                           -math.tan(alpha) / (1 + kappa), 1.0, coeffs)
                assert (gx, gy) == pytest.approx((-hx, hy), rel=1e-14, abs=1e-9)
            # longitudinal slip takes lateral force away, more with more slip
            side = [abs(tm.forces(fz, float(alpha), k, 20.0, 1.0, coeffs)[1])
                    for k in (0.0, 0.05, 0.1, 0.2, 0.4)]
            assert all(a > b for a, b in zip(side, side[1:]))


def test_locked_wheel_slides_against_its_velocity(coeffs: np.ndarray) -> None:
    """kappa = -1: the TMeasy slips are the slip velocity over the numerical rolling speed, so
    the generalized slip is far beyond s_S and the force is the sliding force F_S(phi)."""
    fx, fy, _ = tm.forces(PN, 0.0, -1.0, 20.0, 1.0, coeffs)
    assert (fx, fy) == pytest.approx((-5692.145971941859, 0.0))
    fx, fy, _ = tm.forces(PN, math.radians(10.0), -1.0, 20.0, 1.0, coeffs)
    assert fx < 0.0 and fy < 0.0  # against the sliding velocity (forward and to the left)


def test_lfdm_curves_within_one_percent() -> None:
    c = tm.pack_mapping(tm.read_json(LFDM))
    lines = [ln for ln in (DATA / "lfdm_sedan_steady_curves.csv").read_text().splitlines()
             if not ln.startswith("#")]
    rows = list(csv.DictReader(lines))
    assert len(rows) == 462
    worst = 0.0
    for r in rows:
        fz, sx, sy, fx_ref, fy_ref = (float(r[k]) for k in ("fz_n", "sx", "sy", "fx_n", "fy_n"))
        fx, fy, _ = tm.slip_forces(fz, sx, sy, 1.0, c)
        ref = math.hypot(fx_ref, fy_ref)
        if ref == 0.0:
            assert (fx, fy) == (0.0, 0.0)
            continue
        worst = max(worst, math.hypot(fx - fx_ref, fy - fy_ref) / ref)
    # LFDM adds 0.01 m/s to its rolling speeds (0.05 % at the 20 m/s of the run)
    assert worst < 0.01
    assert worst < 1e-3


def _tmeasy_vehicle_file(tmp_path: Path, block: dict) -> Path:
    data = dict(BASE_VEHICLE, tire={"model": "tmeasy", "tmeasy": block})
    path = tmp_path / "car.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_vehicle_file_loads_a_json_relative_to_it_and_reloads_without_it(tmp_path: Path) -> None:
    shutil.copy(LFDM, tmp_path / "tire.json")
    v = load_vehicle(_tmeasy_vehicle_file(tmp_path, {"json": "tire.json", "fym_pn_n": 7000.0}))
    assert v.tire.tmeasy["fym_pn_n"] == 7000.0  # the block's value over the file's
    assert v.tire.tmeasy["fym_p2n_n"] == 12509.947  # the file's
    assert v.tire.tmeasy["json"] == str(tmp_path / "tire.json")
    (tmp_path / "tire.json").unlink()
    again = vehicle_from_mapping(v.to_dict(), "record.yaml")  # complete: the file is not read
    assert np.array_equal(tm.pack(again, "rear"), tm.pack(v, "front"))


@pytest.mark.parametrize("block, field", [
    ({"json": "missing.json"}, "tire.tmeasy.json"),
    ({"sxs_pn": 0.1}, "tire.tmeasy.sxs_pn"),              # sliding slip below the peak slip
    ({"fys_p2n_n": 20000.0}, "tire.tmeasy.fys_p2n_n"),    # sliding force above the maximum
    ({"maximum_load_n": 5000.0}, "tire.tmeasy.maximum_load_n"),
    ({"vertical_stiffness_p2n_n_per_m": 1e6}, "tire.tmeasy.vertical_stiffness_p2n_n_per_m"),
    ({"fym_p2n_n": 30000.0, "fys_p2n_n": 10000.0}, "tire.tmeasy.fym_p2n_n"),  # FyM < 0 at 3.5 pn
    ({"dfy0_pn_n": 1e9}, "tire.tmeasy.dfy0_pn_n"),         # outside the plausibility bounds
    ({"cornering": 1.0}, "tire.tmeasy.cornering"),
])
def test_bad_block_is_one_error_naming_the_field(tmp_path: Path, block: dict,
                                                 field: str) -> None:
    with pytest.raises(ParameterError) as err:
        load_vehicle(_tmeasy_vehicle_file(tmp_path, block))
    assert err.value.field == field


def test_eightdof_runs_tmeasy_through_its_own_compiled_variant() -> None:
    """The 8-DOF picks the tire by name; its compiled variant's forces are the Python
    function's at the kernel's own slips and loads."""
    from fourws_sim.simulator import Inputs, Simulator  # numba: the 8-DOF kernels compile

    vehicle = load_vehicle("table_8_1")
    sim = Simulator(vehicle, tire="tmeasy")
    sim.reset(speed_mps=23.6)
    coeffs = tm.pack(vehicle, "front")
    steer = Inputs(math.radians(1.5), 0.0, 0.0, [0.0] * 4, [0.0] * 4)
    sim.step(steer, n_steps=1500)
    out = sim.outputs()
    mu = vehicle.tire.friction_coefficient
    for i in range(4):
        ref = tm.forces(out["normal_load_n"][i], out["slip_angle_rad"][i], out["slip_ratio"][i],
                        20.0, mu, coeffs)
        got = (out["fx_n"][i], out["fy_n"][i], out["mz_nm"][i])
        assert got == pytest.approx(ref, rel=1e-9)
    assert out["yaw_rate_radps"] > 0.1  # turning left at 1.5 deg
