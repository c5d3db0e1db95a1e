# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Tire models: pure scalar functions that ``numba.njit`` can compile.

Every tire module exposes

``forces(fz_n, alpha_rad, kappa, vx_mps, mu, coeffs) -> (fx_n, fy_n, mz_nm)``
    tire-frame forces (plain float math: no Python objects, no exceptions inside);
``pack(vehicle, axle) -> numpy.ndarray``
    the float64 coefficient array of one tire on ``"front"`` or ``"rear"``;
``pack_mapping(values, source, prefix)`` (the tires with fitted coefficients, ``sti`` and
    ``magic_formula``: the file's ``tire.<name>`` mapping)
    the same from a file's coefficient mapping: all validation of coefficient names and
    values happens here (the vehicle loader calls it, so every tool refuses a bad key);
``N_COEFFS`` and an ``IntEnum`` ``COEF`` naming the array slots.

Sign conventions (``docs/architecture.md``): ``Fy = -C_alpha * alpha`` for small slip angle,
``Fx = +C_s * kappa`` for small slip ratio (positive under drive, -1 locked).

The argument ``mu`` is the road friction coefficient. For ``linear`` it is the absolute peak
friction; ``sti``, ``magic_formula`` and ``tmeasy`` carry their own (load- and speed-dependent)
peak friction measured on a test surface, and ``mu`` scales it (1.0 = the test surface).

Optional, for the compiled kernels: ``forces4`` (the four wheels interleaved, for the 8-DOF
kernels' speed) and ``forces_lane`` (branch-free, for the study's batch kernel in vector
instructions, :mod:`fourws_sim.lanes`), each giving exactly the numbers of ``forces``.

A new tire model is its module plus one line in :data:`TIRES` (and, if the vehicle file gives
its coefficients as a ``tire.<name>`` mapping, that field of
:class:`fourws_sim.params.Tire`); everything else takes the names from here.
"""

from __future__ import annotations

import importlib
from types import ModuleType

import numpy as np

from fourws_sim.errors import UnknownNameError

#: The one list of tire models: name -> module, imported on first use by :func:`get_tire`
#: (the tires bring numba; vehicle files, scenarios and nodes need only the names).
TIRES: dict[str, str] = {
    "linear": "fourws_sim.tires.linear",
    "sti": "fourws_sim.tires.sti",
    "magic_formula": "fourws_sim.tires.magic_formula",
    "tmeasy": "fourws_sim.tires.tmeasy",
}

#: Step of the central difference used by :func:`cornering_stiffness`, rad.
_STIFFNESS_STEP_RAD = 1.0e-5
#: Forward speed at which :func:`cornering_stiffness` evaluates the tire, m/s.
_STIFFNESS_SPEED_MPS = 20.0


def get_tire(name: str) -> ModuleType:
    """Tire module by name (``get_tire("sti").forces(...)``).

    Raises
    ------
    UnknownNameError
        If ``name`` is not one of :data:`TIRES`.
    """
    try:
        target = TIRES[name]
    except (KeyError, TypeError):
        raise UnknownNameError("tire model", str(name), list(TIRES)) from None
    return importlib.import_module(target)


def cornering_stiffness(name: str, coeffs: np.ndarray, fz_n: float, mu: float = 1.0) -> float:
    """Small-slip cornering stiffness ``-dFy/dalpha`` at ``alpha = kappa = 0``, in N/rad.

    Numerical central difference of the tire's lateral force (per tire, positive).

    Parameters
    ----------
    name : str
        Tire model name.
    coeffs : numpy.ndarray
        The model's coefficient array (from its ``pack``).
    fz_n : float
        Normal load in N.
    mu : float
        Road friction (does not change the small-slip slope of a physical tire).
    """
    forces = get_tire(name).forces
    h = _STIFFNESS_STEP_RAD
    _, fy_plus, _ = forces(fz_n, h, 0.0, _STIFFNESS_SPEED_MPS, mu, coeffs)
    _, fy_minus, _ = forces(fz_n, -h, 0.0, _STIFFNESS_SPEED_MPS, mu, coeffs)
    return float(-(fy_plus - fy_minus) / (2.0 * h))
