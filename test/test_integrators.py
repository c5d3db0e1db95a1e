# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Integrators: orders of accuracy against analytic solutions, registry and bad input.

Sources: the exact solution of the linear ODE x' = A x + B u (matrix exponential), the global
error orders of explicit Euler (1) and classical Runge-Kutta (4), and for the 8-DOF model's
semi-implicit Euler its order (1) against the adaptive ``solve_ivp`` reference and its
definition (the rates' explicit step, then the pose with the new rates).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from fourws_sim.errors import ParameterError, UnknownNameError
from fourws_sim.integrators import DEFAULT_STEP_S, INTEGRATORS, get_integrator
from fourws_sim.models import linear2dof
from fourws_sim.params import load_vehicle

SPEED_MPS = 85.0 / 3.6


def linear_system() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 2-DOF bicycle (table_4_1_set_1) at 85 km/h: A, B and a front-steer input."""
    A, B = linear2dof.matrices(load_vehicle("table_4_1_set_1"), SPEED_MPS)
    return A, B, np.array([0.02, 0.0])


def f_linear(t: float, x: np.ndarray, u: np.ndarray, p: tuple[np.ndarray, np.ndarray]
             ) -> np.ndarray:
    A, B = p
    return A @ x + B @ u


def exact(A: np.ndarray, B: np.ndarray, u: np.ndarray, x0: np.ndarray, t: float
          ) -> np.ndarray:
    """x(t) = e^{At} x0 + A^-1 (e^{At} - I) B u (constant input)."""
    E = expm(A * t)
    return E @ x0 + np.linalg.solve(A, (E - np.eye(len(x0))) @ (B @ u))


def global_error(name: str, dt: float, t_end: float = 1.0) -> float:
    A, B, u = linear_system()
    x0 = np.array([0.1, -0.05])
    n = int(round(t_end / dt))
    x = get_integrator(name).advance(f_linear, 0.0, x0, u, (A, B), dt, n)
    return float(np.max(np.abs(x - exact(A, B, u, x0, t_end))))


def test_rk4_is_fourth_order() -> None:
    """Halving the step divides the RK4 error by 2^4 = 16."""
    e1, e2 = global_error("rk4", 0.02), global_error("rk4", 0.01)
    assert e1 / e2 == pytest.approx(16.0, rel=0.1)
    assert global_error("rk4", DEFAULT_STEP_S) < 1e-10


def test_euler_is_first_order() -> None:
    """Halving the step halves the explicit-Euler error."""
    e1, e2 = global_error("euler", 0.002), global_error("euler", 0.001)
    assert e1 / e2 == pytest.approx(2.0, rel=0.05)


def test_solve_ivp_reference_is_exact_to_its_tolerance() -> None:
    """The SciPy reference matches the matrix exponential to its 1e-10 tolerance."""
    assert global_error("solve_ivp", 0.1) < 1e-9


def test_advance_does_not_modify_the_start_state() -> None:
    A, B, u = linear_system()
    x0 = np.array([0.1, -0.05])
    get_integrator("rk4").advance(f_linear, 0.0, x0, u, (A, B), 1e-3, 10)
    assert x0.tolist() == [0.1, -0.05]


def test_zero_steps_returns_the_state() -> None:
    A, B, u = linear_system()
    x0 = np.array([0.1, -0.05])
    for name in INTEGRATORS:
        assert np.array_equal(get_integrator(name).advance(f_linear, 0.0, x0, u, (A, B),
                                                           1e-3, 0), x0)


def test_unknown_integrator_lists_the_valid_names() -> None:
    with pytest.raises(UnknownNameError,
                       match="euler, rk4, semi_implicit_euler, solve_ivp") as info:
        get_integrator("rk45")
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize("dt, n, field", [(0.0, 1, "dt_s"), (float("nan"), 1, "dt_s"),
                                          (1e-3, -1, "n_steps"), (1e-3, 1.5, "n_steps")])
def test_bad_step_names_the_field(dt: float, n: int, field: str) -> None:
    A, B, u = linear_system()
    with pytest.raises(ParameterError, match=field):
        get_integrator("rk4").advance(f_linear, 0.0, np.zeros(2), u, (A, B), dt, n)


def _eightdof_final(integrator: str, dt: float, t_end: float = 2.0) -> np.ndarray:
    """8-DOF (table_8_1) state after ``t_end`` s of a 0.03 rad front step at 85 km/h."""
    from fourws_sim.models.eightdof import INPUT
    from fourws_sim.simulator import Simulator

    sim = Simulator("table_8_1", integrator=integrator, dt_s=dt, speed_mps=SPEED_MPS)
    u = np.zeros(len(INPUT))
    u[INPUT.DELTA_F] = 0.03
    sim.step(u, int(round(t_end / dt)))
    return sim.state


def test_semi_implicit_euler_is_first_order_on_the_eightdof() -> None:
    """Halving the step halves the semi-implicit Euler error of the yaw rate and the heading
    against the solve_ivp reference (DOP853 at 1e-10, four orders below these errors)."""
    from fourws_sim.models.eightdof import STATE

    ref = _eightdof_final("solve_ivp", 0.01)
    e1, e2 = (np.abs(_eightdof_final("semi_implicit_euler", dt) - ref) for dt in (2e-3, 1e-3))
    for s in (STATE.R, STATE.PSI, STATE.Y):
        assert e1[s] / e2[s] == pytest.approx(2.0, rel=0.05), STATE(s).name
    assert 1e-6 < e2[STATE.R] < 1e-3  # first order at 1 ms: far from RK4's 1e-10


def test_semi_implicit_euler_kernel_takes_the_pose_with_the_new_rates() -> None:
    """One compiled step equals its definition in NumPy (``simulator._semi_implicit_step``,
    which also replays a diverging step) from the compiled right-hand side: x' = x + h f(x),
    then roll angle, heading, position and free steering angle again from the new rates at
    the old heading."""
    from fourws_sim.models import eightdof
    from fourws_sim.models.eightdof import INPUT
    from fourws_sim.simulator import Simulator, _semi_implicit_step

    sim = Simulator("table_8_1", integrator="semi_implicit_euler", speed_mps=SPEED_MPS)
    u = np.zeros(len(INPUT))
    u[INPUT.DELTA_F] = 0.03
    sim.step(u, 300)  # turning and rolling: every pose rate is non-zero
    x = sim.state.copy()
    k = np.zeros(eightdof.N_STATE)
    eightdof.kernels_for(sim._p.tire_name).rhs(x, u, sim._q, sim._cf, sim._cr, k,
                                               np.zeros(eightdof.N_AUX))
    want = _semi_implicit_step(x, k, sim.dt_s)
    sim.step(u, 1)
    np.testing.assert_allclose(sim.state, want, rtol=1e-15, atol=1e-18)
    assert not np.array_equal(want, x + sim.dt_s * k)  # the pose did take the new rates


def test_semi_implicit_euler_is_refused_for_models_without_a_pose_split() -> None:
    from fourws_sim.simulator import Simulator

    with pytest.raises(ParameterError, match="semi_implicit_euler is for the 8dof"):
        Simulator("table_4_1_set_1", model="2dof", integrator="semi_implicit_euler")
    A, B, u = linear_system()
    with pytest.raises(ParameterError, match="compiled 8-DOF"):
        get_integrator("semi_implicit_euler").advance(f_linear, 0.0, np.zeros(2), u, (A, B),
                                                      1e-3, 1)
