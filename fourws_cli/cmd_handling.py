# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws handling``: steady-state handling of the 2-DOF vehicle, FWS versus a law (ch. 4.5).

Output (``--json``; keys are stable)::

    {"vehicle", "law", "understeer_gradient_rad_per_mps2", "understeer_gradient_deg_per_g",
     "steer_character", "characteristic_speed_mps" (understeer, else null),
     "critical_speed_mps" (oversteer FWS, else null), "law_critical_speed_mps",
     "equal_slope_speed_mps" (eq. 4.107; null if none in 1-100 m/s),
     "slopes": [{"speed_mps", "fws_deg_per_g", "law_deg_per_g",
                 "law_understeer_gradient_deg_per_g"}, ...]}
"""

from __future__ import annotations

import argparse
import json

from fourws_cli._bounds import speed_mps
from fourws_cli._law_args import add_law_arguments, build_law
from fourws_sim.params import load_vehicle

HELP = "understeer gradient, characteristic/critical speed and FWS-vs-law steer slopes"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``handling`` sub-parser."""
    parser.add_argument("--vehicle", required=True,
                        help="vehicle name (file stem under config/vehicles) or YAML path")
    add_law_arguments(parser, default="fws")
    parser.add_argument("--speeds-mps", type=float, nargs="+", default=[7.0, 15.0, 25.0],
                        help="speeds of the steer-slope table, m/s")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def _f(x: float | None, fmt: str = ".3f", unit: str = "") -> str:
    return "none" if x is None else f"{x:{fmt}}{unit}"


def run(args: argparse.Namespace) -> int:
    """Run the handling analysis and print it; returns the exit code."""
    from fourws_analysis.handling import handling_report  # scipy, control: not for --help

    speeds = [speed_mps("--speeds-mps", v) for v in args.speeds_mps]
    vehicle = load_vehicle(args.vehicle)
    law = build_law(args, vehicle)
    out = handling_report(vehicle, law, speeds).to_dict()
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print(f"{out['vehicle']}  law {out['law']}")
    print(f"understeer gradient: {out['understeer_gradient_rad_per_mps2']:.6g} rad/(m/s^2) = "
          f"{out['understeer_gradient_deg_per_g']:.4f} deg/g ({out['steer_character']})")
    print(f"characteristic speed: {_f(out['characteristic_speed_mps'], unit=' m/s')}")
    print(f"critical speed (FWS): {_f(out['critical_speed_mps'], unit=' m/s')}")
    print(f"critical speed with {out['law']}: {_f(out['law_critical_speed_mps'], unit=' m/s')}")
    print(f"equal steer/ay slope speed (FWS vs {out['law']}): "
          f"{_f(out['equal_slope_speed_mps'], unit=' m/s')}")
    print(f"{'U (m/s)':>8} {'FWS deg/g':>10} {'law deg/g':>10} {'law K_us deg/g':>15}")
    for row in out["slopes"]:
        print(f"{row['speed_mps']:8.2f} {row['fws_deg_per_g']:10.4f} "
              f"{_f(row['law_deg_per_g'], '10.4f'):>10} "
              f"{_f(row['law_understeer_gradient_deg_per_g'], '15.4f'):>15}")
    return 0
