# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Critical and characteristic speeds per model level (``fourws_analysis/critical_speeds.py``)
in ``fourws handling`` and ``fourws linear``.

Sources of the asserted numbers:

* the 2-DOF critical speed of an oversteering set in closed form: with per-axle cornering
  stiffness ``K_us = m/L (b/C_f - a/C_r)`` and ``U_crit = sqrt(-L/K_us)`` (the paper's
  eq. 4.93; Wong, *Theory of Ground Vehicles*, 3rd ed., eq. 5.x), i.e.
  ``U_crit = sqrt(L^2 C_f C_r / (m (a C_f - b C_r)))``;
* the 3-DOF's with roll steer from the effective cornering stiffnesses derived by hand in the
  test (steady roll ``phi = m_s h a_y/(K_phi - m_s g h)`` from the 3-DOF's roll equation;
  ``F_f = C_f (delta + eps_f phi - alpha_kin)`` with ``a_y = L F_f/(m b)``);
* the static-divergence relation of each level: the steady yaw gain ``U/(L + K U^2)`` is
  infinite where the real eigenvalue crosses zero, so ``U_crit = sqrt(-L/K)`` of the level's
  own understeer gradient;
* the tools against each other: the same number for the same level.
"""

from __future__ import annotations

import json
import math

import pytest

from fourws_analysis import critical_speeds as cs
from fourws_cli.main import main
from fourws_sim.params import GRAVITY_MPS2, load_vehicle, vehicle_from_mapping


def _json(capsys, *argv) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _levels(data: dict) -> dict[str, dict]:
    return {lv["level"]: lv for lv in data["levels"]}


def test_tools_give_one_number_per_level(capsys):
    hand = _json(capsys, "handling", "--vehicle", "table_8_1", "--law", "fws")
    levels = _levels(hand)
    assert [lv["label"] for lv in hand["levels"]] == list(cs.LEVELS.values())
    assert hand["speeds_model_level"] == "2dof"
    # the 2-DOF keys are the 2-DOF level's
    assert hand["characteristic_speed_mps"] == levels["2dof"]["characteristic_speed_mps"]
    assert hand["critical_speed_mps"] == levels["2dof"]["critical_speed_mps"] is None
    for level in ("2dof", "3dof"):
        lin = _json(capsys, "linear", "--vehicle", "table_8_1", "--model", level, "--law",
                    "fws", "--speed-kmh", "85", "--critical-speed")
        assert lin["critical_speed_model_level"] == level
        assert lin["critical_speed_mps"] == levels[level]["critical_speed_mps"]
    v = load_vehicle("table_8_1")
    assert cs.critical_speed("8dof-lin", v).critical_speed_mps == \
        levels["8dof-lin"]["critical_speed_mps"]
    # table_8_1: an understeering tire set, an oversteering car through roll steer
    assert levels["2dof"]["steer_character"] == "understeer"
    assert levels["3dof"]["steer_character"] == levels["8dof-lin"]["steer_character"] == \
        "oversteer"
    assert hand["roll_steer_makes_oversteer"] is True
    assert levels["3dof"]["critical_speed_mps"] == pytest.approx(41.77, abs=0.01)
    assert levels["8dof-lin"]["critical_speed_mps"] == pytest.approx(32.77, abs=0.01)
    assert "makes the understeering tire set an oversteering car" in hand["why_they_differ"][0]


def test_text_output_names_the_level_of_every_speed(capsys):
    assert main(["handling", "--vehicle", "table_8_1", "--law", "fws"]) == 0
    text = capsys.readouterr().out
    assert "characteristic speed (2-DOF): 34.923 m/s" in text
    assert "critical speed (FWS, 2-DOF): none" in text
    for label in cs.LEVELS.values():
        assert label in text
    assert "41.775 m/s (150.4 km/h)" in text and "32.770 m/s (118.0 km/h)" in text
    assert main(["linear", "--vehicle", "table_8_1", "--model", "3dof", "--law", "fws",
                 "--speed-kmh", "85", "--critical-speed"]) == 0
    assert "critical speed (3-DOF with roll steer): 41.775 m/s" in capsys.readouterr().out


def _oversteering_tire_set():
    """table_8_1 with axle_tires 80/40 kN/rad (a C_f > b C_r)."""
    data = load_vehicle("table_8_1").to_dict()
    data["axle_tires"] = {"cornering_stiffness_front_n_per_rad": 80000.0,
                          "cornering_stiffness_rear_n_per_rad": 40000.0}
    return vehicle_from_mapping(data, "oversteer.yaml")


def test_two_dof_critical_speed_of_an_oversteering_set_is_the_closed_form():
    v = _oversteering_tire_set()
    m, a, b = 1298.857, 1.0, 1.45
    L, cf, cr = a + b, 80000.0, 40000.0
    assert a * cf > b * cr  # oversteer: 80000 > 58000
    u_crit = math.sqrt(L ** 2 * cf * cr / (m * (a * cf - b * cr)))  # = 25.93 m/s
    assert u_crit == pytest.approx(25.93, abs=0.01)
    two = cs.level_speeds("2dof", v)
    assert two.critical_speed_mps == pytest.approx(u_crit, abs=1e-5)
    assert two.understeer_gradient_rad_per_mps2 == pytest.approx(m / L * (b / cf - a / cr),
                                                                 rel=1e-9)
    assert two.characteristic_speed_mps is None


def test_three_dof_critical_speed_from_the_effective_cornering_stiffness():
    v = load_vehicle("table_8_1")
    m, a, b, L = 1298.857, 1.0, 1.45, 2.45
    cf, cr = 65100.0, 54100.0                       # axle_tires
    ms, h = 1167.512, 0.4572
    k_phi = 37300.0 + 30499.1
    eps_f, eps_r = 0.2, -0.2
    r_phi = ms * h / (k_phi - ms * GRAVITY_MPS2 * h)           # 8.53e-3 rad/(m/s^2)
    assert r_phi == pytest.approx(8.53e-3, abs=1e-5)
    cf_eff = cf / (1.0 - cf * eps_f * r_phi * L / (m * b))     # 76.1 kN/rad
    cr_eff = cr / (1.0 - cr * eps_r * r_phi * L / (m * a))     # 46.1 kN/rad
    assert (cf_eff, cr_eff) == pytest.approx(cs.effective_cornering_stiffness(v), rel=1e-12)
    k_eff = m / L * (b / cf_eff - a / cr_eff)
    k_us = m / L * (b / cf - a / cr)
    assert k_eff == pytest.approx(k_us - (eps_f - eps_r) * r_phi, rel=1e-12)
    assert k_us > 0.0 > k_eff  # understeering tires, oversteering car
    u_crit = math.sqrt(L ** 2 * cf_eff * cr_eff / (m * (a * cf_eff - b * cr_eff)))
    three = cs.level_speeds("3dof", v)
    assert three.critical_speed_mps == pytest.approx(u_crit, abs=1e-5)
    assert three.understeer_gradient_rad_per_mps2 == pytest.approx(k_eff, rel=1e-9)


@pytest.mark.parametrize("level", list(cs.LEVELS))
def test_each_level_loses_stability_where_its_steady_gain_diverges(level):
    v = _oversteering_tire_set()
    speeds = cs.level_speeds(level, v)
    k = speeds.understeer_gradient_rad_per_mps2
    assert k < 0.0
    assert speeds.critical_speed_mps == pytest.approx(math.sqrt(-v.chassis.wheelbase_m / k),
                                                      rel=1e-3)


def test_levels_a_vehicle_lacks_are_named_not_computed(capsys):
    data = _json(capsys, "handling", "--vehicle", "table_4_4", "--law", "sol1")
    levels = _levels(data)
    assert levels["2dof"]["unavailable"] is None
    for level in ("3dof", "8dof-lin"):
        assert "no roll" in levels[level]["unavailable"]
        assert levels[level]["critical_speed_mps"] is None
    assert data["why_they_differ"] == []


def test_the_laws_of_one_car_share_its_8dof_jacobians(monkeypatch):
    """The 8-DOF critical-speed search of a second law on the same car linearizes at no
    speed the first search sampled (the open-loop Jacobians do not depend on the law), and
    finds the same speed as a search that computes every Jacobian anew."""
    from fourws_analysis import linearize
    from fourws_analysis.memo import Memo

    car = load_vehicle("table_8_1")
    calls: list[int] = []
    real = linearize.jacobians

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(linearize, "jacobians", counted)
    monkeypatch.setattr(linearize, "_JACOBIAN_CACHE", Memo(1024))
    first = cs.critical_speed("8dof-lin", car, "sol1")
    sampled = len(calls)
    assert first.critical_speed_mps is None and sampled == 200  # stable over the whole grid
    second = cs.critical_speed("8dof-lin", car, "rwc2_3dof")
    assert len(calls) == sampled and second.critical_speed_mps is None
    fws_kept = cs.critical_speed("8dof-lin", car, "fws").critical_speed_mps
    monkeypatch.setattr(linearize, "_JACOBIAN_CACHE", Memo(1))
    assert cs.critical_speed("8dof-lin", car, "fws").critical_speed_mps == fws_kept
