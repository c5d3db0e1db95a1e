# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The one place rear-steer laws are registered: name -> ``module:Class``.

A new law is one module (a :class:`fourws_control.base.Law` subclass) plus one line here.
Modules are imported on first use.
"""

from __future__ import annotations

import importlib
from typing import Any, Mapping

from fourws_control.base import Law
from fourws_sim.errors import ParameterError, UnknownNameError
from fourws_sim.params import Vehicle

#: Law name -> "module:class".
LAWS: dict[str, str] = {
    "fws": "fourws_control.fws:FwsLaw",
    "ff_zero_sideslip": "fourws_control.ff_zero_sideslip:FfZeroSideslipLaw",
    "sol1": "fourws_control.sol1:Sol1Law",
    "sol2": "fourws_control.sol2:Sol2Law",
    "rwc1_3dof": "fourws_control.rwc_3dof:Rwc1Law",
    "rwc2_3dof": "fourws_control.rwc_3dof:Rwc2Law",
    "rwc4_3dof": "fourws_control.rwc_3dof:Rwc4Law",
    "lqr": "fourws_control.lqr:LqrLaw",
}


def available_laws() -> list[str]:
    """Names of the registered laws."""
    return sorted(LAWS)


def law_class(name: str) -> type[Law]:
    """The :class:`Law` subclass registered as ``name``.

    Raises
    ------
    UnknownNameError
        If ``name`` is not registered (the message lists the valid names).
    """
    try:
        target = LAWS[name]
    except (KeyError, TypeError):
        raise UnknownNameError("law", str(name), list(LAWS)) from None
    module, cls = target.split(":")
    return getattr(importlib.import_module(module), cls)


def make_law(name: str, belief_vehicle: Vehicle, **options: Any) -> Law:
    """Build law ``name`` with gains computed from ``belief_vehicle``.

    Parameters
    ----------
    name : str
        One of :data:`LAWS`.
    belief_vehicle : Vehicle
        The controller's belief of the vehicle (may differ from the simulated one).
    **options
        Law options (``min_speed_mps`` for every law; see each law for its own).

    Raises
    ------
    UnknownNameError
        Unknown law name.
    ParameterError
        Unknown or invalid option, or the belief vehicle lacks what the law needs.
    """
    cls = law_class(name)
    try:
        return cls(belief_vehicle, **options)
    except TypeError as exc:
        # an unexpected keyword is the caller's error: name the option and the law
        raise ParameterError("options", f"law {name!r}: {exc}") from None


def make_loop_law(name: str, belief_vehicle: Vehicle, control_period_s: float,
                  options: Mapping[str, Any] | None = None) -> Law:
    """Build law ``name`` for a loop that applies its command every ``control_period_s``.

    The loop's period is the one source of the law's ``control_period_s`` (a sampled design
    such as ``lqr``'s is computed for it); the offline runner and the controller node build
    their laws here.

    Parameters
    ----------
    name : str
        One of :data:`LAWS`.
    belief_vehicle : Vehicle
        The controller's belief of the vehicle.
    control_period_s : float
        The loop's control period, s (> 0).
    options : mapping, optional
        The law's other options.

    Raises
    ------
    ParameterError
        ``options`` sets ``control_period_s`` (the loop sets it), or as :func:`make_law`.
    UnknownNameError
        Unknown law name.
    """
    opts = dict(options or {})
    if "control_period_s" in opts:
        raise ParameterError("law_options.control_period_s",
                             f"law {name!r}: the law runs at the loop's control period "
                             f"({control_period_s} s); set the scenario's control_period_s "
                             "instead")
    return make_law(name, belief_vehicle, control_period_s=control_period_s, **opts)
