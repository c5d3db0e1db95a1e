# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Numerical linearization of any fourws model about a trim, and eigenvalues vs speed.

Central finite differences of the model's ``derivatives(t, x, u, p)``:

.. math::

    A_{:,j} = \frac{f(x + h_j e_j, u) - f(x - h_j e_j, u)}{2 h_j}, \qquad
    B_{:,j} = \frac{f(x, u + h_j e_j) - f(x, u - h_j e_j)}{2 h_j},

with :math:`h_j = \epsilon\,\max(|x_j|, 1)` and :math:`\epsilon = 10^{-6}` (about the cube
root of machine precision scaled for the smooth tire curves; truncation error O(h^2)).
For a linear model this reproduces ``(A, B)`` to rounding (tested).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from fourws_analysis.bag import MetricUnavailableError
from fourws_analysis.memo import Memo
from fourws_control import Law, make_law
from fourws_sim.models import get_model

#: Relative finite-difference step.
REL_STEP = 1e-6

Derivatives = Callable[[float, np.ndarray, np.ndarray, Any], np.ndarray]


def model_derivatives(mod: Any) -> Derivatives:
    """The derivatives a linearization of model module ``mod`` differentiates: its compiled
    right-hand side where it has one (``derivatives_compiled``: the 8-DOF, equal to its
    NumPy reference to round-off), else its ``derivatives``."""
    return getattr(mod, "derivatives_compiled", mod.derivatives)


def jacobians(derivatives: Derivatives, x0: np.ndarray, u0: np.ndarray, p: Any,
              t: float = 0.0, rel_step: float = REL_STEP) -> tuple[np.ndarray, np.ndarray]:
    """State and input Jacobians (A, B) of ``derivatives`` at ``(x0, u0)``.

    Parameters
    ----------
    derivatives : callable
        ``f(t, x, u, p) -> dx/dt``.
    x0, u0 : ndarray
        Trim state and input (model's ``STATE``/``INPUT`` order).
    p : object
        The model's parameter object.
    t : float
        Time, s (models are time-invariant; passed through).
    rel_step : float
        Relative step.
    """
    x0 = np.asarray(x0, dtype=float)
    u0 = np.asarray(u0, dtype=float)

    def column(vec: np.ndarray, j: int, which: str) -> np.ndarray:
        h = rel_step * max(abs(vec[j]), 1.0)
        plus, minus = vec.copy(), vec.copy()
        plus[j] += h
        minus[j] -= h
        if which == "x":
            fp, fm = derivatives(t, plus, u0, p), derivatives(t, minus, u0, p)
        else:
            fp, fm = derivatives(t, x0, plus, p), derivatives(t, x0, minus, p)
        return (np.asarray(fp, dtype=float) - np.asarray(fm, dtype=float)) / (2.0 * h)

    a = np.column_stack([column(x0, j, "x") for j in range(x0.size)])
    b = np.column_stack([column(u0, j, "u") for j in range(u0.size)]) if u0.size else \
        np.zeros((x0.size, 0))
    return a, b


@dataclass
class EigenSweep:
    """Eigenvalues of a linearized model over forward speed.

    Attributes
    ----------
    model : str
    speed_mps : ndarray (n_speeds,)
    eigenvalues : ndarray (n_speeds, n_states) of complex, 1/s
    """

    model: str
    speed_mps: np.ndarray
    eigenvalues: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"model": self.model, "speed_mps": self.speed_mps.tolist(),
                "eigenvalues_re_per_s": self.eigenvalues.real.tolist(),
                "eigenvalues_im_per_s": self.eigenvalues.imag.tolist()}


def _trim(mod: Any, vehicle: Any, speed: float) -> tuple[np.ndarray, np.ndarray, Any]:
    """Straight-running trim of a model at ``speed``: (x0, u0, p)."""
    linear = hasattr(mod, "matrices")  # linear models take the speed as a parameter
    p = mod.params_for(vehicle, speed) if linear else mod.params_for(vehicle)
    n_x, n_u = len(mod.STATE), len(mod.INPUT)
    if linear:
        return np.zeros(n_x), np.zeros(n_u), p
    for name in ("trim_state", "straight_state", "initial_state"):
        fn = getattr(mod, name, None)
        if fn is not None:
            x0 = np.asarray(fn(vehicle, speed) if name != "initial_state" else
                            fn(p, speed), dtype=float)
            return x0, np.zeros(n_u), p
    raise MetricUnavailableError(
        f"eigenvalues vs speed: model {mod.__name__} has no straight-running trim function "
        "(trim_state/straight_state/initial_state)")


@dataclass(frozen=True)
class EightDofLoop:
    """The 8-DOF linearized at straight running and a law written in its state and input
    order (:meth:`fourws_control.base.Law.linear_gains`): ``delta_r = K_x x + K_u u``. With
    fixed steering control (model ``8dof``) the law's front-angle gain multiplies the driver's
    input ``DELTA_F``; with the free steering system (``8dof-free``) the law sees the steering
    system's angle, the state ``DELTA_S`` (the model declares it, ``FRONT_ANGLE_STATE``), as
    the paper's free-control laws take the front angle state (ch. 3.4/4.4).

    Attributes
    ----------
    a, b : numpy.ndarray
        Open-loop Jacobians (``STATE`` x ``STATE``, ``STATE`` x ``INPUT``), SI.
    gains : LinearGains
        The law in the model's order.
    model : module
        The model module (``STATE``, ``INPUT``).
    """

    a: np.ndarray
    b: np.ndarray
    gains: Any
    model: Any

    @property
    def closed(self) -> np.ndarray:
        """The closed-loop state matrix ``a + b_r K_x``."""
        return self.a + np.outer(self.b[:, self.model.INPUT.DELTA_R], self.gains.K_x)

    def lateral_eigenvalues(self, tol: float = 1e-6) -> np.ndarray:
        """Closed-loop eigenvalues (1/s) without the zero ones (position, heading, and the
        speed-wheel momentum mode at a trim without drag): ``|lambda| > tol``."""
        ev = np.linalg.eigvals(self.closed)
        return ev[np.abs(ev) > tol]


#: Open-loop Jacobians kept per model, vehicle and speed (about 9 kB each): a critical-speed
#: search samples up to 200 speeds, the same for every law of a car (a demo's three laws, a
#: study's points), and the run's overlays and eigenvalue sweep ask again.
_JACOBIAN_CACHE: Memo[tuple[np.ndarray, np.ndarray]] = Memo(1024)


def straight_running_jacobians(vehicle: Any, speed_mps: float, model: str = "8dof"
                               ) -> tuple[np.ndarray, np.ndarray]:
    """Open-loop Jacobians ``(A, B)`` of ``model`` (``8dof`` or ``8dof-free``) linearized by
    :func:`jacobians` at straight running at ``speed_mps`` (m/s), new arrays each call;
    computed once per model, vehicle and speed in this process (:data:`_JACOBIAN_CACHE`:
    the same numbers, the finite differences are deterministic)."""
    mod = get_model(model)

    def compute() -> tuple[np.ndarray, np.ndarray]:
        p = mod.params_for(vehicle)
        return jacobians(model_derivatives(mod), mod.initial_state(p, speed_mps),
                         np.zeros(len(mod.INPUT)), p)

    key = f"{model}|{float(speed_mps)!r}|{vehicle.cache_key()}"
    kept = _JACOBIAN_CACHE.get(key, compute)
    assert kept is not None  # (compute returns the matrices or raises)
    return kept[0].copy(), kept[1].copy()


def eightdof_loop(vehicle: Any, speed_mps: float, law: Any = "fws",
                  belief_vehicle: Any = None, law_options: Mapping[str, Any] | None = None,
                  free_steering: bool = False) -> EightDofLoop:
    """Linearize the 8-DOF (``8dof``, or ``8dof-free`` with ``free_steering``) at straight
    running at ``speed_mps`` (m/s) by finite differences, with the law written in its order
    (:class:`EightDofLoop`). ``law`` is a name (built on the belief vehicle with
    ``law_options``) or a built :class:`fourws_control.Law`."""
    name = "8dof-free" if free_steering else "8dof"
    mod = get_model(name)
    a, b = straight_running_jacobians(vehicle, speed_mps, name)
    law_obj = law if isinstance(law, Law) else make_law(
        law, belief_vehicle if belief_vehicle is not None else vehicle,
        **dict(law_options or {}))
    return EightDofLoop(a, b, law_obj.linear_gains(name, vehicle, speed_mps), mod)


def eigenvalues_vs_speed(vehicle: Any, speeds_mps: Sequence[float], model: str = "8dof",
                         drop_zero: bool = True) -> EigenSweep:
    """Eigenvalues of ``model`` linearized at straight running for each speed.

    Parameters
    ----------
    vehicle : Vehicle
    speeds_mps : sequence of float
        Forward speeds, m/s.
    model : str
        Model name (any registered model).
    drop_zero : bool
        Keep the zero eigenvalues (heading, position) out? They are padded with NaN so every
        row has the same length.

    Raises
    ------
    MetricUnavailableError
        If the model cannot be trimmed.
    UnknownNameError
        Unknown model name.
    """
    mod = get_model(model)
    rows = []
    for speed in speeds_mps:
        x0, u0, p = _trim(mod, vehicle, float(speed))
        a, _ = jacobians(model_derivatives(mod), x0, u0, p)
        ev = np.linalg.eigvals(a)
        if drop_zero:
            ev = np.where(np.abs(ev) < 1e-9, np.nan, ev)
        rows.append(ev[np.argsort(-np.nan_to_num(ev.real, nan=-np.inf))])
    return EigenSweep(model, np.asarray(speeds_mps, dtype=float), np.array(rows))
