# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""LQR rear steer (Samsundar 1996 ch. 3): trends of Figures 3.2, 3.5, 3.6, 3.13-3.15, agreement
with python-control's ``lqr``/``dlqr``, the gain schedule, the design for the sampled loop
(zero-order hold at the control period), and weight validation."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

from fourws_analysis.compare import eightdof_sampled_loop
from fourws_analysis.linear import closed_loop, is_stable, sampled_closed_loop
from fourws_analysis.lqr_analysis import detectable, lqr_sweep, plot_lqr_gains
from fourws_control import make_law, make_loop_law
from fourws_control.lqr import (LqrWeights, check_weights, dlqr_gain_matrix, lqr_gain,
                                rear_weight_from_actuator, sampled_problem)
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


@pytest.mark.parametrize("design, period", [("continuous", 0.01), ("discrete", 0.01),
                                            ("discrete", 0.02)])
def test_lqr_law_schedule_interpolates_exact_gains(car, design, period):
    """The law's speed table reproduces the exact Riccati gains between grid points."""
    law = make_law("lqr", car, q=20.0, p=1.0, design=design, control_period_s=period)
    w = LqrWeights(q=20.0)
    for u in (2.7, 9.3, 17.1, 33.3, 61.0):
        exact = -lqr_gain("2dof", car, u, w, design, period)
        k = law.gains(u)
        assert k[4] == pytest.approx(exact[0], rel=5e-3)  # lateral velocity
        assert k[1] == pytest.approx(exact[1], rel=5e-3)  # yaw rate
    top = law.speed_grid_mps[-1]
    np.testing.assert_array_equal(law.gains(2 * top), law.gains(top))  # held above the grid


@pytest.mark.parametrize("model", ["2dof", "2dof-free", "3dof"])
def test_lqr_closed_loop_stable(model):
    """Continuous design: LQR on its design model is stable at every speed (Riccati theory,
    section 3.1); discrete design: the loop sampled at its period is (discrete Riccati
    theory: every |z| < 1)."""
    v = load_vehicle("table_4_4" if model != "3dof" else "table_4_1_set_1")
    weights = {"q": 10.0, "q_yaw": 1.0 if model == "3dof" else 0.0}
    cont = make_law("lqr", v, model=model, design="continuous", **weights)
    disc = make_law("lqr", v, model=model, control_period_s=0.02, **weights)
    for u in (3.0, 15.0, 45.0):
        assert is_stable(closed_loop(model, v, cont, u).A)
        assert sampled_closed_loop(model, v, disc, u).spectral_radius < 1.0


def test_3dof_roll_gain_sign_change_figure_3_25():
    """Figure 3.25: the roll-angle gain changes sign as q grows (paper: negative to positive
    in its roll convention, i.e. positive to negative in fourws'). Weights q_yaw = q_roll =
    q_roll_rate = 1 (the paper does not print its values)."""
    v = load_vehicle("table_4_1_set_1")
    s = lqr_sweep("3dof", v, [10.0, 40.0], [0.5, 50.0],
                  LqrWeights(q_yaw=1.0, q_roll=1.0, q_roll_rate=1.0))
    k_phi = s.gain("PHI")
    assert np.all(k_phi[:, 0] > 0.0) and np.all(k_phi[:, 1] < 0.0)


# ------------------------------------------------------------------ design for the sampled loop

def test_sampled_cost_is_the_continuous_cost_over_one_hold(car):
    """Van Loan's block exponential against direct quadrature: with delta_r held over T,
    x(t) = e^{At} x0 + int_0^t e^{As} ds b u, and the continuous cost integrated over [0, T]
    equals x0^T Qd x0 + 2 x0^T Nd u + u^T Rd u (three quadratic forms read off by
    quadrature of the integrand's matrix)."""
    A, B = get_model("2dof").matrices(car, 20.0)
    b = B[:, [1]]  # DELTA_R
    Q, R, T = np.diag([10.0, 0.3]), np.array([[2.0]]), 0.02
    pr = sampled_problem(A, b, Q, R, T)
    F = np.zeros((3, 3))
    F[:2, :2], F[:2, 2:] = A, b
    W = scipy.linalg.block_diag(Q, R)
    Wq, _ = scipy.integrate.quad_vec(
        lambda t: scipy.linalg.expm(F.T * t) @ W @ scipy.linalg.expm(F * t), 0.0, T,
        epsabs=1e-14, epsrel=1e-12)
    np.testing.assert_allclose(pr.Qd, Wq[:2, :2], rtol=1e-9)
    np.testing.assert_allclose(pr.Nd, Wq[:2, 2:], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(pr.Rd, Wq[2:, 2:], rtol=1e-9)
    np.testing.assert_allclose(pr.Phi, scipy.linalg.expm(A * T), rtol=1e-12)


def test_discrete_gain_matches_python_control_dlqr(car):
    """Same K as control.dlqr on the sampled problem (two independent DARE solvers)."""
    for model in ("2dof", "2dof-free"):
        A, B = get_model(model).matrices(car, 25.0)
        b = B[:, [list(get_model(model).INPUT.__members__).index("DELTA_R")]]
        Q = np.zeros((A.shape[0], A.shape[0]))
        Q[0, 0] = 10.0
        pr = sampled_problem(A, b, Q, np.array([[365.0]]), 0.01)
        K_ref, _, _ = control.dlqr(pr.Phi, pr.Gamma, pr.Qd, pr.Rd, pr.Nd)
        np.testing.assert_allclose(dlqr_gain_matrix(pr), np.asarray(K_ref), rtol=1e-8)


def test_discrete_gain_tends_to_the_continuous_one(car):
    """Sampled-data LQR of the exactly discretized cost tends to the continuous LQR as T -> 0
    with an O(T) error (ten times smaller for a ten times shorter period; 0.1 % at 10 us),
    while at 10 ms the hold halves the V gain of Figures 3.5/3.6 (q = 10, p = 1: about 1.5
    against 3.1 rad/(m/s))."""
    w = LqrWeights(q=10.0)
    cont = lqr_gain("2dof", car, 25.0, w)
    err = [np.max(np.abs(lqr_gain("2dof", car, 25.0, w, "discrete", t) / cont - 1.0))
           for t in (1e-4, 1e-5)]
    assert err[0] / err[1] == pytest.approx(10.0, rel=0.1)
    assert err[1] < 1e-3
    coarse = lqr_gain("2dof", car, 25.0, w, "discrete", 1e-2)
    assert 0.3 < coarse[0] / cont[0] < 0.7


def test_default_rear_weight_from_the_actuator():
    """Bryson's rule on the rear angle the actuator reaches within the 0.1 s steering ramp:
    min(5 deg, 30 deg/s * 0.1 s) = 3 deg on table_8_1, p = 1/(3 deg)^2 = 364.8 rad^-2; the
    continuous design keeps the paper's p = 1."""
    car = load_vehicle("table_8_1")
    assert rear_weight_from_actuator(car) == pytest.approx(1.0 / math.radians(3.0) ** 2)
    assert make_law("lqr", car).weights.p == pytest.approx(364.756, rel=1e-5)
    assert make_law("lqr", car, design="continuous").weights.p == 1.0
    assert make_law("lqr", car, p=50.0).weights.p == 50.0


def test_sampled_design_stable_on_the_8dof_from_5_to_60_mps():
    """Closed-loop eigenvalues of the sampled design inside the unit circle over 5-60 m/s
    (table_8_1, 100 Hz and 50 Hz): on its 2-DOF design model (discrete Riccati theory), and
    on the linearized 8-DOF with the command held over the period - which without rear steer
    is unstable above ~30 m/s (roll oversteer: the fws loop's largest |z| > 1 at 40 m/s).
    The 8-DOF's position, heading, speed and wheel-spin modes (z = 1 at a trim without drag)
    are left out: the law does not act on them."""
    car = load_vehicle("table_8_1")
    speeds = np.linspace(5.0, 60.0, 12)
    for period in (0.01, 0.02):
        law = make_law("lqr", car, control_period_s=period)
        rho2 = [sampled_closed_loop("2dof", car, law, u).spectral_radius for u in speeds]
        rho8 = []
        for u in speeds:
            rho8.append(eightdof_sampled_loop(car, u, period, law).radius(1e-6))
        assert max(rho2) < 0.95 and max(rho8) < 0.97
        assert eightdof_sampled_loop(car, 40.0, period, "fws").radius(1e-6) > 1.0


def test_chapter_3_weights_sampled_at_100_hz_destabilize_the_8dof():
    """Why the sampled design uses the actuator's weight: the chapter-3 weights (q = 10,
    p = 1) held over 10 ms make the linearized 8-DOF unstable at 85 km/h (|z| > 1: the limit
    cycle of the nonlinear run, test_maneuvers.py) whether designed in continuous time or for
    the hold - gains that high (V gain 1.5-3 rad/(m/s)) reach the roll and tire dynamics the
    2-DOF design model lacks; the default weight of the discrete design
    (rear_weight_from_actuator) gives a stable loop."""
    car = load_vehicle("table_8_1")
    u = 85 / 3.6
    rho = {}
    for name, options in (("continuous", {"design": "continuous"}),
                          ("discrete p=1", {"p": 1.0}), ("discrete", {})):
        rho[name] = eightdof_sampled_loop(car, u, 0.01, make_law("lqr", car, **options)) \
            .radius(1e-6)
    assert rho["continuous"] > 1.0 and rho["discrete p=1"] > 1.0
    assert rho["discrete"] < 0.95


def test_sampled_loop_maps_to_the_continuous_eigenvalues():
    """ln(z)/T of a loop sampled at T: without feedback exactly the continuous eigenvalues
    (z = e^{lambda T}); with sol1's feedback, close to them when T is short (0.1 ms)."""
    v = load_vehicle("table_4_1_set_1")
    for law, period, rtol in (("fws", 0.01, 1e-10), ("sol1", 1e-4, 1e-2)):
        cont = np.sort_complex(np.linalg.eigvals(closed_loop("2dof", v, law, 20.0).A))
        loop = sampled_closed_loop("2dof", v, law, 20.0, period)
        np.testing.assert_allclose(np.sort_complex(loop.s_plane), cont, rtol=rtol)
        assert loop.spectral_radius == pytest.approx(np.max(np.exp(cont.real * period)),
                                                     rel=rtol)


def test_design_and_period_validation(car):
    with pytest.raises(UnknownNameError, match="continuous"):
        make_law("lqr", car, design="hybrid")
    with pytest.raises(ParameterError, match="control_period_s"):
        make_law("lqr", car, control_period_s=0.0)
    with pytest.raises(ParameterError, match="control_period_s"):
        make_loop_law("lqr", car, 0.01, {"control_period_s": 0.02})  # the loop's, not an option
    assert make_loop_law("lqr", car, 0.02, {"q": 5.0}).control_period_s == 0.02


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
