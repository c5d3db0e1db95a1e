# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Tire variants of the compiled kernels: the one loader, digest and naming rule.

The compiled kernels call a tire model's functions as compile-time globals, so that numba
inlines them and keeps one disk-cache entry per tire (a kernel that took the tire as an
argument, or a closure over it, would be compiled again in every new process). A kernel
module written this way is a *template*, compiled once per tire model:

* :mod:`fourws_sim.models.eightdof_kernels`: the 8-DOF right-hand side and integrators
  (:func:`fourws_sim.models.eightdof.kernels_for`);
* :mod:`fourws_study.loop_kernels`: the study's closed loop, built on the former
  (:func:`fourws_study.kernel.loop_kernel_for`).

:func:`load` runs a template's file once per tire and process as a module of its own, named
``<template>[<tire>]`` (``fourws_sim.models.eightdof_kernels[sti]``), kept in
``sys.modules``; the template reads its tire from that name (:func:`tire_of`; a plain import
of a template gives the :data:`DEFAULT_TIRE` variant, which nothing runs). So every variant
module is the template's source with one tire, and a reader finds each of its globals in that
source.

Inside a template one :class:`Variant` compiles the functions: :meth:`Variant.jit` with
numba's disk cache under a name that holds the tire and a digest of every source compiled into
the variant (numba checks only the stamp of a function's own file and names its cache files
after the function, so without the digest an edited tire, model or law would run from a stale
cache and the tires' variants would share one entry), :meth:`Variant.inline` for the functions
inlined into their callers. :func:`register_plain` lets numba compile plain functions of other
modules (the laws', the driver's) where a kernel calls them, which stay plain Python for
everyone else.
"""

from __future__ import annotations

import hashlib
import importlib.util
import re
import sys
import types
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Iterable, Mapping

from fourws_sim.tires import get_tire

#: Tire of a template imported under its own name (not through :func:`load`).
DEFAULT_TIRE = "linear"
_VARIANT_NAME = re.compile(r"^(?P<template>[\w.]+)\[(?P<tire>\w+)\]$")
#: Plain functions numba may compile where a kernel calls them (:func:`register_plain`).
_REGISTERED: set[Callable[..., Any]] = set()


def variant_name(template: str, tire_name: str) -> str:
    """The module name of the variant of ``template`` (a dotted module name) for a tire."""
    return f"{template}[{tire_name}]"


def tire_of(module_name: str) -> str:
    """The tire of the variant module named ``module_name`` (a template's ``__name__``);
    :data:`DEFAULT_TIRE` for the template imported under its own name."""
    match = _VARIANT_NAME.match(module_name)
    return match["tire"] if match else DEFAULT_TIRE


def load(template: str, tire_name: str) -> ModuleType:
    """The variant of the template module ``template`` for tire model ``tire_name``: its file
    run once per process as the module :func:`variant_name` (later calls return it).

    Raises
    ------
    UnknownNameError
        If ``tire_name`` is not a tire model (before anything is run).
    """
    get_tire(tire_name)
    name = variant_name(template, tire_name)
    module = sys.modules.get(name)
    if module is None:
        found = importlib.util.find_spec(template)
        assert found is not None and found.origin is not None, template
        spec = importlib.util.spec_from_file_location(name, found.origin)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # before it runs, as an import does
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
    return module


class Variant:
    """How a template compiles its functions for one tire (see the module docstring).

    Parameters
    ----------
    module_file : str
        The template's file (its ``__file__``).
    tire_name : str
        The variant's tire (:func:`tire_of` of the module's ``__name__``).
    sources : iterable of module
        Every other module whose code or constants the variant compiles in.
    options : mapping
        numba options of every function of the variant.
    depends : iterable of Variant
        Variants whose compiled functions this one calls (their digests enter this one's).

    Attributes
    ----------
    tire : str
    digest : str
        12 hex digits of the SHA-1 of the template, the options, the sources and the digests
        of ``depends``.
    name : str
        ``<tire>_<digest>``: the suffix of every compiled function's cache name.
    """

    def __init__(self, module_file: str, tire_name: str, sources: Iterable[ModuleType],
                 options: Mapping[str, Any], depends: Iterable[Variant] = ()) -> None:
        digest = hashlib.sha1()
        digest.update(Path(module_file).read_bytes())
        digest.update(repr(sorted(options.items())).encode())
        for module in sources:
            digest.update(Path(module.__file__).read_bytes())  # type: ignore[arg-type]
        for other in depends:
            digest.update(other.digest.encode())
        self.tire = tire_name
        self.options = dict(options)
        self.digest = digest.hexdigest()[:12]
        self.name = f"{tire_name}_{self.digest}"

    def jit(self, func: Callable[..., Any]) -> Any:
        """``func`` compiled for this variant and cached on disk as ``<name>_<variant>`` (a
        copy of it, so the template's own function keeps its name)."""
        # numba: only the compiled kernels load it (about 0.5 s)
        import numba

        copy = types.FunctionType(func.__code__, func.__globals__, func.__name__,
                                  func.__defaults__, func.__closure__)
        copy.__qualname__ = f"{func.__name__}_{self.name}"
        copy.__doc__ = func.__doc__
        return numba.njit(cache=True, **self.options)(copy)

    def inline(self, func: Callable[..., Any]) -> Any:
        """``func`` compiled to be inlined (numba IR) into the kernels that call it."""
        # numba: only the compiled kernels load it (about 0.5 s)
        import numba

        return numba.njit(inline="always", **self.options)(func)


def register_plain(functions: Iterable[Callable[..., Any]]) -> None:
    """Let numba compile the plain functions ``functions`` where compiled code calls them
    (each once per process; they stay ordinary Python functions for every other caller)."""
    # numba: only the compiled kernels load it (about 0.5 s)
    from numba.extending import register_jitable

    for function in functions:
        if function not in _REGISTERED:
            register_jitable(function)
            _REGISTERED.add(function)


__all__ = ["DEFAULT_TIRE", "Variant", "load", "register_plain", "tire_of", "variant_name"]
