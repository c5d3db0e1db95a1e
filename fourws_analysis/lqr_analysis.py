# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""LQR rear-steer gains versus weight and speed (chapter 3, Figures 3.2-3.26), as data and plots.

Gains are reported as the paper plots them: :math:`K` of :math:`\delta_r = -K x` in the design
model's state order (so a positive lateral-velocity gain and a negative yaw-rate gain for the
2-DOF car, Figures 3.5/3.6). The closed-loop eigenvalues over the weight sweep are the root
loci of Figures 3.2, 3.8, 3.21 and 3.22.

Controllability through the rear steer (section 3.3.1): for the 2-DOF fixed-control model
:math:`\det[b, A b]\,U\,I_z^2 m^2/C_r^2 = C_f L (a b m - I_z) + b^2 m^2 U^2`, so the model is
uncontrollable at :math:`U_c = \sqrt{C_f L (I_z - a b m)}/(b m)` when :math:`I_z > a b m`
(eq. 3.14, re-derived), and controllable at every speed otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import control
import numpy as np

from fourws_analysis.linear import controllability
from fourws_control.base import check_option, check_speed
from fourws_control.bicycle import bicycle
from fourws_control.lqr import (LQR_MODELS, LqrWeights, lqr_gain_matrix, weight_matrices)
from fourws_control.signals import signal_map
from fourws_sim.errors import ParameterError, UnknownNameError
from fourws_sim.models import get_model
from fourws_sim.params import Vehicle

#: Default weights of the sweeps (Figures 3.5/3.6 run q from 0 to 50 at 10-40 m/s).
DEFAULT_Q_VALUES = (0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 30.0, 40.0, 50.0)
DEFAULT_SPEEDS_MPS = (10.0, 20.0, 30.0, 40.0)


@dataclass(frozen=True)
class LqrSweep:
    """LQR gains over a grid of speeds and sideslip weights.

    Attributes
    ----------
    model, vehicle : str
        Design model and vehicle names.
    speeds_mps : numpy.ndarray
        Speeds, m/s (n_speed).
    q_values : numpy.ndarray
        Sideslip (lateral-velocity) weights q (n_q).
    base_weights : LqrWeights
        The other weights (its ``q`` is replaced by each sweep value).
    state_names : tuple of str
        Design-model states.
    gains : numpy.ndarray
        K of ``delta_r = -K x``, shape (n_speed, n_q, n_states); units rad per state unit.
    eigenvalues : numpy.ndarray
        Closed-loop eigenvalues (1/s), shape (n_speed, n_q, n_states), complex.
    """

    model: str
    vehicle: str
    speeds_mps: np.ndarray
    q_values: np.ndarray
    base_weights: LqrWeights
    state_names: tuple[str, ...]
    gains: np.ndarray
    eigenvalues: np.ndarray

    def gain(self, state: str) -> np.ndarray:
        """Gain on ``state`` (e.g. ``"V"``), shape (n_speed, n_q)."""
        return self.gains[:, :, self.state_names.index(state)]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {
            "model": self.model, "vehicle": self.vehicle,
            "speeds_mps": self.speeds_mps.tolist(), "q_values": self.q_values.tolist(),
            "weights": self.base_weights.to_dict(), "state_names": list(self.state_names),
            "gain_convention": "delta_r = -K x",
            "gains": {s: self.gain(s).tolist() for s in self.state_names},
            "eigenvalues": [[[[z.real, z.imag] for z in row] for row in per_speed]
                            for per_speed in self.eigenvalues],
        }


def lqr_sweep(model_name: str, vehicle: Vehicle,
              speeds_mps: Sequence[float] = DEFAULT_SPEEDS_MPS,
              q_values: Sequence[float] = DEFAULT_Q_VALUES,
              base_weights: LqrWeights | None = None) -> LqrSweep:
    """LQR gains and closed-loop eigenvalues for every (speed, q) pair.

    Raises
    ------
    UnknownNameError
        Model not one of ``2dof``, ``2dof-free``, ``3dof``.
    ParameterError
        A speed not > 0, a negative weight, ``p`` not > 0, or an empty grid.
    """
    if model_name not in LQR_MODELS:
        raise UnknownNameError("LQR design model", str(model_name), list(LQR_MODELS))
    speeds = np.array([check_speed(u, "speeds_mps") for u in speeds_mps])
    qs = np.array([check_option("q", q, "nonnegative") for q in q_values])
    if speeds.size == 0 or qs.size == 0:
        raise ParameterError("speeds_mps/q_values", "need at least one speed and one weight")
    base = base_weights or LqrWeights()
    smap = signal_map(model_name)
    n = len(smap.state_names)
    gains = np.zeros((speeds.size, qs.size, n))
    eigs = np.zeros((speeds.size, qs.size, n), dtype=complex)
    model = get_model(model_name)
    for i, u in enumerate(speeds):
        A, B = model.matrices(vehicle, float(u))
        b = B[:, [smap.rear_input]]
        for j, q in enumerate(qs):
            w = LqrWeights(float(q), base.q_steer, base.q_yaw, base.q_roll, base.q_roll_rate,
                           base.p)
            Q, R = weight_matrices(model_name, w)
            K = lqr_gain_matrix(A, b, Q, R)
            gains[i, j] = K[0]
            lam = np.linalg.eigvals(A - b @ K)
            eigs[i, j] = lam[np.lexsort((lam.imag, lam.real))]
    return LqrSweep(model_name, vehicle.name, speeds, qs, base, smap.state_names, gains, eigs)


def plot_lqr_gains(sweep: LqrSweep, path: str | Path) -> Path:
    """Plot each state's gain versus q, one line per speed (Figures 3.5/3.6/3.13-3.15/3.23-3.26),
    and the root locus over q; write a PNG to ``path`` (matplotlib Agg backend)."""
    import matplotlib  # matplotlib: about 0.5 s to load, only the plots need it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: about 0.5 s to load, only the plots need it

    n = len(sweep.state_names)
    fig, axes = plt.subplots(1, n + 1, figsize=(4.0 * (n + 1), 3.6), squeeze=False)
    labels = {"V": "lateral velocity gain, rad/(m/s)", "R": "yaw rate gain, rad/(rad/s)",
              "DELTA_F": "front steer gain, rad/rad", "PHI": "roll angle gain, rad/rad",
              "PHI_DOT": "roll rate gain, rad/(rad/s)"}
    for k, state in enumerate(sweep.state_names):
        ax = axes[0, k]
        for i, u in enumerate(sweep.speeds_mps):
            ax.plot(sweep.q_values, sweep.gains[i, :, k], marker="o", ms=3, label=f"U = {u:g} m/s")
        ax.set_xlabel("weight q on lateral velocity")
        ax.set_ylabel(labels.get(state, f"gain on {state}"))
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    ax = axes[0, n]
    for i, u in enumerate(sweep.speeds_mps):
        z = sweep.eigenvalues[i].ravel()
        ax.plot(z.real, z.imag, ".", label=f"U = {u:g} m/s")
    ax.set_xlabel("Re, 1/s")
    ax.set_ylabel("Im, rad/s")
    ax.set_title("closed-loop eigenvalues over q")
    ax.grid(True, alpha=0.3)
    fig.suptitle(f"LQR rear-steer gains (delta_r = -K x), {sweep.model}, {sweep.vehicle}")
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def uncontrollable_speed_2dof(vehicle: Vehicle) -> float | None:
    """Speed (m/s) where the 2-DOF model is not controllable by rear steer (eq. 3.14).

    None when ``I_z <= a b m`` (controllable at every speed > 0).
    """
    p = bicycle(vehicle)
    arg = p.cf * p.L * (p.iz - p.a * p.b * p.m)
    if arg <= 0.0:
        return None
    return math.sqrt(arg) / (p.b * p.m)


def controllability_determinants(model_name: str, vehicle: Vehicle,
                                 speeds_mps: Sequence[float]) -> np.ndarray:
    """det of the rear-steer controllability matrix at each speed (zero = uncontrollable)."""
    model = get_model(model_name)
    rear = signal_map(model_name).rear_input
    out = []
    for u in speeds_mps:
        A, B = model.matrices(vehicle, check_speed(u, "speeds_mps"))
        out.append(controllability(A, B[:, rear]).determinant)
    return np.array(out)


def detectable(model_name: str, vehicle: Vehicle, speed_mps: float,
               weights: LqrWeights | None = None) -> bool:
    """Rank test of section 3.3.2: is ``(Q^1/2, A)`` observable (rank n)?"""
    Q, _ = weight_matrices(model_name, weights or LqrWeights())
    A, _ = get_model(model_name).matrices(vehicle, check_speed(speed_mps))
    w, v = np.linalg.eigh(Q)
    sqrt_q = (v * np.sqrt(np.clip(w, 0.0, None))) @ v.T
    return int(np.linalg.matrix_rank(control.obsv(A, sqrt_q))) == A.shape[0]
