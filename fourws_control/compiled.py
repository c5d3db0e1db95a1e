# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The laws as the study's compiled closed loop calls them, built from the law registry.

Each law class names, beside its Python law, the plain functions numba compiles for it:
:attr:`~fourws_control.base.Law.gain_functions` (the functions its
:class:`~fourws_control.base.GainFunction` may hold) and
:attr:`~fourws_control.base.Law.gain_helpers` (the plain functions those call). This module
collects them from :data:`fourws_control.registry.LAWS`, in the registry's order, and is the
only place that lists them:

* :func:`gain_functions`: every law's gain functions; the position of one is its *law kind*,
  the number the compiled loop dispatches on (:func:`law_kind`; None: the twin runs the law);
* :func:`source_modules`: the modules whose code the compiled loop compiles in (the digest of
  its disk cache, :class:`fourws_sim.variants.Variant`);
* :func:`compiled_gains`: the compiled dispatch ``gains(kind, speed_mps, params, out)``, after
  :func:`register` has let numba compile the laws' plain functions and the law step's
  (:data:`STEP_FUNCTIONS`).

The dispatch is a chain of links, one a law kind, built from :func:`gain_functions`: link
``k`` is ``if kind == k: f_k(speed, params, out) else: link_{k+1}(...)``. numba inlines every
link, so the chain compiles to the branches of a hand-written ``if``/``elif`` on the kind
(numba indexes a tuple of functions at run time only through its experimental first-class
function types).

A new law is its module and one line in the registry: the study's compiled loop takes it from
here, the simulator's controller and the analysis from the registry.
"""

from __future__ import annotations

import functools
import sys
from types import ModuleType
from typing import Any, Callable

from fourws_control import base, registry
from fourws_control.base import Law
from fourws_sim import variants

#: The plain functions of a law step the compiled loop calls besides the law's gains: the
#: low-speed fade, the sum of the gained signals, the actuator's limits.
STEP_FUNCTIONS = (base.gain_speed, base.rear_angle_of, base.actuator_step)
#: numba options of the dispatch and the gain functions (those of the kernels they are
#: inlined into: IEEE division, no fast-math).
JIT_OPTIONS: dict[str, Any] = {"error_model": "numpy"}


@functools.cache
def law_classes() -> tuple[type[Law], ...]:
    """The registered law classes, in :data:`~fourws_control.registry.LAWS` order."""
    return tuple(registry.law_class(name) for name in registry.LAWS)


@functools.cache
def gain_functions() -> tuple[Callable[..., None], ...]:
    """Every registered law's gain functions, in registry order; the position is the law
    kind."""
    found: list[Callable[..., None]] = []
    for cls in law_classes():
        found += [f for f in cls.gain_functions if f not in found]
    return tuple(found)


def law_kind(function: Callable[..., None]) -> int | None:
    """The law kind of gain function ``function`` (its position in :func:`gain_functions`),
    or None if no registered law declares it."""
    for kind, candidate in enumerate(gain_functions()):
        if candidate is function:
            return kind
    return None


@functools.cache
def source_modules() -> tuple[ModuleType, ...]:
    """The modules whose functions the compiled dispatch and law step compile in: this one,
    the registry (the order of the kinds), :mod:`fourws_control.base` and every law's."""
    modules: list[ModuleType] = [sys.modules[__name__], registry, base]
    for cls in law_classes():
        module = sys.modules[cls.__module__]
        if module not in modules:
            modules.append(module)
    return tuple(modules)


def register() -> None:
    """Let numba compile the law step's plain functions and every law's helpers where
    compiled code calls them (once per process; they stay plain Python functions)."""
    variants.register_plain(STEP_FUNCTIONS)
    for cls in law_classes():
        variants.register_plain(cls.gain_helpers)


def _no_law(kind, speed_mps, params, out):  # type: ignore[no-untyped-def]
    """The end of the chain: a kind no law has (``out`` unchanged)."""


def _link(kind: int, gain: Any, rest: Any) -> Any:
    """The dispatch link of law kind ``kind``: ``gain`` for it, ``rest`` for the others."""
    # numba: the compiled loop only (the interpreted twin runs without it)
    import numba

    def link(k, speed_mps, params, out):  # type: ignore[no-untyped-def]
        if k == kind:
            gain(speed_mps, params, out)
        else:
            rest(k, speed_mps, params, out)
    return numba.njit(inline="always", **JIT_OPTIONS)(link)


@functools.cache
def compiled_gains() -> Any:
    """The compiled ``gains(kind, speed_mps, params, out)``: the gain function of law kind
    ``kind`` at ``speed_mps`` (m/s) into ``out`` (:class:`~fourws_control.base.GainFunction`'s
    contract), for compiled callers (inlined into them)."""
    # numba: the compiled loop only (the interpreted twin runs without it)
    import numba

    register()
    chain = numba.njit(inline="always", **JIT_OPTIONS)(_no_law)
    functions = gain_functions()
    for kind in reversed(range(len(functions))):
        chain = _link(kind, numba.njit(inline="always", **JIT_OPTIONS)(functions[kind]), chain)
    return chain


__all__ = ["JIT_OPTIONS", "STEP_FUNCTIONS", "compiled_gains", "gain_functions", "law_classes",
           "law_kind", "register", "source_modules"]
