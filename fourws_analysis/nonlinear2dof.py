# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Lateral stability of the nonlinear cubic-tire 2-DOF vehicle (Samsundar 1996, chapter 7).

Model: :mod:`fourws_sim.models.cubic2dof` at constant forward speed U and zero steer
(straight-line motion). This module computes, as data objects:

* :func:`equilibria` -- every real equilibrium (V, r) with the eigenvalues of the linearized
  model and its stability (Table 7.4). The equilibria are found exactly: in slip-angle
  coordinates the yaw equation gives the rear slip as a cubic of the front slip, and the
  lateral equation becomes one polynomial of degree 9 in the front slip (the Bezout count of
  two cubics, the paper's "nine equilibrium points"); its real roots, polished by Newton, are
  all the real equilibria.
* :func:`lyapunov_estimate` -- the quadratic Lyapunov function :math:`V_1 = x^T P x` with
  :math:`A^T P + P A = -I` (eq. 7.33, A the Jacobian at the origin) and the largest level set
  :math:`V_1 = C` inside :math:`\dot V_1 < 0`, found by the tangency-point method (eqs.
  7.38-7.43, Table 7.2): minimize :math:`V_1` on :math:`\dot V_1 = 0, x \ne 0`.
* :func:`trajectory_reversal` -- the boundary of the region of attraction of the straight
  motion (Genesio et al.): integrate :math:`\dot x = -f(x)` from each saddle along its stable
  eigenvector (both ways); the reversed trajectories trace the saddles' stable manifolds,
  which end in the unstable nodes, and together close the "phase polygon" (section 7.5).

:func:`stability_region` bundles the three; :func:`plot_stability_region` draws it (a separate
step, matplotlib Agg).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.polynomial import Polynomial
from scipy.integrate import solve_ivp
from scipy.linalg import solve_continuous_lyapunov
from scipy.optimize import minimize_scalar

from fourws_sim.errors import IncompatibleError, NonFiniteError
from fourws_sim.models import cubic2dof
from fourws_sim.params import Vehicle

_ZERO_INPUT = np.zeros(len(cubic2dof.INPUT))
#: Relative size of the imaginary part below which a polynomial root counts as real.
_REAL_ROOT_TOL = 1e-6
#: Newton polishing: iterations and step tolerance in slip angle (rad).
_NEWTON_ITER = 50
_NEWTON_TOL = 1e-13
#: Two equilibria closer than this (m/s and rad/s) are the same point.
_SAME_POINT = 1e-6
#: Real parts within this of zero (1/s) make an equilibrium "marginal" (not stable).
_MARGINAL = 1e-9


@dataclass(frozen=True)
class Equilibrium:
    """One equilibrium of the straight-running cubic-tire 2-DOF model.

    Attributes
    ----------
    v_mps : float
        Lateral velocity V in m/s.
    r_radps : float
        Yaw rate r in rad/s.
    eigenvalues : tuple of complex
        Eigenvalues of the Jacobian there, in 1/s (sorted by real part, descending).
    stable : bool
        All eigenvalues have negative real part.
    kind : str
        ``"stable focus"``, ``"stable node"``, ``"saddle"``, ``"unstable node"``,
        ``"unstable focus"`` or ``"marginal"``.
    """

    v_mps: float
    r_radps: float
    eigenvalues: tuple[complex, ...]
    stable: bool
    kind: str

    @property
    def state(self) -> np.ndarray:
        """The point as a state vector ``[V, r]``."""
        return np.array([self.v_mps, self.r_radps])

    def to_dict(self) -> dict:
        """JSON-ready mapping ``{v_mps, r_radps, eigenvalues: [[re, im], ...], stable, kind}``."""
        return {"v_mps": self.v_mps, "r_radps": self.r_radps,
                "eigenvalues": [[float(e.real), float(e.imag)] for e in self.eigenvalues],
                "stable": self.stable, "kind": self.kind}


@dataclass(frozen=True)
class LyapunovEstimate:
    """Quadratic Lyapunov estimate of the stability region (eqs. 7.21-7.43, Table 7.2).

    Attributes
    ----------
    P : numpy.ndarray
        2x2 solution of ``A^T P + P A = -I`` (units mixing m/s and rad/s).
    level : float
        C, the largest value with ``{x: x^T P x < C}`` inside ``dV1/dt < 0``.
    tangency_points : tuple of numpy.ndarray
        The points ``[V (m/s), r (rad/s)]`` where ``x^T P x = C`` touches ``dV1/dt = 0``
        (a symmetric pair).
    multiplier : float
        Lagrange multiplier lambda of ``L = V1 + lambda dV1/dt`` at the tangency points.
    vdot_zero_curve : numpy.ndarray
        Points ``(k, 2)`` of the curve ``dV1/dt = 0`` (x != 0) around the origin, NaN in the
        directions where it does not exist (the curve of Figures 7.2/7.3).
    """

    P: np.ndarray
    level: float
    tangency_points: tuple[np.ndarray, ...]
    multiplier: float
    vdot_zero_curve: np.ndarray

    def ellipse(self, n: int = 361) -> np.ndarray:
        """Points ``(n, 2)`` of the boundary ``x^T P x = C`` (V in m/s, r in rad/s)."""
        theta = np.linspace(0.0, 2.0 * np.pi, n)
        e = np.vstack([np.cos(theta), np.sin(theta)])
        rho = np.sqrt(self.level / np.einsum("ij,ik,kj->j", e, self.P, e))
        return (e * rho).T

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Whether each point ``[V, r]`` (shape ``(k, 2)``) lies inside the estimate."""
        pts = np.atleast_2d(points)
        return np.einsum("ij,jk,ik->i", pts, self.P, pts) < self.level


@dataclass(frozen=True)
class ReversalBoundary:
    """Boundary of the region of attraction by trajectory reversal.

    Attributes
    ----------
    branches : tuple of numpy.ndarray
        Each the ``(k, 2)`` points ``[V, r]`` of one reversed trajectory, from next to a
        saddle to where it ended.
    ends : tuple of str
        For each branch, ``"equilibrium"`` (reached an unstable equilibrium of the forward
        system), ``"escaped"`` (left the box) or ``"time"`` (integration time ran out).
    polygon : numpy.ndarray or None
        The closed boundary ``(k, 2)`` when the branches join into one cycle through the
        saddles and unstable nodes, else ``None`` (unbounded region).
    """

    branches: tuple[np.ndarray, ...]
    ends: tuple[str, ...]
    polygon: np.ndarray | None

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Whether each point ``[V, r]`` (shape ``(k, 2)``) lies inside the closed boundary.

        Raises
        ------
        ValueError
            If the boundary is not closed (``polygon`` is ``None``).
        """
        if self.polygon is None:
            raise ValueError("the trajectory-reversal boundary is not closed")
        return _inside_polygon(np.atleast_2d(points), self.polygon)


@dataclass(frozen=True)
class StabilityRegion:
    """Everything chapter 7 computes for one vehicle and speed."""

    vehicle_name: str
    speed_mps: float
    equilibria: tuple[Equilibrium, ...]
    lyapunov: LyapunovEstimate
    reversal: ReversalBoundary


def _classify(eig: np.ndarray) -> tuple[bool, str]:
    re = eig.real
    if np.any(np.abs(re) <= _MARGINAL):
        return False, "marginal"
    complex_pair = bool(np.any(np.abs(eig.imag) > 0.0))
    if np.all(re < 0.0):
        return True, "stable focus" if complex_pair else "stable node"
    if np.all(re > 0.0):
        return False, "unstable focus" if complex_pair else "unstable node"
    return False, "saddle"


def _equilibrium_at(x: np.ndarray, p: cubic2dof.Params) -> Equilibrium:
    eig = np.linalg.eigvals(cubic2dof.jacobian(x, _ZERO_INPUT, p))
    eig = eig[np.lexsort((-eig.imag, -eig.real))]
    stable, kind = _classify(eig)
    return Equilibrium(float(x[0]), float(x[1]), tuple(complex(e) for e in eig), stable, kind)


def _slips_to_state(alpha_f: float, alpha_r: float, p: cubic2dof.Params) -> np.ndarray:
    """Zero steer: alpha_f = (V + a r)/U, alpha_r = (V - b r)/U solved for V, r."""
    wheelbase = p.a_m + p.b_m
    u = p.speed_mps
    return np.array([u * (p.b_m * alpha_f + p.a_m * alpha_r) / wheelbase,
                     u * (alpha_f - alpha_r) / wheelbase])


def _newton(x: np.ndarray, p: cubic2dof.Params) -> np.ndarray:
    for _ in range(_NEWTON_ITER):
        try:
            step = np.linalg.solve(cubic2dof.jacobian(x, _ZERO_INPUT, p),
                                   cubic2dof.derivatives(0.0, x, _ZERO_INPUT, p))
        except np.linalg.LinAlgError:  # a double root (bifurcation): keep the root as found
            break
        x = x - step
        if np.max(np.abs(step)) < _NEWTON_TOL * max(1.0, np.max(np.abs(x))):
            break
    return x


def equilibria_of(p: cubic2dof.Params) -> tuple[Equilibrium, ...]:
    r"""All real equilibria of the cubic-tire model with parameters ``p`` at zero steer.

    With axle forces :math:`F_f(\alpha_f)`, :math:`F_r(\alpha_r)` and
    :math:`k = m U^2 / L^2`, equilibrium means :math:`a F_f = b F_r` and
    :math:`F_f + F_r = m U r = k L (\alpha_f - \alpha_r)`, so
    :math:`\alpha_r = \alpha_f - F_f(\alpha_f)/(b k)` and
    :math:`F_r(\alpha_r(\alpha_f)) - (a/b) F_f(\alpha_f) = 0`, a polynomial of degree 9.

    Returns
    -------
    tuple of Equilibrium
        Sorted by lateral velocity V (ascending).
    """
    wheelbase = p.a_m + p.b_m
    k = p.mass_kg * p.speed_mps ** 2 / wheelbase ** 2
    ff = Polynomial([0.0, -p.cf_n_per_rad, 0.0, p.cf_n_per_rad * p.kf_per_rad2])
    fr = Polynomial([0.0, -p.cr_n_per_rad, 0.0, p.cr_n_per_rad * p.kr_per_rad2])
    alpha_r = Polynomial([0.0, 1.0]) - ff / (p.b_m * k)
    residual = fr(alpha_r) - ff * (p.a_m / p.b_m)
    roots = residual.trim().roots()
    scale = max(1.0, float(np.max(np.abs(roots)))) if roots.size else 1.0
    found: list[np.ndarray] = []
    for root in roots:
        if abs(root.imag) > _REAL_ROOT_TOL * scale:
            continue
        af = float(root.real)
        x = _newton(_slips_to_state(af, float(alpha_r(af)), p), p)
        if not np.all(np.isfinite(x)):
            raise NonFiniteError(f"equilibrium search diverged near alpha_f = {af!r} rad")
        residual_scale = p.speed_mps * max(1.0, float(np.max(np.abs(x))))
        if np.max(np.abs(cubic2dof.derivatives(0.0, x, _ZERO_INPUT, p))) > 1e-8 * residual_scale:
            continue  # a nearly real complex root that is no real equilibrium
        if all(np.max(np.abs(x - y)) > _SAME_POINT for y in found):
            found.append(x)
    found.sort(key=lambda x: (round(x[0], 9), x[1]))
    return tuple(_equilibrium_at(x, p) for x in found)


def equilibria(vehicle: Vehicle, speed_mps: float) -> tuple[Equilibrium, ...]:
    """All real equilibria of ``vehicle`` on the cubic-tire 2-DOF model at ``speed_mps`` (m/s).

    Raises
    ------
    ParameterError
        If the speed is not finite and > 0 or the vehicle has no ``tire`` subsystem.
    """
    return equilibria_of(cubic2dof.params_for(vehicle, speed_mps))


def _vdot(x: np.ndarray, P: np.ndarray, p: cubic2dof.Params) -> float:
    return float(2.0 * x @ P @ cubic2dof.derivatives(0.0, x, _ZERO_INPUT, p))


def _cubic_part(x: np.ndarray, p: cubic2dof.Params) -> np.ndarray:
    """The cubic terms h(x) of the zero-steer model, f(x) = A x + h(x) (exact, no rounding)."""
    alpha_f = (x[0] + p.a_m * x[1]) / p.speed_mps
    alpha_r = (x[0] - p.b_m * x[1]) / p.speed_mps
    fyf3 = p.cf_n_per_rad * p.kf_per_rad2 * alpha_f ** 3
    fyr3 = p.cr_n_per_rad * p.kr_per_rad2 * alpha_r ** 3
    return np.array([(fyf3 + fyr3) / p.mass_kg,
                     (p.a_m * fyf3 - p.b_m * fyr3) / p.yaw_inertia_kgm2])


def lyapunov_estimate(vehicle: Vehicle, speed_mps: float, *,
                      n_angles: int = 20001) -> LyapunovEstimate:
    r"""Quadratic Lyapunov estimate of the straight-motion stability region (Table 7.2).

    Along a ray :math:`x = \rho e` the model splits into its linear and cubic parts,
    :math:`f(\rho e) = \rho A e + \rho^3 h(e)`, so
    :math:`\dot V_1 = -\rho^2 |e|^2 + 2\rho^4 e^T P h(e)` vanishes (away from 0) at
    :math:`\rho^2 = 1/(2 e^T P h(e))` where that is positive. The tangency level is the
    smallest :math:`V_1 = \rho^2 e^T P e` over the directions, found on a grid of
    ``n_angles`` directions and refined by a bounded scalar minimization.

    Raises
    ------
    ParameterError
        As :func:`equilibria`.
    IncompatibleError
        If the origin is not asymptotically stable (no Lyapunov function of this form) or
        ``dV1/dt`` never vanishes (linear tires: the estimate is the whole plane).
    """
    p = cubic2dof.params_for(vehicle, speed_mps)
    A = cubic2dof.jacobian(np.zeros(2), _ZERO_INPUT, p)
    if np.any(np.linalg.eigvals(A).real >= 0.0):
        raise IncompatibleError(f"straight motion of {vehicle.name} is unstable at "
                                f"{p.speed_mps} m/s: it has no stability region")
    P = solve_continuous_lyapunov(A.T, -np.eye(2))

    def level_along(theta: float) -> float:
        e = np.array([np.cos(theta), np.sin(theta)])
        q4 = 2.0 * e @ P @ _cubic_part(e, p)
        return float(e @ P @ e / q4) if q4 > 0.0 else np.inf

    thetas = np.linspace(0.0, np.pi, n_angles)  # V1 and its derivative are odd-symmetric
    levels = np.array([level_along(t) for t in thetas])
    i = int(np.argmin(levels))
    if not np.isfinite(levels[i]):
        raise IncompatibleError(f"dV1/dt < 0 everywhere for {vehicle.name} (tire cubic "
                                f"coefficients zero?): the Lyapunov estimate is unbounded")
    step = thetas[1] - thetas[0]
    res = minimize_scalar(level_along, bounds=(thetas[i] - step, thetas[i] + step),
                          method="bounded", options={"xatol": 1e-12})
    theta = float(res.x) if res.fun <= levels[i] else float(thetas[i])
    level = min(float(res.fun), float(levels[i]))
    e = np.array([np.cos(theta), np.sin(theta)])
    x = e * np.sqrt(level / float(e @ P @ e))
    # multiplier of  grad V1 + lambda grad Vdot = 0  (least squares; exact at the optimum)
    grad_v = 2.0 * P @ x
    h = 1e-7 * max(1.0, float(np.max(np.abs(x))))
    grad_vdot = np.array([(_vdot(x + h * d, P, p) - _vdot(x - h * d, P, p)) / (2.0 * h)
                          for d in np.eye(2)])
    multiplier = -float(grad_v @ grad_vdot) / float(grad_vdot @ grad_vdot)
    around = np.linspace(0.0, 2.0 * np.pi, 721)
    curve = np.full((around.size, 2), np.nan)
    for j, t in enumerate(around):
        e = np.array([np.cos(t), np.sin(t)])
        q4 = 2.0 * e @ P @ _cubic_part(e, p)
        if q4 > 0.0:
            curve[j] = e / np.sqrt(q4)
    return LyapunovEstimate(P, level, (x, -x), multiplier, curve)


def trajectory_reversal(vehicle: Vehicle, speed_mps: float, *, offset: float = 1e-5,
                        t_max_s: float = 30.0, box: tuple[float, float] | None = None,
                        found: tuple[Equilibrium, ...] | None = None) -> ReversalBoundary:
    """Boundary of the straight motion's region of attraction by trajectory reversal.

    Parameters
    ----------
    vehicle : Vehicle
        Vehicle with the cubic tire coefficients.
    speed_mps : float
        Forward speed U in m/s.
    offset : float
        Start distance from each saddle along its stable eigenvector, relative to the
        saddle's distance from the origin.
    t_max_s : float
        Longest reversed integration, s.
    box : (float, float), optional
        Stop a branch when ``|V|`` or ``|r|`` exceeds these (m/s, rad/s); default 4x the
        largest equilibrium coordinates, and at least U m/s and 2 U/L rad/s (a front-rear
        slip-angle difference of 2 rad, far beyond the tire law's range).
    found : tuple of Equilibrium, optional
        Equilibria already computed by :func:`equilibria` (saves recomputing them).
    """
    p = cubic2dof.params_for(vehicle, speed_mps)
    eqs = equilibria_of(p) if found is None else found
    pts = np.array([e.state for e in eqs]) if eqs else np.zeros((1, 2))
    if box is None:
        box = (max(4.0 * float(np.max(np.abs(pts[:, 0]))), p.speed_mps),
               max(4.0 * float(np.max(np.abs(pts[:, 1]))),
                   2.0 * p.speed_mps / (p.a_m + p.b_m)))
    box_arr = np.asarray(box, dtype=float)

    def reversed_field(t: float, x: np.ndarray) -> np.ndarray:
        return -cubic2dof.derivatives(t, x, _ZERO_INPUT, p)

    def leave_box(t: float, x: np.ndarray) -> float:
        return float(np.max(np.abs(x) / box_arr) - 1.0)

    leave_box.terminal = True  # type: ignore[attr-defined]

    branches: list[np.ndarray] = []
    ends: list[str] = []
    edges: list[tuple[int, int | None]] = []
    for si, eq in enumerate(eqs):
        if eq.kind != "saddle":
            continue
        xs = eq.state
        w, vecs = np.linalg.eig(cubic2dof.jacobian(xs, _ZERO_INPUT, p))
        stable_dir = np.real(vecs[:, int(np.argmin(w.real))])
        size = offset * max(1.0, float(np.linalg.norm(xs)))
        for sign in (1.0, -1.0):
            sol = solve_ivp(reversed_field, (0.0, t_max_s), xs + sign * size * stable_dir,
                            method="LSODA", rtol=1e-9, atol=1e-12, events=leave_box,
                            dense_output=False, max_step=t_max_s / 2000.0)
            path = np.vstack([xs, sol.y.T])
            end = path[-1]
            end_index = None
            if sol.status == 1:
                ends.append("escaped")
            else:
                near = [j for j, u in enumerate(eqs)
                        if not u.stable and np.linalg.norm(end - u.state)
                        < 1e-3 * max(1.0, float(np.linalg.norm(u.state)))]
                if near:
                    end_index = near[0]
                    ends.append("equilibrium")
                    path = np.vstack([path, eqs[end_index].state])
                else:
                    ends.append("time")
            branches.append(path)
            edges.append((si, end_index))
    return ReversalBoundary(tuple(branches), tuple(ends), _close_polygon(branches, edges))


def _close_polygon(branches: list[np.ndarray],
                   edges: list[tuple[int, int | None]]) -> np.ndarray | None:
    """Chain branches (saddle -> end equilibrium) into one closed cycle, if they form one."""
    if not branches or any(end is None for _, end in edges):
        return None
    unused = list(range(len(branches)))
    first = unused.pop(0)
    start, current = edges[first]
    chain = [branches[first]]
    while unused:
        nxt = None
        for i in unused:
            a, b = edges[i]
            if b == current:
                nxt, piece, current = i, branches[i][::-1], a
                break
            if a == current:
                nxt, piece, current = i, branches[i], b
                break
        if nxt is None:
            return None
        unused.remove(nxt)
        chain.append(piece)
        if current == start and unused:
            return None
    if current != start:
        return None
    return np.vstack(chain)


def _inside_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Even-odd ray casting test of ``points`` (k, 2) against a closed ``polygon`` (n, 2)."""
    x, y = points[:, 0][:, None], points[:, 1][:, None]
    x1, y1 = polygon[:-1, 0][None, :], polygon[:-1, 1][None, :]
    x2, y2 = polygon[1:, 0][None, :], polygon[1:, 1][None, :]
    crosses = (y1 > y) != (y2 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
    return np.count_nonzero(crosses & (x < x_cross), axis=1) % 2 == 1


def stability_region(vehicle: Vehicle, speed_mps: float) -> StabilityRegion:
    """Equilibria, Lyapunov/tangency estimate and trajectory-reversal boundary at one speed."""
    p = cubic2dof.params_for(vehicle, speed_mps)
    eqs = equilibria_of(p)
    return StabilityRegion(vehicle.name, p.speed_mps, eqs,
                           lyapunov_estimate(vehicle, p.speed_mps),
                           trajectory_reversal(vehicle, p.speed_mps, found=eqs))


def plot_stability_region(region: StabilityRegion, path: str | Path) -> Path:
    """Draw the stability region (V horizontal in m/s, r vertical in rad/s) to a PNG file.

    Shows the trajectory-reversal boundary, the Lyapunov/tangency ellipse with its tangency
    points, the curve dV1/dt = 0, and the equilibria (filled = stable). Returns the written path.
    """
    import matplotlib  # matplotlib: about 0.5 s to load, only the plots need it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: about 0.5 s to load, only the plots need it

    out = Path(path)
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    for i, branch in enumerate(region.reversal.branches):
        ax.plot(branch[:, 0], branch[:, 1], color="C0",
                label="trajectory reversal" if i == 0 else None)
    ell = region.lyapunov.ellipse()
    ax.plot(ell[:, 0], ell[:, 1], color="C1", linestyle="--",
            label=f"Lyapunov estimate (C = {region.lyapunov.level:.3g})")
    vz = region.lyapunov.vdot_zero_curve
    ax.plot(vz[:, 0], vz[:, 1], color="C2", linestyle=":", label="dV1/dt = 0")
    tp = np.array(region.lyapunov.tangency_points)
    ax.plot(tp[:, 0], tp[:, 1], "x", color="C1", label="tangency points")
    for eq in region.equilibria:
        ax.plot(eq.v_mps, eq.r_radps, "o", color="k",
                markerfacecolor="k" if eq.stable else "white")
    ax.set_xlabel("lateral velocity V (m/s)")
    ax.set_ylabel("yaw rate r (rad/s)")
    ax.set_title(f"{region.vehicle_name}: stability region at U = {region.speed_mps:g} m/s")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out
