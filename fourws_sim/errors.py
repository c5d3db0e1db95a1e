# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Package exceptions of fourws.

Every error a user can cause (a bad file, a bad name, a bad number) is raised as one of
these. They subclass :class:`ValueError` (or :class:`TypeError`) so callers that do not know
fourws still catch them; command-line tools and nodes catch :class:`FourwsError` at their
boundary and print its message, which always names the offending field and, where there is
one, the file.
"""

from __future__ import annotations


class FourwsError(ValueError):
    """Base class of every user-facing fourws error."""


class ParameterError(FourwsError):
    """A parameter is missing, unknown, of the wrong type or out of its valid range.

    Parameters
    ----------
    field : str
        Dotted name of the field, e.g. ``"chassis.mass_kg"``.
    problem : str
        What is wrong with it.
    source : str, optional
        File (or other origin) the value came from.
    """

    def __init__(self, field: str, problem: str, source: str | None = None) -> None:
        self.field = field
        self.problem = problem
        self.source = source
        where = f" in {source}" if source else ""
        super().__init__(f"{field}: {problem}{where}")


class UnknownNameError(FourwsError):
    """A name (model, tire, law, integrator, maneuver, vehicle) is not one of the known ones."""

    def __init__(self, kind: str, name: object, valid: list[str] | tuple[str, ...],
                 source: str | None = None) -> None:
        self.kind = kind
        self.name = name
        self.valid = sorted(valid)
        self.source = source
        where = f" in {source}" if source else ""
        super().__init__(f"unknown {kind} {describe(name)}; valid: {', '.join(self.valid)}"
                         f"{where}")


class NonFiniteError(FourwsError):
    """A state, input or result is NaN or infinite."""


class DivergedError(NonFiniteError):
    """The simulated state became non-finite: the simulation diverged.

    Not a user-input error but an outcome of the run (a car driven past what the model can
    represent); runs report it with its time as their result (``fourws_run``).

    Parameters
    ----------
    message : str
        What diverged, and where.
    time_s : float
        Simulation time of the last finite state, s.
    """

    def __init__(self, message: str, time_s: float) -> None:
        super().__init__(message)
        self.time_s = time_s


class IncompatibleError(FourwsError):
    """Two valid things that do not go together (e.g. a 3-DOF law on a 2-DOF model)."""


def describe(value: object, limit: int = 60) -> str:
    """``repr(value)`` cut to ``limit`` characters, for messages that quote a bad value (a
    value may be a whole sub-document of a file)."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 5] + " ...>"


def one_line(exc: BaseException) -> str:
    """The message of ``exc`` on one line (whitespace runs, newlines included, become one
    space), as command-line tools and nodes print it."""
    return " ".join(str(exc).split()) or type(exc).__name__
