# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Dominant eigenvalues identified from transient responses of a recorded run.

Every output of a linear(ized) vehicle shares the characteristic polynomial of its state
matrix. Sampled every :math:`h` seconds, with the input held between samples, each output obeys

.. math::

    y_i[k] + a_1 y_i[k-1] + \dots + a_n y_i[k-n] = \sum_{j=0}^{n} b_{ij} u[k-j] + c_i,

with the same :math:`a_1 \dots a_n` for every output :math:`i` (the coefficients of
:math:`\det(zI - e^{Ah})`). Stacking the equations of all outputs and solving by least squares
gives the :math:`a`'s; the eigenvalues are :math:`s = \ln(z)/h` for the roots :math:`z`.
This is exact for a linear model excited by a step (input constant between samples), and
gives the dominant (slowest, most visible) modes of a nonlinear run near its trim.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fourws_analysis.bag import MetricUnavailableError

#: Default identification sample period, s: fine against the yaw/sideslip modes (1-3 Hz,
#: time constants 0.1-1 s) yet coarse enough that the roots z stay away from 1.
DEFAULT_SAMPLE_S = 0.01


@dataclass
class IdentifiedModes:
    """Eigenvalues identified from data.

    Attributes
    ----------
    eigenvalues : ndarray of complex
        Identified continuous-time eigenvalues, 1/s, sorted by real part (slowest first).
    order : int
        Model order used.
    sample_s : float
        Identification sample period, s.
    fit_rms : float
        RMS of the equation error relative to the RMS of the outputs.
    """

    eigenvalues: np.ndarray
    order: int
    sample_s: float
    fit_rms: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (eigenvalues as [re, im] pairs, 1/s)."""
        return {"eigenvalues_per_s": [[float(e.real), float(e.imag)] for e in self.eigenvalues],
                "order": self.order, "sample_s": self.sample_s, "fit_rms": self.fit_rms}


def identify_modes(time_s: np.ndarray, u: np.ndarray, outputs: list[np.ndarray],
                   order: int = 2, sample_s: float = DEFAULT_SAMPLE_S) -> IdentifiedModes:
    """Identify ``order`` eigenvalues shared by ``outputs`` driven by input ``u``.

    Parameters
    ----------
    time_s : ndarray
        Uniform time grid, s.
    u : ndarray
        Input (e.g. front road-wheel angle, rad).
    outputs : list of ndarray
        Responses (e.g. yaw rate and lateral velocity); scaled to unit RMS internally.
    order : int
        Number of eigenvalues.
    sample_s : float
        Identification sample period, s (the data are sub-sampled to it).

    Raises
    ------
    MetricUnavailableError
        If the record is too short or carries no transient.
    """
    t = np.asarray(time_s, dtype=float)
    dt = float(t[1] - t[0])
    step = max(1, int(round(sample_s / dt)))
    h = dt * step
    uu = np.asarray(u, dtype=float)[::step]
    ys = [np.asarray(y, dtype=float)[::step] for y in outputs]
    n = order
    if uu.size < 4 * (2 * n + 2):
        raise MetricUnavailableError(
            f"eigenvalue identification: {uu.size} samples at {h:g} s; need {8 * n + 8}")
    rows = []
    rhs = []
    m = len(ys)
    n_par = n + m * (n + 2)
    y_rms_all = []
    for i, y in enumerate(ys):
        scale = float(np.std(y))
        if scale <= 0.0:
            continue
        y = y / scale
        y_rms_all.append(1.0)
        k = np.arange(n, y.size)
        block = np.zeros((k.size, n_par))
        for j in range(1, n + 1):
            block[:, j - 1] = -y[k - j]
        base = n + i * (n + 2)
        for j in range(n + 1):
            block[:, base + j] = uu[k - j]
        block[:, base + n + 1] = 1.0
        rows.append(block)
        rhs.append(y[k])
    if not rows:
        raise MetricUnavailableError("eigenvalue identification: every output is constant")
    a_mat = np.vstack(rows)
    b_vec = np.concatenate(rhs)
    theta, *_ = np.linalg.lstsq(a_mat, b_vec, rcond=None)
    resid = b_vec - a_mat @ theta
    fit = float(np.sqrt(np.mean(resid ** 2)))
    z = np.roots(np.concatenate(([1.0], theta[:n])))
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.log(z.astype(complex)) / h
    s = s[np.argsort(-s.real)]
    if not np.all(np.isfinite(s)):
        raise MetricUnavailableError("eigenvalue identification: a root at z = 0 (no dynamics)")
    return IdentifiedModes(s, n, h, fit)


def match_eigenvalues(identified: np.ndarray, model: np.ndarray) -> list[tuple[complex, complex,
                                                                               float]]:
    """Pair each identified eigenvalue with the nearest model eigenvalue.

    Returns ``(identified, model, relative distance |id - model| / |model|)`` per pair.
    """
    pairs = []
    pool = list(np.asarray(model, dtype=complex))
    for e in np.asarray(identified, dtype=complex):
        if not pool:
            break
        k = int(np.argmin([abs(e - p) for p in pool]))
        p = pool.pop(k)
        pairs.append((complex(e), complex(p), abs(e - p) / max(abs(p), 1e-12)))
    return pairs


def damping_and_frequency(eig: complex) -> tuple[float, float]:
    """Damping ratio and natural frequency (Hz) of an eigenvalue (1/s)."""
    wn = abs(eig)
    return (-eig.real / wn if wn > 0 else math.nan), wn / (2 * math.pi)
