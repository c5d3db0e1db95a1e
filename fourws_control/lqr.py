# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""``lqr``: chapter 3 optimal rear steer minimizing sideslip (linear quadratic regulator).

For a linear model :math:`\dot x = A x + B_r \delta_r + \dots` (the rear-steer column of the
model's B) the law is :math:`\delta_r = -K x`, minimizing

.. math::

    J = \int_0^\infty (x^T Q x + p\,\delta_r^2)\,dt

(eqs. 3.1-3.5). Design models and their states: ``2dof`` ``[V, r]``, ``2dof-free``
``[V, r, delta_f]``, ``3dof`` ``[V, r, phi, phi_dot]`` (fourws sign conventions).

Two designs (law option ``design``)
-----------------------------------
``continuous``
    The dissertation's design: :math:`K = R^{-1} B_r^T P` with
    :math:`0 = A^T P + P A + Q - P B_r R^{-1} B_r^T P` (``scipy.linalg.solve_continuous_are``).
    It assumes the rear angle follows :math:`-K x` continuously and without limit. Use it for
    the chapter-3 figures (``fourws lqr-gains`` and :mod:`fourws_analysis.lqr_analysis` always
    use it).
``discrete`` (default)
    The same cost for the loop the law runs in: the command is computed every control period
    ``T`` (law option ``control_period_s``, the loop's period, see
    :func:`fourws_control.registry.make_loop_law`) and held by the actuator (zero-order hold).
    Over one period with :math:`\delta_r` held, :math:`x_{k+1} = \Phi x_k + \Gamma \delta_{r,k}`
    and the cost integrates exactly to
    :math:`\sum x_k^T Q_d x_k + 2 x_k^T N_d \delta_{r,k} + \delta_{r,k}^T R_d \delta_{r,k}`
    (:func:`sampled_problem`, Van Loan 1978); the discrete Riccati equation
    (``scipy.linalg.solve_discrete_are``) gives :math:`\delta_{r,k} = -K_d x_k`. As
    :math:`T \to 0`, :math:`K_d \to K`.

Why the sampled design is the default (every closed-loop run samples the law): the
continuous gains on the 8-DOF car at the 100 Hz control rate (``table_8_1``, q = 10, p = 1: a
V gain of -3 rad/(m/s)) command tens of degrees of rear steer, so the 5 deg / 30 deg/s
actuator acts as a relay and the sampled loop limit-cycles (0.19 rad/s yaw-rate swing with the
steer held; it settles only at 500 Hz); the car leaves the ISO 3888-2 course at 60 km/h. The
hold alone does not cure it: the discrete design with p = 1 still has gains (V gain 1.5) that
reach the roll and tire dynamics the 2-DOF design model lacks, and the linearized 8-DOF loop
is unstable (|z| = 1.04 at 85 km/h). With the default weight below, the loop is stable from 5
to 60 m/s at 100 and 50 Hz (|z| <= 0.97), settles with the steer held (yaw-rate swing after
2 s 0.006 % of its steady value in the ISO 7401 step at 85 km/h) and clears ISO 3888-2 at
60 km/h by 6.3 cm with the rear command within 2.8 deg and 21 deg/s.

Weights (all >= 0, ``p`` > 0)
-----------------------------
``q``
    on the lateral velocity V, in (m/s)^-2 - the paper's "weight on sideslip": its Q (3.11)
    puts q in the 1-1 position of the state ``[V, r]``, and with ``p = 1`` this reproduces the
    gain magnitudes of Figures 3.5/3.6 (V gain to ~7 at q = 50, yaw-rate gain -0.3 to -0.9);
``q_steer``
    on the front road-wheel angle (free control, eq. 3.26's q2);
``q_yaw``, ``q_roll``, ``q_roll_rate``
    on r, phi, phi_dot (3-DOF, eq. 3.56's q2..q4);
``p``
    on the rear angle (eq. 3.12), rad^-2. Default: 1 for the continuous design (the paper's
    figures); for the discrete design Bryson's rule on the actuator,
    :math:`p = 1/\delta_{budget}^2` (:func:`rear_weight_from_actuator`), with the budget the
    rear angle the belief vehicle's actuator can reach within the quickest steering input a
    driver makes (the ISO 7401 step's 0.1 s ramp, :data:`STEER_RAMP_S`):
    :math:`\min(\delta_{max}, \dot\delta_{max} \cdot 0.1\,s)`, 3 deg for 5 deg / 30 deg/s
    (p = 365 rad^-2). With it the actuator is never saturated in the ISO 7401 step at
    4 m/s^2 nor in the ISO 3888-2 lane change at 60 km/h on ``table_8_1``
    (``test/test_sampled_laws.py``, ``test/test_maneuvers.py``). Give ``p`` to override.

A design that weights the rear-angle *rate* needs the applied angle of the previous period as
a state; fourws laws are stateless (``delta_r = k(U) . [delta_f, r, phi, phi_dot, V]``,
:mod:`fourws_control.base`), and with the weight above the rate limit is not reached, so the
rate enters through the budget instead.

Scheduling: the gains are solved at construction on a speed grid from ``min_speed_mps`` to
``max_speed_mps`` (geometric, ratio ``speed_ratio`` between neighbours) and interpolated
linearly per call; above the grid the gains of ``max_speed_mps`` are held, below
``min_speed_mps`` they fade to zero (:mod:`fourws_control.base`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import scipy.linalg

from fourws_control.base import (DEFAULT_CONTROL_PERIOD_S, DEFAULT_MIN_SPEED_MPS,
                                 GainFunction, Law, Signal, check_option, check_speed)
from fourws_control.signals import signal_map
from fourws_sim.errors import IncompatibleError, NonFiniteError, ParameterError, UnknownNameError
from fourws_sim.models import get_model
from fourws_sim.params import Vehicle

#: Models an LQR law can be designed on.
LQR_MODELS = ("2dof", "2dof-free", "3dof")
#: Designs of the law (module docstring); the first is the default.
LQR_DESIGNS = ("discrete", "continuous")
#: The quickest steering input the rear steer must follow, s: the ramp of the ISO 7401 step
#: (10-90 % rise within 0.15 s; ``config/maneuvers/step_steer_85kmh.yaml`` ramps in 0.1 s).
#: Within it a rate-limited actuator travels ``rate * STEER_RAMP_S``.
STEER_RAMP_S = 0.1
#: Weight name -> the law signal whose state it weights.
_WEIGHT_SIGNAL = {
    "q": Signal.LATERAL_VELOCITY,
    "q_steer": Signal.DELTA_F,
    "q_yaw": Signal.YAW_RATE,
    "q_roll": Signal.ROLL,
    "q_roll_rate": Signal.ROLL_RATE,
}
#: Default top of the gain-schedule grid, m/s (250 km/h).
DEFAULT_MAX_SPEED_MPS = 70.0
#: Default ratio of successive grid speeds: a geometric grid is dense where the gains bend
#: (low speed, 1/U terms) and keeps the construction cost to ~60 Riccati solves.
DEFAULT_SPEED_RATIO = 1.06


@dataclass(frozen=True)
class LqrWeights:
    """LQR weights (see module docstring); units make each ``x^T Q x`` term dimensionless
    per rad^2 of rear steer weighted by ``p``."""

    q: float = 10.0
    q_steer: float = 0.0
    q_yaw: float = 0.0
    q_roll: float = 0.0
    q_roll_rate: float = 0.0
    p: float = 1.0

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            check_option(f"weights.{name}", value, "positive" if name == "p" else "nonnegative")

    def to_dict(self) -> dict[str, float]:
        """JSON-ready mapping."""
        return asdict(self)


def _check_model(model_name: str) -> None:
    if model_name not in LQR_MODELS:
        raise UnknownNameError("LQR design model", str(model_name), list(LQR_MODELS))


def _check_design(design: str) -> None:
    if design not in LQR_DESIGNS:
        raise UnknownNameError("LQR design", str(design), list(LQR_DESIGNS))


def rear_weight_from_actuator(vehicle: Vehicle) -> float:
    r"""Default rear-angle weight ``p`` of the discrete design, rad^-2 (Bryson's rule).

    :math:`p = 1/\delta_{budget}^2` with :math:`\delta_{budget} = \min(\delta_{max},
    \dot\delta_{max} T_{ramp})`: the rear angle ``vehicle.actuators`` can reach within
    :data:`STEER_RAMP_S` (3 deg and p = 365 rad^-2 for 5 deg and 30 deg/s).
    """
    act = vehicle.actuators
    budget = min(act.rear_angle_limit_rad, act.rear_rate_limit_rad_per_s * STEER_RAMP_S)
    return 1.0 / budget ** 2


def weight_matrices(model_name: str, weights: LqrWeights) -> tuple[np.ndarray, np.ndarray]:
    """Q (n x n, diagonal) and R (1 x 1) for ``model_name``.

    Raises
    ------
    IncompatibleError
        A non-zero weight on a state the model does not have (e.g. ``q_roll`` on ``2dof``).
    """
    _check_model(model_name)
    smap = signal_map(model_name)
    Q = np.zeros((len(smap.state_names), len(smap.state_names)))
    for name, sig in _WEIGHT_SIGNAL.items():
        w = getattr(weights, name)
        pos = smap.positions.get(sig)
        if pos is None or pos[0] != "state":
            if w != 0.0:
                raise IncompatibleError(f"LQR weight {name}={w} weights a state model "
                                        f"{model_name!r} does not have")
            continue
        Q[pos[1], pos[1]] = w
    return Q, np.array([[weights.p]])


def check_weights(Q: np.ndarray, R: np.ndarray) -> None:
    """Raise :class:`ParameterError` unless Q is symmetric positive semidefinite and R
    symmetric positive definite (eq. 3.2's conditions)."""
    Q = np.asarray(Q, dtype=float)
    R = np.asarray(R, dtype=float)
    for name, M in (("Q", Q), ("R", R)):
        if M.ndim != 2 or M.shape[0] != M.shape[1] or not np.all(np.isfinite(M)):
            raise ParameterError(name, f"must be a finite square matrix, got shape {M.shape}")
        if not np.allclose(M, M.T):
            raise ParameterError(name, "must be symmetric")
    q_min = float(np.linalg.eigvalsh(Q).min())
    if q_min < -1e-12 * max(1.0, float(np.abs(Q).max())):
        raise ParameterError("Q", f"must be positive semidefinite (smallest eigenvalue {q_min:g})")
    r_min = float(np.linalg.eigvalsh(R).min())
    if r_min <= 0.0:
        raise ParameterError("R", f"must be positive definite (smallest eigenvalue {r_min:g})")


def lqr_gain_matrix(A: np.ndarray, B: np.ndarray, Q: np.ndarray,
                    R: np.ndarray) -> np.ndarray:
    """Optimal gain K (u = -K x) of the continuous LQR problem (eqs. 3.3-3.5).

    Raises
    ------
    ParameterError
        Q not PSD or R not PD.
    IncompatibleError
        The Riccati equation has no stabilizing solution ((A, B) not stabilizable or
        (Q^1/2, A) not detectable).
    """
    check_weights(Q, R)
    try:
        P = scipy.linalg.solve_continuous_are(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise IncompatibleError(f"LQR: no stabilizing Riccati solution ({exc})") from None
    K = np.linalg.solve(R, B.T @ P)
    if not np.all(np.isfinite(K)):
        raise NonFiniteError("LQR: non-finite gain")
    return K


@dataclass(frozen=True)
class SampledProblem:
    """The LQR problem of a continuous model under a zero-order hold of period ``period_s``.

    ``x[k+1] = Phi x[k] + Gamma u[k]``; the continuous cost over one period is
    ``x^T Qd x + 2 x^T Nd u + u^T Rd u``.
    """

    period_s: float
    Phi: np.ndarray
    Gamma: np.ndarray
    Qd: np.ndarray
    Nd: np.ndarray
    Rd: np.ndarray


def sampled_problem(A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray,
                    period_s: float) -> SampledProblem:
    r"""Zero-order-hold model and exactly integrated cost of a continuous LQR problem.

    With :math:`\xi = [x; u]` and :math:`u` held, :math:`\dot\xi = F \xi`,
    :math:`F = [[A, B], [0, 0]]`; Van Loan's (1978) block exponential
    :math:`\exp([[-F^T, W], [0, F]]\,T) = [[\cdot, E_{12}], [0, E_{22}]]` with
    :math:`W = \mathrm{diag}(Q, R)` gives :math:`E_{22} = e^{FT}` (hence
    :math:`\Phi, \Gamma`) and :math:`\int_0^T e^{F^T t} W e^{F t} dt = E_{22}^T E_{12}`
    (hence :math:`Q_d, N_d, R_d`).

    Parameters
    ----------
    A, B : numpy.ndarray
        Continuous model, ``(n, n)`` and ``(n, m)``.
    Q, R : numpy.ndarray
        Continuous weights, ``(n, n)`` and ``(m, m)``.
    period_s : float
        Hold period T, s (> 0).
    """
    T = check_option("control_period_s", period_s)
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    n, m = B.shape
    F = np.zeros((n + m, n + m))
    F[:n, :n], F[:n, n:] = A, B
    W = scipy.linalg.block_diag(Q, R)
    E = scipy.linalg.expm(np.block([[-F.T, W], [np.zeros_like(F), F]]) * T)
    E22, E12 = E[n + m:, n + m:], E[:n + m, n + m:]
    Wd = E22.T @ E12
    Wd = 0.5 * (Wd + Wd.T)  # symmetric in exact arithmetic
    return SampledProblem(T, E22[:n, :n], E22[:n, n:], Wd[:n, :n], Wd[:n, n:], Wd[n:, n:])


def dlqr_gain_matrix(problem: SampledProblem) -> np.ndarray:
    """Optimal gain K (``u[k] = -K x[k]``) of a sampled LQR problem (discrete Riccati).

    Raises
    ------
    IncompatibleError
        The discrete Riccati equation has no stabilizing solution.
    NonFiniteError
        The gain is not finite.
    """
    pr = problem
    try:
        P = scipy.linalg.solve_discrete_are(pr.Phi, pr.Gamma, pr.Qd, pr.Rd, s=pr.Nd)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise IncompatibleError(
            f"LQR: no stabilizing discrete Riccati solution ({exc})") from None
    K = np.linalg.solve(pr.Rd + pr.Gamma.T @ P @ pr.Gamma, pr.Gamma.T @ P @ pr.Phi + pr.Nd.T)
    if not np.all(np.isfinite(K)):
        raise NonFiniteError("LQR: non-finite gain")
    return K


def design_gain_matrix(A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray,
                       design: str = "continuous",
                       control_period_s: float = DEFAULT_CONTROL_PERIOD_S) -> np.ndarray:
    """LQR gain of the continuous problem ``(A, B, Q, R)`` for ``design`` (module docstring).

    Raises
    ------
    UnknownNameError
        Unknown design.
    ParameterError, IncompatibleError, NonFiniteError
        As :func:`lqr_gain_matrix` / :func:`dlqr_gain_matrix`.
    """
    _check_design(design)
    if design == "continuous":
        return lqr_gain_matrix(A, B, Q, R)
    check_weights(Q, R)
    return dlqr_gain_matrix(sampled_problem(A, B, Q, R, control_period_s))


def lqr_gain(model_name: str, vehicle: Vehicle, speed_mps: float,
             weights: LqrWeights | None = None, design: str = "continuous",
             control_period_s: float = DEFAULT_CONTROL_PERIOD_S) -> np.ndarray:
    """LQR rear-steer gain row K (``delta_r = -K x``) in ``model_name``'s STATE order.

    Parameters
    ----------
    model_name : str
        ``2dof``, ``2dof-free`` or ``3dof``.
    vehicle : Vehicle
        Design (belief) vehicle.
    speed_mps : float
        Forward speed, m/s (> 0).
    weights : LqrWeights, optional
        Defaults to ``LqrWeights()``.
    design : str
        ``continuous`` (chapter 3) or ``discrete`` (sampled at ``control_period_s``).
    control_period_s : float
        Hold period of the discrete design, s.
    """
    weights = weights or LqrWeights()
    speed = check_speed(speed_mps)
    Q, R = weight_matrices(model_name, weights)
    A, B = get_model(model_name).matrices(vehicle, speed)
    rear = signal_map(model_name).rear_input
    return design_gain_matrix(A, B[:, [rear]], Q, R, design, control_period_s)[0]


def table_gains(speed_mps: float, params: np.ndarray, out: np.ndarray) -> None:
    """Gains interpolated linearly in a speed table, held above it
    (:class:`~fourws_control.base.GainFunction`): ``params`` = the ``n`` increasing grid
    speeds (m/s), then the ``n x len(Signal)`` gain table row by row."""
    n_sig = out.shape[0]
    n = params.shape[0] // (1 + n_sig)
    grid = params[:n]
    if speed_mps >= grid[n - 1]:
        for i in range(n_sig):
            out[i] = params[n + (n - 1) * n_sig + i]
        return
    j = int(np.searchsorted(grid, speed_mps, side="right")) - 1
    j = min(max(j, 0), n - 2)
    w = (speed_mps - grid[j]) / (grid[j + 1] - grid[j])
    for i in range(n_sig):
        out[i] = (1.0 - w) * params[n + j * n_sig + i] + w * params[n + (j + 1) * n_sig + i]


class LqrLaw(Law):
    """Gain-scheduled LQR rear steer (chapter 3), continuous or designed for the sampled loop.

    Parameters
    ----------
    belief_vehicle : Vehicle
        Design vehicle (needs ``steering`` for ``2dof-free``, ``roll`` for ``3dof``); its
        ``actuators`` give the discrete design's default ``p``.
    model : str
        Design model, one of :data:`LQR_MODELS`.
    design : str
        ``discrete`` (default: for the loop sampled at ``control_period_s``) or
        ``continuous`` (chapter 3); see the module docstring.
    q, q_steer, q_yaw, q_roll, q_roll_rate : float
        State weights (:class:`LqrWeights`).
    p : float, optional
        Rear-angle weight, rad^-2; default 1 (continuous) or
        :func:`rear_weight_from_actuator` (discrete).
    max_speed_mps : float
        Schedule grid top, m/s.
    speed_ratio : float
        Ratio of neighbouring grid speeds (> 1).
    min_speed_mps : float
        Grid bottom; below it the gains fade to zero.
    control_period_s : float
        Period of the loop, s: the hold period of the discrete design.
    """

    name = "lqr"
    summary = ("chapter 3 LQR minimizing sideslip, delta_r = -K(U) x, gain-scheduled; "
               "designed for the sampled loop unless design=continuous")
    gain_functions = (table_gains,)

    def __init__(self, belief_vehicle: Vehicle, *, model: str = "2dof",
                 design: str = LQR_DESIGNS[0], q: float = 10.0, q_steer: float = 0.0,
                 q_yaw: float = 0.0, q_roll: float = 0.0, q_roll_rate: float = 0.0,
                 p: float | None = None, max_speed_mps: float = DEFAULT_MAX_SPEED_MPS,
                 speed_ratio: float = DEFAULT_SPEED_RATIO,
                 min_speed_mps: float = DEFAULT_MIN_SPEED_MPS,
                 control_period_s: float = DEFAULT_CONTROL_PERIOD_S) -> None:
        super().__init__(belief_vehicle, min_speed_mps=min_speed_mps,
                         control_period_s=control_period_s)
        _check_model(model)
        _check_design(design)
        self.model = model
        self.design = design
        if p is None:
            p = 1.0 if design == "continuous" else rear_weight_from_actuator(belief_vehicle)
        self.weights = LqrWeights(q, q_steer, q_yaw, q_roll, q_roll_rate, p)
        top = check_option("max_speed_mps", max_speed_mps)
        ratio = check_option("speed_ratio", speed_ratio)
        if ratio <= 1.0:
            raise ParameterError("speed_ratio", f"must be > 1, got {speed_ratio!r}")
        if top <= self.min_speed_mps:
            raise ParameterError("max_speed_mps",
                                 f"must exceed min_speed_mps={self.min_speed_mps}, got {top}")
        n = int(math.ceil(math.log(top / self.min_speed_mps) / math.log(ratio))) + 1
        self.speed_grid_mps = np.geomspace(self.min_speed_mps, top, n)
        smap = signal_map(model)
        state_signal = {pos[1]: sig for sig, pos in smap.positions.items() if pos[0] == "state"}
        self.signals = tuple(sorted(state_signal.values()))
        table = np.zeros((n, len(Signal)))
        Q, R = weight_matrices(model, self.weights)
        matrices = get_model(model).matrices
        for i, u in enumerate(self.speed_grid_mps):
            A, B = matrices(belief_vehicle, float(u))
            K = design_gain_matrix(A, B[:, [smap.rear_input]], Q, R, design,
                                   self.control_period_s)[0]
            for idx, sig in state_signal.items():
                table[i, sig] = -K[idx]
        self.gain_table = table

        self._gains = GainFunction(table_gains, np.concatenate(
            [self.speed_grid_mps, table.reshape(-1)]))

    def gain_function(self) -> GainFunction:
        """:func:`table_gains` of the designed schedule."""
        return self._gains

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        return self._gains.evaluate(speed_mps)

    def describe(self) -> dict[str, object]:
        """Name, belief vehicle, design model, design, period and weights."""
        out = dict(super().describe())
        out.update(model=self.model, design=self.design, weights=self.weights.to_dict(),
                   max_speed_mps=float(self.speed_grid_mps[-1]))
        return out
