r"""``lqr``: chapter 3 optimal rear steer minimizing sideslip (linear quadratic regulator).

For a linear model :math:`\dot x = A x + B_r \delta_r + \dots` (the rear-steer column of the
model's B) the law is :math:`\delta_r = -K x` with

.. math::

    K = R^{-1} B_r^T P, \qquad 0 = A^T P + P A + Q - P B_r R^{-1} B_r^T P,

minimizing :math:`J = \int (x^T Q x + p\,\delta_r^2)\,dt` (eqs. 3.1-3.5). Design models and
their states: ``2dof`` ``[V, r]``, ``2dof-free`` ``[V, r, delta_f]``, ``3dof``
``[V, r, phi, phi_dot]`` (fourws sign conventions). Weights (all >= 0, ``p`` > 0):

``q``
    on the lateral velocity V, in (m/s)^-2 - the paper's "weight on sideslip": its Q (3.11)
    puts q in the 1-1 position of the state ``[V, r]``, and with ``p = 1`` this reproduces the
    gain magnitudes of Figures 3.5/3.6 (V gain to ~7 at q = 50, yaw-rate gain -0.3 to -0.9);
``q_steer``
    on the front road-wheel angle (free control, eq. 3.26's q2);
``q_yaw``, ``q_roll``, ``q_roll_rate``
    on r, phi, phi_dot (3-DOF, eq. 3.56's q2..q4);
``p``
    on the rear angle (eq. 3.12).

Scheduling: the gains are solved at construction on a speed grid from ``min_speed_mps`` to
``max_speed_mps`` (geometric, ratio ``speed_ratio`` between neighbours) and interpolated
linearly per call; above the grid the gains of ``max_speed_mps`` are held, below
``min_speed_mps`` they fade to zero
(:mod:`fourws_control.base`). The Riccati equation is solved with
``scipy.linalg.solve_continuous_are``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import scipy.linalg

from fourws_control.base import DEFAULT_MIN_SPEED_MPS, Law, Signal, check_option, check_speed
from fourws_control.signals import signal_map
from fourws_sim.errors import IncompatibleError, NonFiniteError, ParameterError, UnknownNameError
from fourws_sim.models import get_model
from fourws_sim.params import Vehicle

#: Models an LQR law can be designed on.
LQR_MODELS = ("2dof", "2dof-free", "3dof")
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


def lqr_gain(model_name: str, vehicle: Vehicle, speed_mps: float,
             weights: LqrWeights | None = None) -> np.ndarray:
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
    """
    weights = weights or LqrWeights()
    speed = check_speed(speed_mps)
    Q, R = weight_matrices(model_name, weights)
    A, B = get_model(model_name).matrices(vehicle, speed)
    rear = signal_map(model_name).rear_input
    return lqr_gain_matrix(A, B[:, [rear]], Q, R)[0]


class LqrLaw(Law):
    """Gain-scheduled LQR rear steer (chapter 3).

    Parameters
    ----------
    belief_vehicle : Vehicle
        Design vehicle (needs ``steering`` for ``2dof-free``, ``roll`` for ``3dof``).
    model : str
        Design model, one of :data:`LQR_MODELS`.
    q, q_steer, q_yaw, q_roll, q_roll_rate, p : float
        Weights (:class:`LqrWeights`).
    max_speed_mps : float
        Schedule grid top, m/s.
    speed_ratio : float
        Ratio of neighbouring grid speeds (> 1).
    min_speed_mps : float
        Grid bottom; below it the gains fade to zero.
    """

    name = "lqr"
    summary = "chapter 3 LQR minimizing sideslip, delta_r = -K(U) x, gain-scheduled"

    def __init__(self, belief_vehicle: Vehicle, *, model: str = "2dof", q: float = 10.0,
                 q_steer: float = 0.0, q_yaw: float = 0.0, q_roll: float = 0.0,
                 q_roll_rate: float = 0.0, p: float = 1.0,
                 max_speed_mps: float = DEFAULT_MAX_SPEED_MPS,
                 speed_ratio: float = DEFAULT_SPEED_RATIO,
                 min_speed_mps: float = DEFAULT_MIN_SPEED_MPS) -> None:
        super().__init__(belief_vehicle, min_speed_mps=min_speed_mps)
        _check_model(model)
        self.model = model
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
            K = lqr_gain_matrix(A, B[:, [smap.rear_input]], Q, R)[0]
            for idx, sig in state_signal.items():
                table[i, sig] = -K[idx]
        self.gain_table = table

    def _design_gains(self, speed_mps: float) -> np.ndarray:
        grid, table = self.speed_grid_mps, self.gain_table
        if speed_mps >= grid[-1]:
            return table[-1].copy()
        j = int(np.searchsorted(grid, speed_mps, side="right")) - 1
        j = min(max(j, 0), len(grid) - 2)
        w = (speed_mps - grid[j]) / (grid[j + 1] - grid[j])
        return (1.0 - w) * table[j] + w * table[j + 1]

    def describe(self) -> dict[str, object]:
        """Name, belief vehicle, design model and weights."""
        out = dict(super().describe())
        out.update(model=self.model, weights=self.weights.to_dict(),
                   max_speed_mps=float(self.speed_grid_mps[-1]))
        return out
