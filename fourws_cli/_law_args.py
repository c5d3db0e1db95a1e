# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Shared command-line options for choosing a rear-steer law and the controller's belief."""

from __future__ import annotations

import argparse
from typing import Any

from fourws_cli._bounds import BELIEF_SCALE, bounded
from fourws_control import Law, available_laws, make_law
from fourws_sim.errors import ParameterError
from fourws_sim.params import Vehicle


def add_law_arguments(parser: argparse.ArgumentParser, default: str | None = None) -> None:
    """Add ``--law``, ``--law-option KEY=VALUE`` and ``--belief-tire-scale``."""
    parser.add_argument("--law", required=default is None, default=default,
                        help=f"rear-steer law: {', '.join(available_laws())}")
    parser.add_argument("--law-option", action="append", default=[], metavar="KEY=VALUE",
                        help="law option, repeatable (e.g. model=3dof, q=20 for lqr)")
    parser.add_argument("--belief-tire-scale", type=float, default=None, metavar="X",
                        help="the controller believes cornering stiffnesses scaled by X "
                             "(e.g. 0.6 for the paper's -40 %% study)")


def _value(text: str) -> Any:
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            continue
    return text


def law_options(items: list[str]) -> dict[str, Any]:
    """Parse ``KEY=VALUE`` strings (numbers become int/float)."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ParameterError("--law-option", f"expected KEY=VALUE, got {item!r}")
        out[key.strip()] = _value(value.strip())
    return out


def build_law(args: argparse.Namespace, vehicle: Vehicle) -> Law:
    """The law of the parsed arguments, designed on the (possibly scaled) belief vehicle."""
    belief = vehicle
    if args.belief_tire_scale is not None:
        scale = bounded("--belief-tire-scale", args.belief_tire_scale, *BELIEF_SCALE)
        belief = vehicle.with_axle_tires(scale)
    return make_law(args.law, belief, **law_options(args.law_option))
