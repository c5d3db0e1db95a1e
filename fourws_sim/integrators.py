# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Time integrators, chosen by name: ``rk4`` (fixed step), ``euler`` (fixed step),
``semi_implicit_euler`` (fixed step, the compiled 8-DOF models only) and ``solve_ivp`` (SciPy
adaptive reference).

``semi_implicit_euler`` is the half-implicit Euler of multibody vehicle codes: the rates
(velocities, roll and yaw rate, wheel spins, lags) take an explicit step from the forces at the
step's start, then the pose (roll angle, heading, position, free steering angle) a step with the
*new* rates. First order and one right-hand side per step like ``euler``, but symplectic for
the roll spring (an undamped oscillator's energy stays bounded instead of growing). It needs
the model's split into pose and rates, which the compiled 8-DOF kernels have
(``eightdof_kernels.semi_implicit_euler``); ``bench/work_precision.py`` compares the three
fixed-step schemes by error against ``solve_ivp`` per cost.

An integrator advances a model ``f(t, x, u, p) -> dx/dt`` with the input ``u`` held constant
over the interval (zero-order hold, the way a simulator node applies its latest command)::

    integ = get_integrator("rk4")
    x_next = integ.advance(f, t, x, u, p, dt_s=1e-3, n_steps=10)

The 8-DOF simulator also has compiled versions of ``rk4`` and ``euler``
(:func:`fourws_sim.models.eightdof.kernels_for`); :attr:`Integrator.compiled_name` names the
kernel a compiled model should use, ``None`` for ``solve_ivp``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from fourws_sim.errors import NonFiniteError, ParameterError, UnknownNameError

Derivative = Callable[[float, np.ndarray, np.ndarray, Any], np.ndarray]

#: Default step, s (1 kHz: 10 steps per 100-Hz simulator tick).
DEFAULT_STEP_S = 1.0e-3
#: Tolerances of the ``solve_ivp`` reference (tight: it is the offline reference).
SOLVE_IVP_RTOL = 1.0e-10
SOLVE_IVP_ATOL = 1.0e-10
#: Method of the ``solve_ivp`` reference (8th-order explicit; the models are not stiff at
#: these tolerances except at standstill, where LSODA would be the alternative).
SOLVE_IVP_METHOD = "DOP853"


def _check_step(dt_s: float, n_steps: int) -> None:
    if not (isinstance(dt_s, (int, float)) and np.isfinite(dt_s) and dt_s > 0.0):
        raise ParameterError("dt_s", f"must be a finite number > 0, got {dt_s!r}")
    if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)) or n_steps < 0:
        raise ParameterError("n_steps", f"must be an integer >= 0, got {n_steps!r}")


@dataclass(frozen=True)
class Integrator:
    """A named integration scheme.

    Attributes
    ----------
    name : str
        Registry name.
    compiled_name : str or None
        Name of the matching compiled kernel (``"rk4"``, ``"euler"``,
        ``"semi_implicit_euler"``) or None.
    """

    name: str
    compiled_name: str | None
    _advance: Callable[..., np.ndarray]
    #: The models it can integrate (None: every model; names as ``fourws_sim.simulator``'s
    #: ``EIGHT_DOF``, ``EIGHT_DOF_FREE``).
    models: tuple[str, ...] | None = None

    def check_model(self, model: str, source: str | None = None) -> None:
        """Raise :class:`ParameterError` (field ``integrator``) if it cannot integrate
        ``model`` (``semi_implicit_euler`` needs the 8-DOF models' split into pose and
        rates)."""
        if self.models is not None and model not in self.models:
            raise ParameterError("integrator", f"{self.name} is for the "
                                 f"{', '.join(self.models)} models (their pose and rates are "
                                 f"split); model {model} takes rk4 or euler", source)

    def advance(self, f: Derivative, t: float, x: np.ndarray, u: np.ndarray, p: Any,
                dt_s: float = DEFAULT_STEP_S, n_steps: int = 1) -> np.ndarray:
        """State after ``n_steps`` steps of ``dt_s`` s from ``(t, x)`` with input ``u`` held.

        Parameters
        ----------
        f : callable
            ``f(t, x, u, p) -> dx/dt``.
        t : float
            Start time, s.
        x : numpy.ndarray
            Start state (not modified).
        u : numpy.ndarray
            Input held over the interval.
        p : object
            Model parameters passed through to ``f``.
        dt_s : float
            Step in s (for ``solve_ivp`` the output interval: it chooses its own steps).
        n_steps : int
            Number of steps.

        Returns
        -------
        numpy.ndarray
            New state.

        Raises
        ------
        ParameterError
            If ``dt_s`` is not > 0 or ``n_steps`` is not a non-negative integer.
        NonFiniteError
            If the state becomes NaN or infinite (``solve_ivp``: if the solver fails).
        """
        _check_step(dt_s, n_steps)
        return self._advance(f, float(t), np.array(x, dtype=float),
                             np.asarray(u, dtype=float), p, float(dt_s), int(n_steps))


def _rk4(f: Derivative, t: float, x: np.ndarray, u: np.ndarray, p: Any, dt: float,
         n: int) -> np.ndarray:
    for k in range(n):
        tk = t + k * dt
        k1 = f(tk, x, u, p)
        k2 = f(tk + 0.5 * dt, x + 0.5 * dt * k1, u, p)
        k3 = f(tk + 0.5 * dt, x + 0.5 * dt * k2, u, p)
        k4 = f(tk + dt, x + dt * k3, u, p)
        x = x + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x


def _euler(f: Derivative, t: float, x: np.ndarray, u: np.ndarray, p: Any, dt: float,
           n: int) -> np.ndarray:
    for k in range(n):
        x = x + dt * f(t + k * dt, x, u, p)
    return x


def _semi_implicit(f: Derivative, t: float, x: np.ndarray, u: np.ndarray, p: Any, dt: float,
                   n: int) -> np.ndarray:
    if n == 0:
        return x
    raise ParameterError("integrator", "semi_implicit_euler needs the model's split into pose "
                         "and rates, which only the compiled 8-DOF models have (8dof, "
                         "8dof-free); use rk4 or euler")


def _solve_ivp(f: Derivative, t: float, x: np.ndarray, u: np.ndarray, p: Any, dt: float,
               n: int) -> np.ndarray:
    from scipy.integrate import solve_ivp  # scipy: only the offline reference needs it

    if n == 0:
        return x
    sol = solve_ivp(lambda tt, xx: f(tt, xx, u, p), (t, t + n * dt), x,
                    method=SOLVE_IVP_METHOD, rtol=SOLVE_IVP_RTOL, atol=SOLVE_IVP_ATOL)
    if not sol.success:
        raise NonFiniteError(f"solve_ivp failed at t = {sol.t[-1]:.6g} s: {sol.message}")
    return np.asarray(sol.y[:, -1], dtype=float)


INTEGRATORS: dict[str, Integrator] = {
    "rk4": Integrator("rk4", "rk4", _rk4),
    "euler": Integrator("euler", "euler", _euler),
    "semi_implicit_euler": Integrator("semi_implicit_euler", "semi_implicit_euler",
                                      _semi_implicit, models=("8dof", "8dof-free")),
    "solve_ivp": Integrator("solve_ivp", None, _solve_ivp),
}


def get_integrator(name: str) -> Integrator:
    """Integrator by name.

    Raises
    ------
    UnknownNameError
        If ``name`` is not one of ``euler``, ``rk4``, ``semi_implicit_euler``, ``solve_ivp``
        (the message lists them).
    """
    try:
        return INTEGRATORS[name]
    except (KeyError, TypeError):
        raise UnknownNameError("integrator", str(name), list(INTEGRATORS)) from None
