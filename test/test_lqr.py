"""LQR rear steer (Samsundar 1996 ch. 3): trends of Figures 3.2, 3.5, 3.6, 3.13-3.15, agreement
with python-control's ``lqr``, the gain schedule, and weight validation."""

from __future__ import annotations

import control
import numpy as np
import pytest

from fourws_analysis.linear import closed_loop, is_stable
from fourws_analysis.lqr_analysis import detectable, lqr_sweep, plot_lqr_gains
from fourws_control import make_law
from fourws_control.lqr import LqrWeights, check_weights, lqr_gain
from fourws_sim.errors import IncompatibleError, ParameterError, UnknownNameError
from fourws_sim.models import get_model
from fourws_sim.params import load_vehicle

SPEEDS = (10.0, 20.0, 30.0, 40.0)  # the speeds of Figures 3.5/3.6
QS = (1.0, 5.0, 10.0, 20.0, 50.0)


@pytest.fixture(scope="module")
def car():
    """Table 3.1 (= Table 4.4), the vehicle of Figures 3.2-3.15."""
    return load_vehicle("table_4_4")


@pytest.fixture(scope="module")
def sweep2(car):
    return lqr_sweep("2dof", car, SPEEDS, QS)


def test_matches_python_control_lqr(car):
    """Same K as control.lqr on the model's (A, b_r) (two independent ARE solvers)."""
    for model in ("2dof", "2dof-free"):
        A, B = get_model(model).matrices(car, 25.0)
        b = B[:, [list(get_model(model).INPUT.__members__).index("DELTA_R")]]
        Q = np.zeros((A.shape[0], A.shape[0]))
        Q[0, 0] = 10.0
        K_ref, _, _ = control.lqr(A, b, Q, np.array([[1.0]]))
        np.testing.assert_allclose(lqr_gain(model, car, 25.0, LqrWeights(q=10.0)),
                                   np.asarray(K_ref)[0], rtol=1e-8)


def test_figure_3_5_3_6_trends(sweep2):
    """Figures 3.5/3.6: gains grow with q and speed; the (lateral velocity) sideslip gain is
    much larger than the yaw-rate gain and insensitive to speed; yaw gain negative."""
    kv, kr = sweep2.gain("V"), sweep2.gain("R")
    assert np.all(np.diff(kv, axis=1) > 0.0)  # grows with q at every speed
    assert np.all(np.diff(-kr, axis=1) > 0.0)  # |Kr| grows with q
    assert np.all(np.diff(-kr, axis=0) > 0.0)  # |Kr| grows with speed
    assert np.all(kr < 0.0) and np.all(kv > 0.0)
    assert np.all(kv[:, QS.index(50.0)] > 5.0 * np.abs(kr[:, QS.index(50.0)]))
    # insensitive to speed: within 5 % between 10 and 40 m/s at q = 50 (Figure 3.6)
    col = kv[:, QS.index(50.0)]
    assert np.ptp(col) < 0.05 * col.mean()
    # magnitudes within the figures' axes: V gain up to ~7 (axis 0-8), yaw gain > -1
    assert 5.0 < col.max() < 8.0 and kr.min() > -1.0


def test_figure_3_2_root_locus(sweep2):
    """Figure 3.2 (U = 25 m/s): as q grows the oscillation vanishes and the fast root moves
    far left (to about -300 1/s at q = 50)."""
    s = lqr_sweep("2dof", load_vehicle("table_4_4"), [25.0], [0.01, 50.0])
    low, high = s.eigenvalues[0, 0], s.eigenvalues[0, 1]
    assert np.all(np.abs(high.imag) < 1e-9)
    assert high.real.min() < -250.0
    assert high.real.min() < low.real.min()


def test_free_control_gains_figures_3_13_to_3_15(car, sweep2):
    """Figures 3.13/3.14 equal the fixed-control gains almost exactly; Figure 3.15: the front
    steer gain grows with q and falls with speed."""
    free = lqr_sweep("2dof-free", car, SPEEDS, QS)
    np.testing.assert_allclose(free.gain("V"), sweep2.gain("V"), rtol=0.05)
    np.testing.assert_allclose(free.gain("R"), sweep2.gain("R"), rtol=0.15)
    kd = free.gain("DELTA_F")
    assert np.all(np.diff(kd, axis=1) > 0.0)
    assert np.all(np.diff(kd, axis=0) < 0.0)


def test_lqr_law_schedule_interpolates_exact_gains(car):
    """The law's speed table reproduces the exact Riccati gains between grid points."""
    law = make_law("lqr", car, q=20.0)
    w = LqrWeights(q=20.0)
    for u in (2.7, 9.3, 17.1, 33.3, 61.0):
        exact = -lqr_gain("2dof", car, u, w)
        k = law.gains(u)
        assert k[4] == pytest.approx(exact[0], rel=5e-3)  # lateral velocity
        assert k[1] == pytest.approx(exact[1], rel=5e-3)  # yaw rate
    top = law.speed_grid_mps[-1]
    np.testing.assert_array_equal(law.gains(2 * top), law.gains(top))  # held above the grid


@pytest.mark.parametrize("design", ["2dof", "2dof-free", "3dof"])
def test_lqr_closed_loop_stable(design):
    """LQR on its design model is stable at every speed (Riccati theory, section 3.1)."""
    v = load_vehicle("table_4_4" if design != "3dof" else "table_4_1_set_1")
    law = make_law("lqr", v, model=design, q=10.0, q_yaw=1.0 if design == "3dof" else 0.0)
    for u in (3.0, 15.0, 45.0):
        assert is_stable(closed_loop(design, v, law, u).A)


def test_3dof_roll_gain_sign_change_figure_3_25():
    """Figure 3.25: the roll-angle gain changes sign as q grows (paper: negative to positive
    in its roll convention, i.e. positive to negative in fourws'). Weights q_yaw = q_roll =
    q_roll_rate = 1 (the paper does not print its values)."""
    v = load_vehicle("table_4_1_set_1")
    s = lqr_sweep("3dof", v, [10.0, 40.0], [0.5, 50.0],
                  LqrWeights(q_yaw=1.0, q_roll=1.0, q_roll_rate=1.0))
    k_phi = s.gain("PHI")
    assert np.all(k_phi[:, 0] > 0.0) and np.all(k_phi[:, 1] < 0.0)


def test_weights_validation(car):
    with pytest.raises(ParameterError, match="weights.q"):
        LqrWeights(q=-1.0)
    with pytest.raises(ParameterError, match="weights.p"):
        LqrWeights(p=0.0)
    with pytest.raises(ParameterError, match="Q"):
        check_weights(np.array([[1.0, 2.0], [2.0, 1.0]]), np.eye(1))  # indefinite
    with pytest.raises(ParameterError, match="R"):
        check_weights(np.eye(2), -np.eye(1))
    with pytest.raises(IncompatibleError, match="q_roll"):
        make_law("lqr", car, q_roll=1.0)  # 2dof has no roll state
    with pytest.raises(UnknownNameError, match="2dof-free"):
        make_law("lqr", car, model="2dof-lagged")
    with pytest.raises(ParameterError, match="speed"):
        lqr_gain("2dof", car, 0.0)
    with pytest.raises(ParameterError, match="steering"):
        make_law("lqr", load_vehicle("table_4_1_set_1"), model="2dof-free")


def test_detectability_of_sideslip_weight(car):
    """Section 3.3.2: with weight only on V, (Q^1/2, A) is observable for the 2-DOF car."""
    assert detectable("2dof", car, 25.0)


def test_plot_writes_png(tmp_path, sweep2):
    out = plot_lqr_gains(sweep2, tmp_path / "gains.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
