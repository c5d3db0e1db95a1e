# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Linear analysis of the linear vehicle models closed with a rear-steer law.

Closing the loop
----------------
A linear model :math:`\dot x = A x + B u` (``fourws_sim.models``, ``STATE``/``INPUT`` order)
and a law written for it, :math:`\delta_r = K_x x + K_u u`
(:meth:`fourws_control.base.Law.linear_gains`), give

.. math::

    \dot x = (A + b_r K_x)\,x + (B_d + b_r K_{u,d})\,u_d

with :math:`b_r` the rear-steer column of B and :math:`u_d` the driver inputs (front angle,
or steering torque for free control). Everything else here works on that closed loop:
eigenvalues with natural frequencies (Hz) and damping ratios, the Routh-Hurwitz array of its
characteristic polynomial, controllability through the rear steer, the critical speed,
transfer functions, Bode data (frequencies in Hz), steady-state gains and the Lyapunov
check of chapter 5. The closed loop is a python-control ``StateSpace``
(:attr:`ClosedLoop.system`, states, inputs and outputs named), the one representation of a
linear model in fourws (:func:`linear_system` gives it with the run channels' names, as the
analysis of recorded runs compares with it); scipy solves the Lyapunov equation.
:func:`sampled_closed_loop` closes the same loop as the controller runs it, the command held
over each control period (zero-order hold): eigenvalues in the z-plane and mapped to the
s-plane, ``ln(z) / T``. Results are dataclasses with ``to_dict()`` for JSON.

Outputs of the transfer functions (SI, per unit of the driver input): ``yaw_rate`` (rad/s),
``lateral_acceleration`` :math:`a_y = \dot V + U r` (m/s^2), ``sideslip``
:math:`\beta = V/U` (rad, small angle), ``lateral_velocity`` (m/s), ``roll`` (rad, 3-DOF)
and ``front_steer`` (rad, free control).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import control
import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.signal

from fourws_analysis.frequency import break_phase_jumps, dc_gain
from fourws_analysis.units import ROAD_WHEEL
from fourws_control.base import Law, LinearGains, check_option, check_speed
from fourws_control.registry import make_law
from fourws_control.signals import LINEAR_MODELS, signal_map
from fourws_sim.errors import IncompatibleError, NonFiniteError, ParameterError, \
    UnknownNameError
from fourws_sim.models import get_model
from fourws_sim.params import Vehicle

#: Default speed range searched for a critical speed, m/s.
CRITICAL_SPEED_RANGE_MPS = (1.0, 100.0)
#: Number of speeds sampled before the sign change is refined with brentq.
_CRITICAL_SPEED_SAMPLES = 200
#: Absolute tolerance of the critical-speed root, m/s.
_CRITICAL_SPEED_XTOL_MPS = 1e-6
#: Real parts within this of zero (1/s) count as on the imaginary axis (marginal).
MARGINAL_TOL_PER_S = 1e-9
#: Default Bode frequency grid, Hz.
DEFAULT_BODE_HZ = (0.01, 10.0)
_DEFAULT_BODE_POINTS = 200


def _law(law: Law | str | None, vehicle: Vehicle) -> Law:
    if law is None:
        return make_law("fws", vehicle)
    if isinstance(law, str):
        return make_law(law, vehicle)
    return law


def _check_model_name(model_name: str) -> None:
    if model_name not in LINEAR_MODELS:
        raise UnknownNameError("linear model", str(model_name), list(LINEAR_MODELS))


@dataclass(frozen=True)
class ClosedLoop:
    """A linear model closed with a law at one speed.

    Attributes
    ----------
    model, law : str
        Model and law names.
    speed_mps : float
        Forward speed U, m/s.
    system : control.StateSpace
        The closed loop: states named by the model's ``STATE``, inputs the driver's (model
        ``INPUT`` names), outputs the standard outputs of the module docstring (SI).
    A_open, b_rear : numpy.ndarray
        Open-loop state matrix and rear-steer column (for controllability).
    """

    model: str
    law: str
    speed_mps: float
    system: control.StateSpace
    A_open: np.ndarray
    b_rear: np.ndarray

    @property
    def A(self) -> np.ndarray:
        """Closed-loop state matrix (n x n), 1/s."""
        return self.system.A

    @property
    def B(self) -> np.ndarray:
        """Closed-loop input matrix for the driver inputs (n x m)."""
        return self.system.B

    @property
    def state_names(self) -> tuple[str, ...]:
        """Model ``STATE`` names."""
        return tuple(self.system.state_labels)

    @property
    def input_names(self) -> tuple[str, ...]:
        """Driver-input names (model ``INPUT`` names)."""
        return tuple(self.system.input_labels)

    def state_index(self, name: str) -> int:
        """Index of state ``name`` (e.g. ``"V"``)."""
        return self.state_names.index(name)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (matrices as nested lists, SI)."""
        return {"model": self.model, "law": self.law, "speed_mps": self.speed_mps,
                "A": self.A.tolist(), "B": self.B.tolist(),
                "state_names": list(self.state_names), "input_names": list(self.input_names)}


def closed_loop(model_name: str, vehicle: Vehicle, law: Law | str | None,
                speed_mps: float) -> ClosedLoop:
    """Close linear model ``model_name`` of ``vehicle`` with ``law`` at ``speed_mps``.

    Parameters
    ----------
    model_name : str
        ``2dof``, ``2dof-free``, ``2dof-lagged`` or ``3dof``.
    vehicle : Vehicle
        The (true) vehicle of the model.
    law : Law or str or None
        A law object (its belief vehicle may differ), a law name (built on ``vehicle``), or
        None for ``fws``.
    speed_mps : float
        Forward speed in m/s (> 0).

    Raises
    ------
    ParameterError
        Speed not > 0, or the vehicle lacks a subsystem the model needs.
    IncompatibleError
        The law cannot be written for the model.
    """
    speed = check_speed(speed_mps)
    A_cl, B_cl, law_obj, A, B = closed_loop_matrices(model_name, vehicle, law, speed)
    smap = signal_map(model_name)
    names, C, D = _standard_outputs(A_cl, B_cl, smap.state_names, speed)
    inputs = [smap.input_names[i] for i in smap.driver_inputs]
    system = control.ss(A_cl, B_cl, C, D, inputs=inputs, outputs=names,
                        states=list(smap.state_names), name=f"{model_name} {law_obj.name}")
    return ClosedLoop(model_name, law_obj.name, speed, system, A, B[:, smap.rear_input])


def closed_loop_matrices(model_name: str, vehicle: Vehicle, law: Law | str | None,
                         speed_mps: float
                         ) -> tuple[np.ndarray, np.ndarray, Law, np.ndarray, np.ndarray]:
    """The matrices of :func:`closed_loop` without its state-space object (a study's
    eigenvalues need A alone): ``(A_cl, B_cl, law, A_open, B_open)``; the same checks and
    errors."""
    _check_model_name(model_name)
    speed = check_speed(speed_mps)
    law_obj = _law(law, vehicle)
    A, B = get_model(model_name).matrices(vehicle, speed)
    smap = signal_map(model_name)
    g = law_obj.linear_gains(model_name, vehicle, speed)
    A_cl, B_cl = close_loop(A, B, g, smap.rear_input, smap.driver_inputs)
    if not (np.all(np.isfinite(A_cl)) and np.all(np.isfinite(B_cl))):
        raise NonFiniteError(f"closed loop {model_name}/{law_obj.name} at {speed} m/s "
                             "is not finite")
    return A_cl, B_cl, law_obj, A, B


def close_loop(A: np.ndarray, B: np.ndarray, gains: LinearGains, rear_input: int,
               driver_inputs: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    r"""Close ``dx/dt = A x + B u`` with the law ``delta_r = K_x x + K_u u``.

    .. math::

        A_{cl} = A + b_r K_x, \qquad B_{cl} = B_d + b_r K_{u,d}

    with :math:`b_r` column ``rear_input`` of B and :math:`d` the ``driver_inputs``.

    Parameters
    ----------
    A, B : numpy.ndarray
        Open-loop matrices (n x n, n x m) in the order of ``gains``.
    gains : LinearGains
        The law in the model's state/input order (:meth:`fourws_control.base.Law.linear_gains`).
    rear_input : int
        Index of the rear-steer input.
    driver_inputs : sequence of int
        Inputs kept as the closed loop's inputs, in order.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``A_cl`` (n x n) and ``B_cl`` (n x len(driver_inputs)).
    """
    b_r = B[:, rear_input]
    drv = list(driver_inputs)
    return A + np.outer(b_r, gains.K_x), B[:, drv] + np.outer(b_r, gains.K_u[drv])


# ----------------------------------------------------------------------------- eigenvalues

@dataclass(frozen=True)
class Mode:
    """One eigenvalue with its natural frequency and damping ratio.

    ``natural_frequency_hz = |lambda| / (2 pi)``, ``damping_ratio = -Re(lambda)/|lambda|``
    (1 for a stable real root, negative when unstable).
    """

    eigenvalue: complex
    natural_frequency_hz: float
    damping_ratio: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (eigenvalue as ``[re, im]`` in 1/s)."""
        return {"eigenvalue": [self.eigenvalue.real, self.eigenvalue.imag],
                "natural_frequency_hz": self.natural_frequency_hz,
                "damping_ratio": self.damping_ratio}


def modes(A: np.ndarray) -> list[Mode]:
    """Eigenvalues of ``A`` (1/s) sorted by real part, with frequency (Hz) and damping."""
    A = np.asarray(A, dtype=float)
    if not np.all(np.isfinite(A)):
        raise NonFiniteError("state matrix is not finite")
    lam = np.linalg.eigvals(A)
    lam = lam[np.lexsort((lam.imag, lam.real))]
    out = []
    for z in lam:
        z = complex(z)
        wn = abs(z)
        zeta = -z.real / wn if wn > 0.0 else 1.0
        out.append(Mode(z, wn / (2.0 * math.pi), zeta))
    return out


def is_stable(A: np.ndarray, tol: float = MARGINAL_TOL_PER_S) -> bool:
    """True when every eigenvalue of ``A`` has real part < ``-tol`` (asymptotic stability)."""
    return bool(np.max(np.linalg.eigvals(np.asarray(A, dtype=float)).real) < -tol)


# ------------------------------------------------------------------------------ sampled loop

@dataclass(frozen=True)
class SampledLoop:
    r"""A continuous model closed with a law whose command is held over each control period.

    The law runs once per period ``T`` and the actuator holds its command (zero-order hold),
    so from tick to tick :math:`x_{k+1} = (\Phi + \Gamma_r K_x) x_k + \dots` with
    :math:`\Phi = e^{A T}`, :math:`\Gamma_r = \int_0^T e^{A t} dt\, b_r`.

    Attributes
    ----------
    period_s : float
        Control period T, s.
    Phi : numpy.ndarray
        Closed-loop transition matrix over one period (n x n).
    eigenvalues : numpy.ndarray
        Its eigenvalues z (z-plane, dimensionless); stable when all ``|z| < 1``.
    """

    period_s: float
    Phi: np.ndarray
    eigenvalues: np.ndarray

    @property
    def s_plane(self) -> np.ndarray:
        """The eigenvalues mapped to the s-plane, ``ln(z) / T`` (1/s; principal branch, so
        imaginary parts within +-pi/T: a negative real z maps to pi/T, the Nyquist rate)."""
        return np.log(self.eigenvalues.astype(complex)) / self.period_s

    @property
    def spectral_radius(self) -> float:
        """Largest ``|z|``."""
        return float(np.max(np.abs(self.eigenvalues)))

    def radius(self, min_abs_s_per_s: float = 0.0) -> float:
        """Largest ``|z|`` of the modes with ``|ln(z)/T| > min_abs_s_per_s`` (1/s), e.g. 1e-6
        to leave out modes at z = 1 that steering does not reach (an 8-DOF's speed and wheel
        spin at a trim without drag); nan when no mode is left."""
        keep = np.abs(self.s_plane) > min_abs_s_per_s
        return float(np.max(np.abs(self.eigenvalues[keep]))) if np.any(keep) else math.nan

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (``z`` and ``s_per_s`` as ``[re, im]`` pairs;
        ``spectral_radius_s_nonzero`` is :meth:`radius` over modes with ``|s| > 1e-6``)."""
        return {"period_s": self.period_s, "spectral_radius": self.spectral_radius,
                "spectral_radius_s_nonzero": self.radius(1e-6),
                "z": [[float(z.real), float(z.imag)] for z in self.eigenvalues],
                "s_per_s": [[float(e.real), float(e.imag)] for e in self.s_plane]}


def sample_loop(A_open: np.ndarray, b_rear: np.ndarray, K_x: np.ndarray,
                period_s: float) -> SampledLoop:
    """Close ``dx/dt = A_open x + b_rear delta_r`` with ``delta_r = K_x x`` held over
    ``period_s`` (zero-order hold, ``scipy.signal.cont2discrete``).

    Parameters
    ----------
    A_open : numpy.ndarray
        Open-loop state matrix (n x n), 1/s.
    b_rear : numpy.ndarray
        Rear-steer column (n,).
    K_x : numpy.ndarray
        Law gains on the states (n,), rad per state unit.
    period_s : float
        Control period, s (> 0).

    Raises
    ------
    ParameterError
        Period not finite and > 0.
    NonFiniteError
        Non-finite matrices.
    """
    T = check_option("period_s", period_s)
    A_open = np.asarray(A_open, dtype=float)
    b = np.asarray(b_rear, dtype=float).reshape(-1, 1)
    k = np.asarray(K_x, dtype=float).reshape(1, -1)
    if not (np.all(np.isfinite(A_open)) and np.all(np.isfinite(b)) and np.all(np.isfinite(k))):
        raise NonFiniteError("sampled loop: non-finite model or gains")
    n = A_open.shape[0]
    phi, gamma, *_ = scipy.signal.cont2discrete(
        (A_open, b, np.zeros((1, n)), np.zeros((1, 1))), T, method="zoh")
    phi_cl = phi + gamma @ k
    z = np.linalg.eigvals(phi_cl)
    return SampledLoop(T, phi_cl, z[np.lexsort((z.imag, -np.abs(z)))])


def sampled_closed_loop(model_name: str, vehicle: Vehicle, law: Law | str | None,
                        speed_mps: float, period_s: float | None = None) -> SampledLoop:
    """:func:`closed_loop` with the law's command held over each control period.

    Parameters
    ----------
    model_name, vehicle, law, speed_mps
        As :func:`closed_loop`.
    period_s : float, optional
        Control period, s; default the law's ``control_period_s`` (the period it was built
        for).
    """
    law_obj = _law(law, vehicle)
    cl = closed_loop(model_name, vehicle, law_obj, speed_mps)
    g = law_obj.linear_gains(model_name, vehicle, cl.speed_mps)
    T = law_obj.control_period_s if period_s is None else period_s
    return sample_loop(cl.A_open, cl.b_rear, g.K_x, T)


# ------------------------------------------------------------------------------ Routh-Hurwitz

@dataclass(frozen=True)
class RouthHurwitz:
    """Routh-Hurwitz test of a characteristic polynomial (Appendix A).

    Attributes
    ----------
    coefficients : list of float
        ``[a_n, ..., a_0]`` of ``a_n s^n + ... + a_0`` (monic, from the closed-loop A).
    array : list of list of float
        The Routh array rows (zero-padded).
    first_column : list of float
        First column of the array; all > 0 is necessary and sufficient for stability.
    conditions : list of dict
        Named conditions ``{name, value, satisfied}``: every coefficient ``a_k > 0``, and the
        Hurwitz inequalities (cubic: ``a2 a1 - a3 a0 > 0``; quartic: ``a3 a2 - a4 a1 > 0`` and
        ``a1 (a3 a2 - a4 a1) - a0 a3^2 > 0``, the paper's eqs. 4.59, 6.67, 6.68); for other
        orders the first-column entries.
    sign_changes : int
        Sign changes of the first column = number of right-half-plane roots.
    stable : bool
        All conditions satisfied.
    """

    coefficients: list[float]
    array: list[list[float]]
    first_column: list[float]
    conditions: list[dict[str, Any]]
    sign_changes: int
    stable: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"coefficients": self.coefficients, "first_column": self.first_column,
                "conditions": self.conditions, "sign_changes": self.sign_changes,
                "stable": self.stable, "array": self.array}


def routh_array(coefficients: Sequence[float], eps: float = 1e-12) -> np.ndarray:
    """Routh array of ``coefficients`` (highest power first).

    A zero first-column entry is replaced by ``eps`` times the largest coefficient magnitude
    (the usual epsilon method), which keeps the sign-change count right for isolated zeros.
    """
    c = np.asarray(coefficients, dtype=float)
    n = len(c) - 1
    width = n // 2 + 1
    R = np.zeros((n + 1, width))
    R[0, : len(c[0::2])] = c[0::2]
    R[1, : len(c[1::2])] = c[1::2]
    small = eps * max(1.0, float(np.abs(c).max()))
    for i in range(2, n + 1):
        if R[i - 1, 0] == 0.0:
            R[i - 1, 0] = small
        for j in range(width - 1):
            R[i, j] = (R[i - 1, 0] * R[i - 2, j + 1] - R[i - 2, 0] * R[i - 1, j + 1]) / R[i - 1, 0]
    return R


def routh_hurwitz(A: np.ndarray) -> RouthHurwitz:
    """Routh-Hurwitz analysis of the characteristic polynomial ``det(sI - A)``."""
    A = np.asarray(A, dtype=float)
    coeffs = np.real(np.poly(A))
    n = len(coeffs) - 1
    R = routh_array(coeffs)
    first = R[:, 0]
    # scale-free tolerance: a coefficient that is zero up to rounding is not "positive"
    scale = np.abs(coeffs).max()
    conds: list[dict[str, Any]] = []
    for k in range(n, -1, -1):
        val = float(coeffs[n - k])
        conds.append({"name": f"a{k} > 0", "value": val, "satisfied": bool(val > 1e-12 * scale)})
    a = {k: float(coeffs[n - k]) for k in range(n + 1)}
    if n == 3:
        val = a[2] * a[1] - a[3] * a[0]
        conds.append({"name": "a2 a1 - a3 a0 > 0", "value": val,
                      "satisfied": bool(val > 1e-12 * scale ** 2)})
    elif n == 4:
        h2 = a[3] * a[2] - a[4] * a[1]
        h3 = a[1] * h2 - a[0] * a[3] ** 2
        conds.append({"name": "a3 a2 - a4 a1 > 0", "value": h2,
                      "satisfied": bool(h2 > 1e-12 * scale ** 2)})
        conds.append({"name": "a1 (a3 a2 - a4 a1) - a0 a3^2 > 0", "value": h3,
                      "satisfied": bool(h3 > 1e-12 * scale ** 3)})
    elif n > 4:
        for i, v in enumerate(first):
            conds.append({"name": f"routh[{i}][0] > 0", "value": float(v),
                          "satisfied": float(v) > 0.0})
    signs = np.sign(first[np.abs(first) > 0])
    changes = int(np.count_nonzero(np.diff(signs)))
    stable = all(c["satisfied"] for c in conds)
    return RouthHurwitz([float(x) for x in coeffs], [[float(x) for x in row] for row in R],
                        [float(x) for x in first], conds, changes, stable)


# --------------------------------------------------------------------------- controllability

@dataclass(frozen=True)
class Controllability:
    """Controllability of the open-loop model through the rear steer (section 3.3.1).

    Attributes
    ----------
    rank : int
        Rank of ``[b, A b, ..., A^{n-1} b]``.
    n_states : int
        n.
    determinant : float
        Determinant of that (square) matrix; its zero gives the uncontrollable speed (3.14).
    controllable : bool
        Full rank.
    """

    rank: int
    n_states: int
    determinant: float
    controllable: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"rank": self.rank, "n_states": self.n_states, "determinant": self.determinant,
                "controllable": self.controllable}


def controllability(A: np.ndarray, b: np.ndarray) -> Controllability:
    """Controllability of ``(A, b)`` from python-control's ``ctrb``."""
    C = control.ctrb(np.asarray(A, dtype=float), np.asarray(b, dtype=float).reshape(-1, 1))
    n = C.shape[0]
    rank = int(np.linalg.matrix_rank(C))
    det = float(np.linalg.det(C)) if C.shape[1] == n else float("nan")
    return Controllability(rank, n, det, rank == n)


# ----------------------------------------------------------------------------- critical speed

@dataclass(frozen=True)
class CriticalSpeed:
    """Lowest speed of a range at which a closed loop loses stability.

    Attributes
    ----------
    critical_speed_mps : float or None
        Speed (m/s) where the largest real part of the eigenvalues crosses zero going up in
        speed; None when stable over the whole range.
    searched_range_mps : tuple of float
        The range searched.
    unstable_at_start : bool
        Already unstable at the bottom of the range (then ``critical_speed_mps`` is the
        range's lower end).
    """

    critical_speed_mps: float | None
    searched_range_mps: tuple[float, float]
    unstable_at_start: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"critical_speed_mps": self.critical_speed_mps,
                "searched_range_mps": list(self.searched_range_mps),
                "unstable_at_start": self.unstable_at_start}


def max_real_part(model_name: str, vehicle: Vehicle, law: Law | str | None,
                  speed_mps: float) -> float:
    """Largest real part (1/s) of the closed-loop eigenvalues at ``speed_mps`` (from the
    matrices alone: a critical-speed search asks at up to 200 speeds, and the state-space
    object of :func:`closed_loop` doubled the cost of each)."""
    A_cl = closed_loop_matrices(model_name, vehicle, law, speed_mps)[0]
    return float(np.max(np.linalg.eigvals(A_cl).real))


def critical_speed(model_name: str, vehicle: Vehicle, law: Law | str | None = None,
                   speed_range_mps: tuple[float, float] = CRITICAL_SPEED_RANGE_MPS,
                   samples: int = _CRITICAL_SPEED_SAMPLES,
                   criterion: str = "eigenvalues") -> CriticalSpeed:
    """Search ``speed_range_mps`` for the speed where the closed loop becomes unstable.

    Parameters
    ----------
    criterion : {"eigenvalues", "lyapunov"}
        Stability measure: largest real eigenvalue part, or the chapter-5 Lyapunov test
        (smallest leading principal minor of P, see :func:`lyapunov_check`).
    """
    law_obj = _law(law, vehicle)

    if criterion == "eigenvalues":
        def margin(u: float) -> float:
            return -max_real_part(model_name, vehicle, law_obj, u)
    elif criterion == "lyapunov":
        def margin(u: float) -> float:
            return lyapunov_check(closed_loop_matrices(model_name, vehicle, law_obj, u)[0]
                                  ).margin
    else:
        raise ParameterError("criterion", f"must be 'eigenvalues' or 'lyapunov', got "
                             f"{criterion!r}")
    return search_critical_speed(margin, speed_range_mps, samples)


def search_critical_speed(margin: Any, speed_range_mps: tuple[float, float],
                          samples: int = _CRITICAL_SPEED_SAMPLES) -> CriticalSpeed:
    """The lowest speed of ``speed_range_mps`` where ``margin(U)`` (a stability margin of the
    speed U in m/s, > 0 stable) reaches 0: sampled on a geometric grid of ``samples`` speeds,
    the first sign change refined with brentq.

    Raises
    ------
    ParameterError
        The range is not two increasing speeds > 0.
    """
    lo, hi = (check_speed(s, "speed_range_mps") for s in speed_range_mps)
    if hi <= lo:
        raise ParameterError("speed_range_mps", f"must be increasing, got {speed_range_mps}")
    speeds = np.geomspace(lo, hi, int(samples))
    prev_u, prev_m = speeds[0], margin(float(speeds[0]))
    if prev_m <= 0.0:
        return CriticalSpeed(float(lo), (lo, hi), True)
    for u in speeds[1:]:
        m = margin(float(u))
        if m <= 0.0:
            root = scipy.optimize.brentq(margin, float(prev_u), float(u),
                                         xtol=_CRITICAL_SPEED_XTOL_MPS)
            return CriticalSpeed(float(root), (lo, hi), False)
        prev_u, prev_m = u, m
    return CriticalSpeed(None, (lo, hi), False)


# ---------------------------------------------------------------- outputs, TF, Bode, gains

def output_matrices(cl: ClosedLoop) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Names, C and D of the standard outputs of ``cl`` (see module docstring)."""
    return list(cl.system.output_labels), cl.system.C, cl.system.D


def _standard_outputs(A: np.ndarray, B: np.ndarray, state_names: Sequence[str],
                      speed_mps: float) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Names, C and D of the standard outputs of the closed loop ``(A, B)``."""
    S = list(state_names)
    n, m = A.shape[0], B.shape[1]
    iv, ir = S.index("V"), S.index("R")
    names: list[str] = []
    rows_c: list[np.ndarray] = []
    rows_d: list[np.ndarray] = []

    def add(name: str, c: np.ndarray, d: np.ndarray | None = None) -> None:
        names.append(name)
        rows_c.append(c)
        rows_d.append(np.zeros(m) if d is None else d)

    e = np.eye(n)
    add("yaw_rate", e[ir])
    add("lateral_acceleration", A[iv] + speed_mps * e[ir], B[iv].copy())
    add("sideslip", e[iv] / speed_mps)
    add("lateral_velocity", e[iv])
    for state, name in (("PHI", "roll"), ("DELTA_F", "front_steer")):
        if state in S:
            add(name, e[S.index(state)])
    return names, np.array(rows_c), np.array(rows_d)


#: Units of each output per unit of each driver input.
OUTPUT_UNITS = {"yaw_rate": "rad/s", "lateral_acceleration": "m/s^2", "sideslip": "rad",
                "lateral_velocity": "m/s", "roll": "rad", "front_steer": "rad"}
INPUT_UNITS = {"DELTA_F": "rad", "T_F": "N m"}


def state_space(cl: ClosedLoop) -> tuple[control.StateSpace, list[str]]:
    """python-control ``StateSpace`` of ``cl`` with the standard outputs, and their names."""
    return cl.system, list(cl.system.output_labels)


#: Standard outputs (:func:`output_matrices`) -> run channel names
#: (:mod:`fourws_analysis.units`).
RUN_CHANNELS = {"yaw_rate": "yaw_rate_radps", "lateral_acceleration": "lateral_accel_mps2",
                "sideslip": "sideslip_rad", "roll": "roll_rad",
                "lateral_velocity": "lateral_velocity_mps"}


def linear_system(vehicle: Vehicle, model_name: str, speed_mps: float, law: str = "fws",
                  belief_vehicle: Vehicle | None = None,
                  law_options: Mapping[str, Any] | None = None) -> control.StateSpace:
    """Closed-loop linear model (``2dof`` or ``3dof``) of ``vehicle`` with rear-steer ``law``,
    as recorded runs are compared with it.

    :func:`closed_loop` (the law closed through its linear gains) with the front road-wheel
    angle as the one input, named ``front_wheel_angle_rad`` (rad), and the standard outputs
    renamed to the run channels they match (:data:`RUN_CHANNELS`: yaw rate rad/s, lateral
    acceleration m/s^2, sideslip rad, lateral velocity m/s, roll rad). Its response is
    :func:`fourws_analysis.frequency.model_response`, its steady-state gains
    :func:`fourws_analysis.frequency.dc_gain`, its eigenvalues ``poles()`` (1/s).

    Parameters
    ----------
    vehicle : Vehicle
        The true vehicle.
    model_name : str
        ``"2dof"`` or ``"3dof"``.
    speed_mps : float
        Forward speed U, m/s.
    law : str
        Rear-steer law name (``fws`` = no rear steer).
    belief_vehicle : Vehicle, optional
        The vehicle the controller believes in (default: the true one).
    law_options : mapping, optional
        Options of the law (``make_law`` keywords).

    Raises
    ------
    UnknownNameError, IncompatibleError, ParameterError
        From the model and law registries; IncompatibleError also for a model whose driver
        input is not the front road-wheel angle (free control).
    """
    law_obj = make_law(law, belief_vehicle if belief_vehicle is not None else vehicle,
                       **dict(law_options or {}))
    cl = closed_loop(model_name, vehicle, law_obj, speed_mps)
    if "DELTA_F" not in cl.input_names:
        raise IncompatibleError(f"model {model_name!r} is not driven by the front road-wheel "
                                f"angle (its driver inputs: {', '.join(cl.input_names)})")
    outputs = [n for n in cl.system.output_labels if n in RUN_CHANNELS]
    system = cl.system[outputs, ["DELTA_F"]]
    return control.ss(system.A, system.B, system.C, system.D,
                      inputs=[ROAD_WHEEL.channel],
                      outputs=[RUN_CHANNELS[n] for n in outputs],
                      states=list(cl.state_names), name=f"{model_name} {law}")


@dataclass(frozen=True)
class TransferFunction:
    """One SISO transfer function ``num(s)/den(s)`` (coefficients highest power first)."""

    output: str
    input: str
    units: str
    num: list[float]
    den: list[float]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"output": self.output, "input": self.input, "units": self.units,
                "num": self.num, "den": self.den}


def transfer_functions(cl: ClosedLoop) -> list[TransferFunction]:
    """Every output/driver-input transfer function of ``cl`` (``control.ss2tf``)."""
    names = list(cl.system.output_labels)
    out = []
    for j, inp in enumerate(cl.input_names):
        for i, name in enumerate(names):
            tf = control.ss2tf(cl.system[i, j])
            num = np.atleast_1d(np.squeeze(tf.num[0][0])).astype(float)
            den = np.atleast_1d(np.squeeze(tf.den[0][0])).astype(float)
            # drop numerically-zero leading numerator terms (relative to the largest)
            while len(num) > 1 and abs(num[0]) <= 1e-10 * np.abs(num).max():
                num = num[1:]
            out.append(TransferFunction(name, inp, f"{OUTPUT_UNITS[name]}/{INPUT_UNITS[inp]}",
                                        [float(x) for x in num], [float(x) for x in den]))
    return out


@dataclass(frozen=True)
class BodeData:
    """Frequency response of every output per driver input.

    Attributes
    ----------
    frequencies_hz : numpy.ndarray
        Frequencies in Hz.
    magnitude : dict
        ``"output/input" -> |G(j 2 pi f)|`` in the transfer function's units.
    phase_deg : dict
        ``"output/input" -> unwrapped phase in degrees``.
    units : dict
        ``"output/input" -> units``.
    """

    frequencies_hz: np.ndarray
    magnitude: dict[str, np.ndarray]
    phase_deg: dict[str, np.ndarray]
    units: dict[str, str]

    def magnitude_db(self, key: str) -> np.ndarray:
        """20 log10 of the magnitude of ``key``."""
        return 20.0 * np.log10(self.magnitude[key])

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"frequencies_hz": self.frequencies_hz.tolist(),
                "magnitude": {k: v.tolist() for k, v in self.magnitude.items()},
                "phase_deg": {k: v.tolist() for k, v in self.phase_deg.items()},
                "units": self.units}


def bode(cl: ClosedLoop, frequencies_hz: Sequence[float] | None = None) -> BodeData:
    """Bode data of ``cl`` at ``frequencies_hz`` (default log-spaced 0.01-10 Hz)."""
    if frequencies_hz is None:
        f = np.geomspace(*DEFAULT_BODE_HZ, _DEFAULT_BODE_POINTS)
    else:
        f = np.asarray(frequencies_hz, dtype=float)
        if f.ndim != 1 or f.size == 0 or np.any(~np.isfinite(f)) or np.any(f <= 0.0):
            raise ParameterError("frequencies_hz", "must be a non-empty list of finite values > 0")
    names = list(cl.system.output_labels)
    resp = control.frequency_response(cl.system, 2.0 * np.pi * f)
    mag = np.asarray(resp.magnitude).reshape(len(names), len(cl.input_names), len(f))
    ph = np.asarray(resp.phase).reshape(len(names), len(cl.input_names), len(f))
    magnitude, phase, units = {}, {}, {}
    for j, inp in enumerate(cl.input_names):
        for i, name in enumerate(names):
            key = f"{name}/{inp}"
            magnitude[key] = mag[i, j]
            phase[key] = np.degrees(np.unwrap(ph[i, j]))
            units[key] = f"{OUTPUT_UNITS[name]}/{INPUT_UNITS[inp]}"
    return BodeData(f, magnitude, phase, units)


def plot_bode(data: BodeData | Sequence[tuple[str, BodeData]], path: str | Path,
              keys: Sequence[str] | None = None) -> Path:
    """Draw magnitude (dB) and phase (deg) versus frequency (Hz) to a PNG (Agg backend).

    Parameters
    ----------
    data : BodeData or list of (label, BodeData)
        One response, or several to overlay (e.g. FWS and a law, Figures 4.6/4.7/4.12/4.13).
    path : str or Path
        Output PNG.
    keys : list of str, optional
        ``"output/input"`` keys to draw (default: every key of the first response).
    """
    import matplotlib  # here, not at the top: only the plots need it, and it is slow to load
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: about 0.5 s to load, only the plots need it

    series = [("", data)] if isinstance(data, BodeData) else list(data)
    if not series:
        raise ParameterError("data", "nothing to plot")
    keys = list(keys) if keys is not None else list(series[0][1].magnitude)
    fig, axes = plt.subplots(2, len(keys), figsize=(4.2 * len(keys), 6.0), squeeze=False,
                             sharex=True)
    for k, key in enumerate(keys):
        for n, (label, bd) in enumerate(series):
            if key not in bd.magnitude:
                raise ParameterError("keys", f"no response {key!r}; have {sorted(bd.magnitude)}")
            color = f"C{n % 10}"
            axes[0, k].semilogx(bd.frequencies_hz, bd.magnitude_db(key), color=color,
                                label=label or None)
            # a zero response (e.g. sideslip under a zero-sideslip law) has no phase; and a
            # jump (a zero on the jw axis) is left open rather than drawn as a vertical line
            phase = np.where(bd.magnitude[key] > 1e-12, bd.phase_deg[key], np.nan)
            axes[1, k].semilogx(*break_phase_jumps(bd.frequencies_hz, phase), color=color)
        axes[0, k].set_title(key)
        axes[0, k].set_ylabel(f"gain, dB re 1 {series[0][1].units[key]}")
        axes[1, k].set_ylabel("phase, deg")
        axes[1, k].set_xlabel("frequency, Hz")
        for ax in axes[:, k]:
            ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    if any(label for label, _ in series):
        # one legend under the panels, never over a curve
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=min(6, len(labels)),
                   fontsize=8, frameon=False)
        fig.subplots_adjust(bottom=0.16)
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def steady_state_gains(cl: ClosedLoop) -> dict[str, float]:
    """Steady-state gains ``-C A^-1 B + D`` as ``{"output/input": gain}`` (units as the TFs).

    Raises
    ------
    IncompatibleError
        The closed loop has an eigenvalue at zero (no steady state).
    """
    if np.linalg.matrix_rank(cl.A) < cl.A.shape[0]:
        raise IncompatibleError(f"{cl.model}/{cl.law} at {cl.speed_mps} m/s has a zero "
                                "eigenvalue; no steady state")
    return {f"{name}/{inp}": dc_gain(cl.system, name, inp) for inp in cl.input_names
            for name in cl.system.output_labels}


# ------------------------------------------------------------------------------- Lyapunov

@dataclass(frozen=True)
class LyapunovCheck:
    """Chapter-5 Lyapunov test: solve ``A^T P + P A = -Q`` and check P > 0 (Sylvester).

    Attributes
    ----------
    P : numpy.ndarray
        The solution (symmetric).
    leading_minors : list of float
        Leading principal minors of P (Sylvester's criterion: all > 0 iff P > 0).
    stable : bool
        P positive definite (and finite): asymptotically stable.
    margin : float
        Smallest leading minor normalized by the size of P (<= 0 or -1 for a non-finite
        P when not stable); used to locate the critical speed.
    """

    P: np.ndarray
    leading_minors: list[float]
    stable: bool
    margin: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"P": self.P.tolist(), "leading_minors": self.leading_minors,
                "stable": self.stable}


def lyapunov_check(A: np.ndarray, Q: np.ndarray | None = None) -> LyapunovCheck:
    """Lyapunov stability test of ``x' = A x`` (eqs. 5.75-5.90) with ``Q`` (default I).

    Raises
    ------
    ParameterError
        Q not symmetric positive definite (the theorem needs Q > 0).
    """
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    Q = np.eye(n) if Q is None else np.asarray(Q, dtype=float)
    if Q.shape != (n, n) or not np.allclose(Q, Q.T) or np.linalg.eigvalsh(Q).min() <= 0.0:
        raise ParameterError("Q", "must be a symmetric positive definite n x n matrix")
    P = scipy.linalg.solve_continuous_lyapunov(A.T, -Q)
    if not np.all(np.isfinite(P)):
        return LyapunovCheck(P, [], False, -1.0)
    P = 0.5 * (P + P.T)
    minors = [float(np.linalg.det(P[:k, :k])) for k in range(1, n + 1)]
    # scale each minor by the matching power of the P size so the margin is dimensionless
    size = float(np.abs(P).max())
    scaled = [m / size ** (k + 1) for k, m in enumerate(minors)]
    margin = min(scaled)
    return LyapunovCheck(P, minors, bool(margin > 0.0), float(margin))


# --------------------------------------------------------------------------------- summary

@dataclass(frozen=True)
class LinearReport:
    """Everything ``fourws linear`` prints for one model/law/speed."""

    vehicle: str
    model: str
    law: str
    speed_mps: float
    modes: list[Mode]
    stable: bool
    routh_hurwitz: RouthHurwitz
    controllability: Controllability
    steady_state_gains: dict[str, float] | None
    critical_speed: CriticalSpeed | None = None
    law_gains: dict[str, float] = field(default_factory=dict)
    lyapunov: LyapunovCheck | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping with the stable keys of ``fourws linear --json``."""
        out: dict[str, Any] = {
            "vehicle": self.vehicle, "model": self.model, "law": self.law,
            "speed_mps": self.speed_mps, "speed_kmh": self.speed_mps * 3.6,
            "eigenvalues": [[m.eigenvalue.real, m.eigenvalue.imag] for m in self.modes],
            "natural_frequencies_hz": [m.natural_frequency_hz for m in self.modes],
            "damping_ratios": [m.damping_ratio for m in self.modes],
            "stable": self.stable,
            "steady_state_gains": self.steady_state_gains,
            "routh_hurwitz": self.routh_hurwitz.to_dict(),
            "controllability": self.controllability.to_dict(),
            "law_gains": self.law_gains,
        }
        if self.lyapunov is not None:
            out["lyapunov"] = {"stable": self.lyapunov.stable,
                               "leading_minors": self.lyapunov.leading_minors}
        if self.critical_speed is not None:
            out["critical_speed_mps"] = self.critical_speed.critical_speed_mps
            out["critical_speed_search"] = self.critical_speed.to_dict()
            # the model level behind the number (fourws_analysis.critical_speeds.LEVELS)
            out["critical_speed_model_level"] = self.model
        return out


def linear_report(model_name: str, vehicle: Vehicle, law: Law | str | None,
                  speed_mps: float, with_critical_speed: bool = False,
                  speed_range_mps: tuple[float, float] = CRITICAL_SPEED_RANGE_MPS
                  ) -> LinearReport:
    """Eigen/Routh/Lyapunov/controllability/steady-state analysis (optionally critical speed)."""
    law_obj = _law(law, vehicle)
    cl = closed_loop(model_name, vehicle, law_obj, speed_mps)
    ms = modes(cl.A)
    stable = is_stable(cl.A)
    try:
        gains = steady_state_gains(cl)
    except IncompatibleError:
        gains = None
    crit = critical_speed(model_name, vehicle, law_obj, speed_range_mps) \
        if with_critical_speed else None
    return LinearReport(vehicle.name, model_name, law_obj.name, cl.speed_mps, ms, stable,
                        routh_hurwitz(cl.A), controllability(cl.A_open, cl.b_rear), gains,
                        crit, law_obj.gains_dict(cl.speed_mps), lyapunov_check(cl.A))
