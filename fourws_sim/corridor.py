# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""The widest-margin reference line through a course of gated lanes (ISO 3888 lane changes).

A test driver walks an ISO 3888-2 course before driving it and picks the line that keeps the
car as far from every cone as the road allows at the test speed. :func:`plan_corridor_path`
does the same as a linear program. The line is :math:`y(x)` on a uniform grid
:math:`x_i = x_0 + i h` (earth frame: x along the course, y to the left). For a gated section
``(x_start, x_end, y_right, y_left)`` and a vehicle of width W, the CG may use
:math:`y_{right} + W/2 \le y \le y_{left} - W/2`; the line maximizes the smallest clearance
``m`` (m) between the body (CG +- W/2, the check of ``test/test_closed_loop.py``) and the cone
lines over all sections,

.. math::

    \max m \quad\text{s.t.}\quad y_i - W/2 - y_{right} \ge m,\;
    y_{left} - W/2 - y_i \ge m \;\; (x_i \text{ in a section}),\qquad
    |\Delta^2 y_i| \le \frac{a_{max}}{U^2} h^2,\qquad
    |\Delta^3 y_i| \le \frac{j_{max}}{U^3} h^3,

with :math:`\Delta^2, \Delta^3` the second and third forward differences. The first bound
limits the path curvature :math:`y'' \approx \kappa` so that driving it at speed U needs at most
the lateral acceleration :math:`a_{max} = U^2 \kappa` (m/s^2); the second limits the curvature
rate, i.e. the lateral jerk :math:`j_{max} = U^3\, d\kappa/dx` (m/s^3), which a car answers
only with the lag of its steering and yaw response. (:math:`y''` bounds the curvature from
above: :math:`\kappa = y''/(1+y'^2)^{3/2}`.) The line starts at the start pose (y, slope and
curvature 0 at :math:`x_0`) and ends straight (slope and curvature 0 over its last points).

A linear program has many optima where the constraints do not bind (e.g. on the approach), so
a second program keeps ``m`` within :data:`MARGIN_BACKOFF_M` of the optimum and minimizes
:math:`\sum |\Delta^3 y_i|`, the total variation of the curvature: the smoothest of the
widest lines, with the fewest steering reversals. Both are solved with HiGHS
(``scipy.optimize.linprog``); the result is deterministic for given inputs.

The clearance ``m`` the line keeps is a property of the course, the car's width, the speed and
the two limits only (no vehicle dynamics): it is the margin a driver who follows the line
exactly would keep. On the ISO 3888-2 course at 60 km/h with W = 1.7 m and 30 m/s^3 it is
4.2 cm for 6 m/s^2, 6.1 cm for 6.25 m/s^2, 7.8 cm for 6.5 m/s^2 and 13.9 cm for 8 m/s^2:
ISO 3888-2 is a limit maneuver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from fourws_sim.errors import NonFiniteError, ParameterError

#: The smoothing program keeps the clearance within this of the optimum, m.
MARGIN_BACKOFF_M = 0.002
#: Points at each end held straight (slope and curvature zero).
_END_POINTS = 3


@dataclass(frozen=True)
class CorridorPlan:
    """A planned line.

    Attributes
    ----------
    x_m, y_m : numpy.ndarray
        Grid points of the line (earth frame), m.
    margin_m : float
        Smallest clearance of the line between the body (CG +- W/2) and the cone lines over
        the grid points in the sections, m (negative: the course cannot be cleared within the
        limits at this speed).
    widest_margin_m : float
        The optimum of the first program, m; ``margin_m`` is within
        :data:`MARGIN_BACKOFF_M` below it.
    """

    x_m: np.ndarray
    y_m: np.ndarray
    margin_m: float
    widest_margin_m: float


def plan_corridor_path(sections: Sequence[tuple[float, float, float, float]],
                       vehicle_width_m: float, speed_mps: float,
                       max_lateral_accel_mps2: float, max_lateral_jerk_mps3: float,
                       x_start_m: float, x_end_m: float, step_m: float = 0.5) -> CorridorPlan:
    """Plan the widest-margin line through ``sections`` (see the module docstring).

    Parameters
    ----------
    sections : sequence of (x_start, x_end, y_right, y_left)
        Gated sections in the earth frame, m (``y_left > y_right``).
    vehicle_width_m : float
        Body width W, m.
    speed_mps : float
        Speed the line is planned for, m/s (> 0).
    max_lateral_accel_mps2 : float
        Bound on ``U^2 y''``, m/s^2 (> 0).
    max_lateral_jerk_mps3 : float
        Bound on ``U^3 y'''``, m/s^3 (> 0).
    x_start_m, x_end_m : float
        Extent of the line, m: it starts at ``y = 0`` heading along x at ``x_start_m`` and
        ends straight at ``x_end_m`` (both outside the sections).
    step_m : float
        Grid step h, m.

    Returns
    -------
    CorridorPlan

    Raises
    ------
    ParameterError
        A non-positive speed, limit, width or step, or a course that does not lie between
        ``x_start_m`` and ``x_end_m``.
    NonFiniteError
        The linear program failed (not expected: ``y = 0`` is always feasible).
    """
    # scipy.optimize and scipy.sparse load in about 0.3 s; only a corridor fit needs them
    import scipy.optimize
    import scipy.sparse as sp

    for name, value in (("vehicle_width_m", vehicle_width_m), ("speed_mps", speed_mps),
                        ("max_lateral_accel_mps2", max_lateral_accel_mps2),
                        ("max_lateral_jerk_mps3", max_lateral_jerk_mps3),
                        ("step_m", step_m)):
        if not (math.isfinite(value) and value > 0.0):
            raise ParameterError(name, f"must be a finite number > 0, got {value!r}")
    if not sections:
        raise ParameterError("sections", "at least one gated section is needed")
    first = min(s[0] for s in sections)
    last = max(s[1] for s in sections)
    if not x_start_m < first or not last < x_end_m:
        raise ParameterError("x_start_m", f"the line [{x_start_m}, {x_end_m}] m must contain "
                             f"the sections [{first}, {last}] m")
    n = int(math.ceil((x_end_m - x_start_m) / step_m)) + 1
    x = x_start_m + step_m * np.arange(n)
    h = step_m
    kappa_max = max_lateral_accel_mps2 / speed_mps ** 2
    dkappa_max = max_lateral_jerk_mps3 / speed_mps ** 3
    half = 0.5 * vehicle_width_m

    d2 = sp.diags([1.0, -2.0, 1.0], [0, 1, 2], shape=(n - 2, n), format="csr")
    d3 = sp.diags([-1.0, 3.0, -3.0, 1.0], [0, 1, 2, 3], shape=(n - 3, n), format="csr")
    # variables [y_0 .. y_{n-1}, m]
    no_m2, no_m3 = sp.csr_matrix((n - 2, 1)), sp.csr_matrix((n - 3, 1))
    rows = [sp.hstack([d2, no_m2]), sp.hstack([-d2, no_m2]),
            sp.hstack([d3, no_m3]), sp.hstack([-d3, no_m3])]
    bounds = [np.full(n - 2, kappa_max * h * h)] * 2 + [np.full(n - 3, dkappa_max * h ** 3)] * 2
    for x0, x1, y_right, y_left in sections:
        idx = np.flatnonzero((x >= x0 - 1e-9) & (x <= x1 + 1e-9))
        pick = sp.csr_matrix((np.ones(idx.size), (np.arange(idx.size), idx)),
                             shape=(idx.size, n))
        ones = sp.csr_matrix(np.ones((idx.size, 1)))
        rows += [sp.hstack([-pick, ones]), sp.hstack([pick, ones])]
        bounds += [np.full(idx.size, -(y_right + half)), np.full(idx.size, y_left - half)]
    a_ub = sp.vstack(rows, format="csr")
    b_ub = np.concatenate(bounds)
    a_eq = np.zeros((2 * _END_POINTS, n + 1))
    for k in range(_END_POINTS):
        a_eq[k, k] = 1.0  # start: y = 0 over the first points (zero slope and curvature)
        a_eq[_END_POINTS + k, n - 1 - k] = 1.0  # end: the last points equal (straight)
        a_eq[_END_POINTS + k, n - 1 - _END_POINTS] = -1.0
    b_eq = np.zeros(2 * _END_POINTS)
    free = [(None, None)] * (n + 1)

    cost = np.zeros(n + 1)
    cost[n] = -1.0
    widest = scipy.optimize.linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq,
                                    bounds=free, method="highs")
    if widest.status != 0:
        raise NonFiniteError(f"corridor line: linear program failed ({widest.message})")
    margin = float(widest.x[n])

    # smoothest of the widest: min sum |d3 y| with m >= margin - backoff (aux t >= |d3 y|)
    k3 = n - 3
    zero = sp.csr_matrix
    a_ub2 = sp.vstack([
        sp.hstack([a_ub, zero((a_ub.shape[0], k3))]),
        sp.hstack([d3, zero((k3, 1)), -sp.identity(k3)]),
        sp.hstack([-d3, zero((k3, 1)), -sp.identity(k3)]),
        sp.hstack([zero((1, n)), sp.csr_matrix([[-1.0]]), zero((1, k3))]),
    ], format="csr")
    b_ub2 = np.concatenate([b_ub, np.zeros(2 * k3), [-(margin - MARGIN_BACKOFF_M)]])
    a_eq2 = np.hstack([a_eq, np.zeros((a_eq.shape[0], k3))])
    cost2 = np.concatenate([np.zeros(n + 1), np.ones(k3)])
    smooth = scipy.optimize.linprog(cost2, A_ub=a_ub2, b_ub=b_ub2, A_eq=a_eq2, b_eq=b_eq,
                                    bounds=free + [(0.0, None)] * k3, method="highs")
    if smooth.status != 0:
        raise NonFiniteError(f"corridor line: smoothing program failed ({smooth.message})")
    y = np.asarray(smooth.x[:n], dtype=float)
    y[:_END_POINTS] = 0.0
    return CorridorPlan(x_m=x, y_m=y, margin_m=clearance(x, y, sections, vehicle_width_m),
                        widest_margin_m=margin)


def clearance(x_m: np.ndarray, y_m: np.ndarray,
              sections: Sequence[tuple[float, float, float, float]],
              vehicle_width_m: float) -> float:
    """Smallest clearance (m) between the body (CG at ``(x, y)`` +- W/2 sideways) and the cone
    lines of ``sections`` over the points inside a section (``inf`` if none is inside)."""
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    half = 0.5 * vehicle_width_m
    worst = math.inf
    for x0, x1, y_right, y_left in sections:
        inside = (x >= x0 - 1e-9) & (x <= x1 + 1e-9)
        if inside.any():
            worst = min(worst, float(np.min(y[inside] - half - y_right)),
                        float(np.min(y_left - half - y[inside])))
    return worst


__all__ = ["CorridorPlan", "MARGIN_BACKOFF_M", "clearance", "plan_corridor_path"]
