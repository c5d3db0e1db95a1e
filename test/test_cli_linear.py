# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws linear``, ``fourws handling``, ``fourws lqr-gains``: stable JSON keys carrying the
paper's numbers (Table 4.3, eq. 4.93, U_ss = 12.99 m/s), readable tables, one-line errors."""

from __future__ import annotations

import json
import math

import pytest

from fourws_cli.main import main
from fourws_sim.params import load_vehicle


def _run(capsys, *argv):
    rc = main(list(argv))
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_linear_json_table_4_3_row(capsys):
    """Table 4.3, data set 2, 60 km/h, Solution 1: -14.469, -5.737."""
    rc, out, _ = _run(capsys, "linear", "--vehicle", "table_4_1_set_2", "--model", "2dof",
                      "--law", "sol1", "--speed-kmh", "60", "--json")
    assert rc == 0
    data = json.loads(out)
    for key in ("eigenvalues", "damping_ratios", "natural_frequencies_hz", "stable",
                "steady_state_gains", "routh_hurwitz"):
        assert key in data
    assert "critical_speed_mps" not in data
    re = sorted(z[0] for z in data["eigenvalues"])
    assert re == [pytest.approx(-14.469, rel=0.01), pytest.approx(-5.737, rel=0.01)]
    assert data["stable"] is True
    assert data["steady_state_gains"]["sideslip/DELTA_F"] == pytest.approx(0.0, abs=1e-12)


def test_linear_critical_speed_oversteer(capsys):
    """Eq. 4.93: FWS critical speed of the oversteer set 2."""
    rc, out, _ = _run(capsys, "linear", "--vehicle", "table_4_1_set_2", "--model", "2dof",
                      "--law", "fws", "--speed-kmh", "60", "--json", "--critical-speed")
    assert rc == 0
    v = load_vehicle("table_4_1_set_2")
    c, t = v.chassis, v.axle_tires
    cf, cr = t.cornering_stiffness_front_n_per_rad, t.cornering_stiffness_rear_n_per_rad
    analytic = math.sqrt(c.wheelbase_m ** 2 * cf * cr / (
        c.mass_kg * (c.cg_to_front_axle_m * cf - c.cg_to_rear_axle_m * cr)))
    assert json.loads(out)["critical_speed_mps"] == pytest.approx(analytic, rel=1e-6)
    rc, out, _ = _run(capsys, "linear", "--vehicle", "table_4_1_set_1", "--model", "2dof",
                      "--law", "sol1", "--speed-kmh", "60", "--json", "--critical-speed")
    assert json.loads(out)["critical_speed_mps"] is None


def test_linear_human_table_and_tf_bode(capsys):
    rc, out, _ = _run(capsys, "linear", "--vehicle", "table_4_1_set_1", "--model", "3dof",
                      "--law", "rwc2_3dof", "--speed-kmh", "85")
    assert rc == 0
    assert "eigenvalue" in out and "stable: yes" in out and "roll/DELTA_F" in out
    rc, out, _ = _run(capsys, "linear", "--vehicle", "table_4_4", "--model", "2dof-free",
                      "--law", "sol1", "--speed-kmh", "85", "--json", "--transfer-functions",
                      "--bode")
    data = json.loads(out)
    assert {t["input"] for t in data["transfer_functions"]} == {"T_F"}
    assert data["bode"]["frequencies_hz"][0] == pytest.approx(0.01)
    # eq. 4.66: Solution 1 on the free-control car keeps -(Cf+Cr)/(mU)
    u = 85 / 3.6
    lam1 = -(55000.0 + 45000.0) / (1000.0 * u)
    assert min(abs(z[0] - lam1) for z in data["eigenvalues"]) < 1e-9 * abs(lam1)


def test_linear_lqr_with_options_and_belief(capsys):
    rc, out, _ = _run(capsys, "linear", "--vehicle", "table_4_1_set_1", "--model", "3dof",
                      "--law", "lqr", "--law-option", "model=3dof", "--law-option", "q=20",
                      "--belief-tire-scale", "0.6", "--speed-kmh", "60", "--json")
    assert rc == 0
    data = json.loads(out)
    assert set(data["law_gains"]) == {"yaw_rate", "roll", "roll_rate", "lateral_velocity"}


def test_handling_json_equal_slope_speed(capsys):
    """Section 4.5.3: U_ss = 12.99 m/s for Table 4.4."""
    rc, out, _ = _run(capsys, "handling", "--vehicle", "table_4_4", "--law", "sol1", "--json")
    assert rc == 0
    data = json.loads(out)
    assert data["equal_slope_speed_mps"] == pytest.approx(12.99, abs=0.005)
    assert data["steer_character"] == "understeer"
    assert data["characteristic_speed_mps"] > 0.0 and data["critical_speed_mps"] is None
    rc, out, _ = _run(capsys, "handling", "--vehicle", "table_4_1_set_2")
    assert rc == 0 and "oversteer" in out


def test_lqr_gains_json_and_plot(capsys, tmp_path):
    """Figure 3.6: V gain grows with q (U = 20 m/s)."""
    rc, out, _ = _run(capsys, "lqr-gains", "--vehicle", "table_4_4", "--model", "2dof",
                      "--speeds", "20", "--q", "1", "50", "--json")
    assert rc == 0
    data = json.loads(out)
    kv = data["gains"]["V"][0]
    assert kv[1] > kv[0] > 0.0
    png = tmp_path / "g.png"
    rc, out, _ = _run(capsys, "lqr-gains", "--vehicle", "table_4_4", "--speeds", "20",
                      "--q", "1", "5", "--plot", str(png))
    assert rc == 0 and png.stat().st_size > 0


@pytest.mark.parametrize("argv, needle", [
    (["linear", "--vehicle", "table_4_1_set_1", "--model", "2dof", "--law", "rwc4_3dof",
      "--speed-kmh", "60"], "rwc4_3dof"),
    (["linear", "--vehicle", "table_4_1_set_1", "--model", "2dof", "--law", "sol1",
      "--speed-kmh", "-5"], "--speed-kmh"),
    (["linear", "--vehicle", "table_4_1_set_1", "--model", "2dof", "--law", "sol9",
      "--speed-kmh", "60"], "valid: ff_zero_sideslip"),
    (["lqr-gains", "--vehicle", "table_4_4", "--q", "-1"], "q"),
    (["lqr-gains", "--vehicle", "table_4_4", "--p", "0"], "weights.p"),
    (["linear", "--vehicle", "table_4_4", "--model", "2dof", "--law", "lqr", "--law-option",
      "q", "--speed-kmh", "60"], "KEY=VALUE"),
])
def test_errors_are_one_line_nonzero_exit(capsys, argv, needle):
    rc, out, err = _run(capsys, *argv)
    assert rc == 2
    assert needle in err and len(err.strip().splitlines()) == 1


def test_linear_bode_plot(capsys, tmp_path):
    png = tmp_path / "bode.png"
    rc, out, _ = _run(capsys, "linear", "--vehicle", "table_4_1_set_1", "--model", "2dof",
                      "--law", "sol1", "--speed-kmh", "85", "--bode-plot", str(png), "--json")
    assert rc == 0 and json.loads(out)["bode_plot"] == str(png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
