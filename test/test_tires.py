# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Tests of the tire models (linear, STI of Appendix C, Magic Formula) and the tire curves.

Sources of the asserted numbers:

* analytic small-slip stiffness of each model (STI: ``C_a = A0 + A1 Fz - (A1/A2) Fz^2`` with
  Table C.1; MF: ``K_y = PKY1 FNOMIN sin(2 atan(Fz/(PKY2 FNOMIN)))``; linear: axle value / 2);
* the friction limit ``|F| <= mu mu_0 Fz`` (STI: ``mu_0 = B3 = 0.85`` of Table C.1; MF: the peak
  ``D_y = mu_y Fz``; linear: ``mu Fz``);
* symmetry ``Fy(-alpha) = -Fy(alpha)``; combined slip lowering the side force;
* the locked wheel (STI): the force opposes the sliding velocity, so
  ``Fy/Fz = mu_0 (1 - KMU) f sin(alpha)`` with ``f -> 1``;
* Figures C.1/C.2 (read from the OCR): y axes up to 0.8, Figure C.1 over slip angles up to
  20 deg (ticks read as tens of degrees). Read: the slip-ratio-0 curve levels off at about
  0.8 within the plotted range; tolerance +-0.05 on the peak (the tick spacing is 0.2, a
  quarter of it), and the slip angle of the peak inside the plotted 5-20 deg. Figure C.2 starts
  (s = 0) at the same flat-top value for alpha = 10 and 20 deg.
"""

from __future__ import annotations

import math
from pathlib import Path

import numba
import numpy as np
import pytest
from numpy.testing import assert_allclose

from fourws_sim.errors import ParameterError, UnknownNameError
from fourws_sim.params import GRAVITY_MPS2, load_vehicle, vehicle_from_mapping
from fourws_sim.tires import TIRES, cornering_stiffness, get_tire, linear, magic_formula, sti

DEG = math.pi / 180.0
ALPHAS = np.radians(np.linspace(-90.0, 90.0, 37))
KAPPAS = np.array([-1.0, -0.6, -0.2, -0.05, -1e-4, 0.0, 1e-4, 0.05, 0.2, 0.6, 1.0, 3.0])
SPEEDS = (0.0, 1e-9, 25.0)
LOADS = (1e-6, 500.0, 4000.0, 12000.0)

BASE_VEHICLE = {
    "name": "tire_test",
    "chassis": {"mass_kg": 1298.9, "yaw_inertia_kgm2": 1627.0, "cg_to_front_axle_m": 1.0,
                "cg_to_rear_axle_m": 1.45},
    "axle_tires": {"cornering_stiffness_front_n_per_rad": 65100.0,
                   "cornering_stiffness_rear_n_per_rad": 54100.0},
}


def _vehicle(tire: dict | None = None, source: str = "tire_test.yaml"):
    data = dict(BASE_VEHICLE)
    if tire is not None:
        data["tire"] = tire
    return vehicle_from_mapping(data, source)


def _coeffs(name: str) -> np.ndarray:
    return get_tire(name).pack(_vehicle({"model": name}), "front")


# ---------------------------------------------------------------- registry


def test_registry_names_and_unknown_name() -> None:
    assert set(TIRES) == {"linear", "sti", "magic_formula", "tmeasy"}
    with pytest.raises(UnknownNameError) as err:
        get_tire("pacejka89")
    assert isinstance(err.value, ValueError)
    for name in TIRES:
        assert name in str(err.value)


@pytest.mark.parametrize("name", list(TIRES))
def test_numba_compiles_and_matches_python(name: str) -> None:
    module = get_tire(name)
    coeffs = _coeffs(name)
    jitted = numba.njit(module.forces)
    for fz in LOADS + (0.0, -50.0):
        for a in ALPHAS[::3]:
            for k in KAPPAS[::2]:
                ref = module.forces(fz, float(a), float(k), 25.0, 0.8, coeffs)
                got = jitted(fz, float(a), float(k), 25.0, 0.8, coeffs)
                assert_allclose(got, ref, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("name", list(TIRES))
def test_robust_no_nan_and_zero_without_load(name: str) -> None:
    module = get_tire(name)
    coeffs = _coeffs(name)
    for fz in (0.0, -100.0):
        assert module.forces(fz, 0.1, -0.5, 20.0, 1.0, coeffs) == (0.0, 0.0, 0.0)
    for fz in LOADS:
        for vx in SPEEDS:
            for a in ALPHAS:
                for k in KAPPAS:
                    out = module.forces(fz, float(a), float(k), vx, 1.0, coeffs)
                    assert all(math.isfinite(v) for v in out), (fz, vx, a, k, out)


@pytest.mark.parametrize("name", list(TIRES))
def test_cornering_stiffness_matches_analytic(name: str) -> None:
    module = get_tire(name)
    coeffs = _coeffs(name)
    # TMeasy's characteristic bends at zero slip already (F = dF0 s (1 - p s/s_M + ...) in
    # |s|, p = dF0 s_M/F_M - 2), so the central difference of step h = 1e-5 is off by about
    # p h/s_M, 4e-5 at 1500 N; the others are smooth there
    rtol = 1e-4 if name == "tmeasy" else 1e-5
    for fz in (1500.0, 3769.4, 4448.2, 6000.0):
        assert_allclose(cornering_stiffness(name, coeffs, fz),
                        module.cornering_stiffness_analytic(coeffs, fz), rtol=rtol)


# ---------------------------------------------------------------- linear


def test_linear_slope_is_half_the_axle_value() -> None:
    v = _vehicle()
    front = linear.pack(v, "front")
    rear = linear.pack(v, "rear")
    assert_allclose(cornering_stiffness("linear", front, 3000.0), 65100.0 / 2, rtol=1e-9)
    assert_allclose(cornering_stiffness("linear", rear, 3000.0), 54100.0 / 2, rtol=1e-9)
    # documented default C_s = 1.5 C_alpha per tire; an explicit value is used as given
    fx, _, _ = linear.forces(3000.0, 0.0, 0.01, 20.0, 1.0, front)
    assert_allclose(fx, linear.DEFAULT_CS_PER_CALPHA * 65100.0 / 2 * 0.01, rtol=1e-12)
    own = linear.pack(_vehicle({"longitudinal_stiffness_n": 80000.0}), "front")
    assert_allclose(linear.forces(3000.0, 0.0, 0.01, 20.0, 1.0, own)[0], 800.0, rtol=1e-12)


def test_linear_saturates_on_friction_circle() -> None:
    v = _vehicle()
    c = linear.pack(v, "front")
    fz, mu = 3000.0, 0.7
    for a, k in ((0.3, 0.0), (0.2, -0.3), (-0.5, 0.4)):
        fx, fy, _ = linear.forces(fz, a, k, 20.0, mu, c)
        assert_allclose(math.hypot(fx, fy), mu * fz, rtol=1e-12)
        # direction kept: same ratio as the unsaturated force
        ux, uy, _ = linear.forces(fz, a, k, 20.0, mu, linear.pack(v, "front", saturate=False))
        assert_allclose(fx * uy, fy * ux, rtol=1e-9, atol=1e-6)
    # below the limit it is purely linear
    assert_allclose(linear.forces(fz, 0.01, 0.0, 20.0, mu, c)[1], -65100.0 / 2 * 0.01)
    with pytest.raises(ParameterError, match="axle"):
        linear.pack(v, "middle")


# ---------------------------------------------------------------- STI


def _sti_ca_lb(fz_lb: float) -> float:
    """Table C.1 lateral stiffness parabola, written out independently of sti.py."""
    a0, a1, a2 = 733.0, 19.5, 2900.0
    return a0 + a1 * fz_lb - a1 / a2 * fz_lb ** 2


def test_sti_cornering_stiffness_is_table_c1_parabola() -> None:
    c = sti.pack_mapping({})
    for fz_lb in (300.0, 584.4, 847.4, 1000.0, 1400.0):
        fz_n = fz_lb * sti.N_PER_LBF
        assert_allclose(cornering_stiffness("sti", c, fz_n), _sti_ca_lb(fz_lb) * sti.N_PER_LBF,
                        rtol=1e-5)


def test_sti_longitudinal_slope_and_aligning_trail() -> None:
    c = sti.pack_mapping({})
    fz_lb = 1000.0
    fz = fz_lb * sti.N_PER_LBF
    h = 1e-6
    slope = (sti.forces(fz, 0.0, h, 20.0, 1.0, c)[0]
             - sti.forces(fz, 0.0, -h, 20.0, 1.0, c)[0]) / (2 * h)
    assert_allclose(slope, 6.0 * fz, rtol=1e-4)  # CS/FZ * Fz of Table C.1, N per unit slip
    # small-slip trail = a_p0/4, a_p0 = 0.0768 sqrt(Fz FZT)/(TW (TP + 5)) ft  (C.1)
    _, fy, mz = sti.forces(fz, 1e-5, 0.0, 20.0, 1.0, c)
    ap0_m = 0.0768 * math.sqrt(fz_lb * 1000.0) / (6.5 * 35.0) * 0.3048
    assert fy < 0.0 < mz
    assert_allclose(-mz / fy, ap0_m / 4.0, rtol=1e-3)


def test_sti_symmetry() -> None:
    c = sti.pack_mapping({})
    for fz in (2000.0, 4448.0):
        for a in np.radians([0.5, 3.0, 10.0, 30.0, 89.0]):
            for k in (-1.0, -0.3, 0.0, 0.2):
                fx1, fy1, mz1 = sti.forces(fz, a, k, 20.0, 1.0, c)
                fx2, fy2, mz2 = sti.forces(fz, -a, k, 20.0, 1.0, c)
                assert_allclose((fx2, fy2, mz2), (fx1, -fy1, -mz1), rtol=1e-12, atol=1e-9)


def test_sti_combined_slip_lowers_side_force_monotonically() -> None:
    c = sti.pack_mapping({})
    fz = 4448.0
    slips = np.linspace(0.0, 1.0, 101)
    for a_deg in (1.0, 4.0, 10.0, 20.0):
        for sign in (-1.0, 1.0):
            fy = np.array([abs(sti.forces(fz, a_deg * DEG, sign * s, 20.0, 1.0, c)[1])
                           for s in slips])
            assert np.all(np.diff(fy) <= 1e-9 * fy[0]), (a_deg, sign)
            assert fy[-1] < 0.5 * fy[0]


@pytest.mark.parametrize("mu", [1.0, 0.4])
def test_sti_force_within_friction_circle(mu: float) -> None:
    c = sti.pack_mapping({})
    mu0 = 0.85  # B3 of Table C.1 (B1 = B4 = 0)
    worst = 0.0
    for fz in (500.0, 2500.0, 4448.0, 8000.0):
        for a in np.radians(np.linspace(-90, 90, 73)):
            for k in np.linspace(-1.0, 1.0, 41):
                fx, fy, _ = sti.forces(fz, float(a), float(k), 20.0, mu, c)
                worst = max(worst, math.hypot(fx, fy) / (mu * mu0 * fz))
    assert worst <= 1.01
    assert worst > 0.95  # the limit is actually reached (the bound is not vacuous)


def test_sti_locked_wheel_force_opposes_sliding() -> None:
    c = sti.pack_mapping({})
    fz = 4448.0
    mu0, kmu = 0.85, sti.TABLE_C1["kmu"]
    for a_deg in (5.0, 10.0, 20.0):
        fx, fy, _ = sti.forces(fz, a_deg * DEG, -1.0, 20.0, 1.0, c)
        assert_allclose(-fy / fz, mu0 * (1 - kmu) * math.sin(a_deg * DEG), rtol=0.02)
        assert_allclose(-fx / fz, mu0 * (1 - kmu) * math.cos(a_deg * DEG), rtol=0.02)


def test_sti_mu_scales_friction() -> None:
    c = sti.pack_mapping({})
    fz = 4448.0
    for mu in (0.3, 0.6):
        locked = sti.forces(fz, 0.0, -1.0, 20.0, mu, c)[0]
        assert_allclose(locked / sti.forces(fz, 0.0, -1.0, 20.0, 1.0, c)[0], mu, rtol=0.02)


def test_sti_curves_match_figures_c1_c2() -> None:
    from fourws_analysis.tire_curves import tire_curves

    curves = tire_curves(load_vehicle("table_8_1"), tire_model="sti")
    assert_allclose(curves.fz_n, 1000.0 * sti.N_PER_LBF)  # FZT, the Table C.1 design load
    s0, s01, s02 = curves.vs_slip_angle
    assert 0.75 <= s0.peak <= 0.85
    assert 5.0 <= s0.x_at_peak <= 20.0
    # combined slip lowers the whole curve (Fig. C.1 ordering s = 0 > 0.1 > 0.2)
    assert np.all(s01.fy_over_fz[1:] < s0.fy_over_fz[1:])
    assert np.all(s02.fy_over_fz[1:] < s01.fy_over_fz[1:])
    a0, a10, a20 = curves.vs_slip_ratio
    assert np.all(a0.fy_over_fz == 0.0)
    assert abs(a10.fy_over_fz[0] - a20.fy_over_fz[0]) < 0.02
    assert 0.75 <= a10.fy_over_fz[0] <= 0.85
    assert a10.fy_over_fz[-1] < a20.fy_over_fz[-1] < a20.fy_over_fz[0]


def test_sti_pack_errors_name_key_and_file() -> None:
    with pytest.raises(ParameterError) as err:
        sti.pack(_vehicle({"model": "sti", "sti": {"tw": 6.5}}, "car.yaml"), "front")
    assert "tire.sti.tw" in str(err.value) and "car.yaml" in str(err.value)
    with pytest.raises(ParameterError, match=r"tire\.sti\.tw_in.*car\.yaml"):
        sti.pack(_vehicle({"model": "sti", "sti": {"tw_in": 0.0}}, "car.yaml"), "front")
    with pytest.raises(ParameterError, match=r"tire\.sti\.kmu"):
        sti.pack_mapping({"kmu": 1.5})
    # the shipped vehicle's coefficients are Table C.1
    packed = sti.pack(load_vehicle("table_8_1"), "rear")
    for key, value in sti.TABLE_C1.items():
        assert packed[sti.COEF[key.upper()]] == value


# ---------------------------------------------------------------- Magic Formula


def test_mf_slot_constants_follow_coef_order() -> None:
    for name, slot in magic_formula.COEF.__members__.items():
        assert getattr(magic_formula, f"_{name}") == int(slot)


def test_mf_pure_slip_peak_is_dy() -> None:
    c = magic_formula.pack_mapping({})
    fz0 = magic_formula.DEFAULTS["FNOMIN"]
    alphas = np.radians(np.linspace(0.0, 30.0, 30001))
    for mu in (1.0, 0.6):
        peak = max(abs(magic_formula.forces(fz0, float(a), 0.0, 20.0, mu, c)[1])
                   for a in alphas)
        assert_allclose(peak, mu * abs(magic_formula.DEFAULTS["PDY1"]) * fz0, rtol=1e-6)
        assert_allclose(magic_formula.peak_lateral_friction(c, fz0, mu) * fz0, peak, rtol=1e-6)


def test_mf_small_slip_stiffness_formula() -> None:
    c = magic_formula.pack_mapping({})
    p = magic_formula.DEFAULTS
    for fz in (2000.0, 4000.0, 6500.0):
        ky = p["PKY1"] * p["FNOMIN"] * math.sin(2 * math.atan(fz / (p["PKY2"] * p["FNOMIN"])))
        h = 1e-6
        dfy = (magic_formula.forces(fz, h, 0.0, 20.0, 1.0, c)[1]
               - magic_formula.forces(fz, -h, 0.0, 20.0, 1.0, c)[1]) / (2 * h)
        assert_allclose(dfy, ky, rtol=1e-6)


def test_mf_combined_slip_reduces_forces() -> None:
    c = magic_formula.pack_mapping({})
    fz = 4000.0
    kappas = np.linspace(0.0, 1.0, 101)
    for a_deg in (2.0, 5.0, 10.0):
        for sign in (-1.0, 1.0):
            fy = np.array([abs(magic_formula.forces(fz, a_deg * DEG, sign * k, 20.0, 1.0, c)[1])
                           for k in kappas])
            assert np.all(np.diff(fy) <= 1e-9 * fy[0])
            assert fy[-1] < 0.3 * fy[0]
    alphas = np.radians(np.linspace(0.0, 20.0, 81))
    fx = np.array([abs(magic_formula.forces(fz, float(a), -0.1, 20.0, 1.0, c)[0])
                   for a in alphas])
    assert np.all(np.diff(fx) <= 0.0)


def test_mf_symmetry_with_shifts_zeroed() -> None:
    c = magic_formula.pack_mapping({})
    for fz in (2500.0, 4000.0):
        for a in np.radians([0.5, 4.0, 12.0, 60.0]):
            for k in (-0.5, -0.05, 0.0, 0.1):
                fx1, fy1, mz1 = magic_formula.forces(fz, a, k, 20.0, 1.0, c)
                fx2, fy2, mz2 = magic_formula.forces(fz, -a, k, 20.0, 1.0, c)
                assert_allclose((fx2, fy2, mz2), (fx1, -fy1, -mz1), rtol=1e-12, atol=1e-9)
    # the published set has ply-steer/conicity: at zero slip and nominal load (dfz = 0)
    # Fy = D_y sin(C_y atan(B_y S_Hy - E_y (B_y S_Hy - atan(B_y S_Hy)))) + S_Vy
    p = magic_formula.PACEJKA_205_60R15
    pub = magic_formula.pack_mapping(p)
    dy = p["PDY1"] * p["FNOMIN"]
    ky = p["PKY1"] * p["FNOMIN"] * math.sin(2 * math.atan(1.0 / p["PKY2"]))
    by = ky / (p["PCY1"] * dy)
    x = by * p["PHY1"]
    ey = p["PEY1"] * (1 - p["PEY3"])
    expected = dy * math.sin(p["PCY1"] * math.atan(x - ey * (x - math.atan(x)))) \
        + p["PVY1"] * p["FNOMIN"]
    assert abs(expected) > 10.0
    assert_allclose(magic_formula.forces(p["FNOMIN"], 0.0, 0.0, 20.0, 1.0, pub)[1], expected,
                    rtol=1e-12)


def test_mf_pack_errors() -> None:
    with pytest.raises(ParameterError, match=r"tire\.magic_formula\.PKY9.*mf\.yaml"):
        magic_formula.pack(_vehicle({"model": "magic_formula",
                                     "magic_formula": {"PKY9": 1.0}}, "mf.yaml"), "front")
    with pytest.raises(ParameterError, match=r"tire\.magic_formula\.FNOMIN"):
        magic_formula.pack_mapping({"FNOMIN": -1.0})


# ---------------------------------------------------------------- curves and command


def test_tire_curves_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from fourws_cli.main import main

    png = tmp_path / "curves.png"
    assert main(["tire-curves", "--vehicle", "table_8_1", "--png", str(png), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert png.stat().st_size > 10_000
    assert out["tire_model"] == "sti"
    assert_allclose(out["cornering_stiffness_n_per_rad"], _sti_ca_lb(1000.0) * sti.N_PER_LBF,
                    rtol=1e-5)
    static_front = 0.5 * 1298.9 * GRAVITY_MPS2 * 1.45 / 2.45
    assert main(["tire-curves", "--vehicle", "table_8_1", "--tire", "linear", "--json"]) == 0
    lin = json.loads(capsys.readouterr().out)
    assert_allclose(lin["fz_n"], static_front, rtol=1e-3)
    assert main(["tire-curves", "--vehicle", "table_8_1", "--tire", "nope"]) == 2
    assert "valid: linear, magic_formula, sti" in capsys.readouterr().err
