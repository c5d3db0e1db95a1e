# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws handling``: steady-state handling of the 2-DOF vehicle, FWS versus a law (ch. 4.5),
and the critical and characteristic speeds of every model level side by side.

Output (``--json``; keys are stable)::

    {"vehicle", "law", "understeer_gradient_rad_per_mps2", "understeer_gradient_deg_per_g",
     "steer_character", "characteristic_speed_mps" (understeer, else null),
     "critical_speed_mps" (oversteer FWS, else null), "law_critical_speed_mps",
     "equal_slope_speed_mps" (eq. 4.107; null if none in 1-100 m/s),
     "slopes": [{"speed_mps", "fws_deg_per_g", "law_deg_per_g",
                 "law_understeer_gradient_deg_per_g"}, ...],
     "speeds_model_level": "2dof"              (the level of every key above),
     "levels": [{"level" ("2dof", "3dof", "8dof-lin"), "label",
                 "understeer_gradient_rad_per_mps2", "steer_character",
                 "characteristic_speed_mps", "critical_speed_mps" (FWS),
                 "law_critical_speed_mps", "searched_range_mps",
                 "unavailable" (why a level has no numbers, else null)}, ...],
     "why_they_differ": [sentence, ...], "roll_steer_makes_oversteer": bool}
"""

from __future__ import annotations

import argparse
import json

from fourws_cli._bounds import KMH_PER_MPS, speed_mps
from fourws_cli._law_args import add_law_arguments, build_law
from fourws_sim.params import load_vehicle

HELP = ("understeer gradient, characteristic/critical speed per model level and FWS-vs-law "
        "steer slopes")


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


def _speed(x: float | None) -> str:
    return "none" if x is None else f"{x:.3f} m/s ({x * KMH_PER_MPS:.1f} km/h)"


def run(args: argparse.Namespace) -> int:
    """Run the handling analysis and print it; returns the exit code."""
    # scipy, control: not for --help
    from fourws_analysis.critical_speeds import LEVEL_DESCRIPTIONS, LEVELS
    from fourws_analysis.handling import handling_report

    speeds = [speed_mps("--speeds-mps", v) for v in args.speeds_mps]
    vehicle = load_vehicle(args.vehicle)
    law = build_law(args, vehicle)
    out = handling_report(vehicle, law, speeds).to_dict()
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    two = next(s["label"] for s in out["levels"] if s["level"] == out["speeds_model_level"])
    print(f"{out['vehicle']}  law {out['law']}")
    print(f"understeer gradient ({two}, axle_tires): "
          f"{out['understeer_gradient_rad_per_mps2']:.6g} rad/(m/s^2) = "
          f"{out['understeer_gradient_deg_per_g']:.4f} deg/g ({out['steer_character']})")
    print(f"characteristic speed ({two}): {_speed(out['characteristic_speed_mps'])}")
    print(f"critical speed (FWS, {two}): {_speed(out['critical_speed_mps'])}")
    print(f"critical speed with {out['law']} ({two}): {_speed(out['law_critical_speed_mps'])}")
    print(f"equal steer/ay slope speed (FWS vs {out['law']}, {two}): "
          f"{_f(out['equal_slope_speed_mps'], unit=' m/s')}")
    print(f"{two} steer slopes:")
    print(f"{'U (m/s)':>8} {'FWS deg/g':>10} {'law deg/g':>10} {'law K_us deg/g':>15}")
    for row in out["slopes"]:
        print(f"{row['speed_mps']:8.2f} {row['fws_deg_per_g']:10.4f} "
              f"{_f(row['law_deg_per_g'], '10.4f'):>10} "
              f"{_f(row['law_understeer_gradient_deg_per_g'], '15.4f'):>15}")
    print()
    print("speeds by model level:")
    print(f"  {'level':<22} {'K_us rad/(m/s^2)':>16} {'steer':10} {'characteristic':>24} "
          f"{'critical (FWS)':>24} {'critical (' + out['law'] + ')':>24}")
    for lv in out["levels"]:
        if lv["unavailable"]:
            print(f"  {lv['label']:<22} not available: {lv['unavailable']}")
            continue
        print(f"  {lv['label']:<22} {lv['understeer_gradient_rad_per_mps2']:>+16.4g} "
              f"{lv['steer_character']:10} {_speed(lv['characteristic_speed_mps']):>24} "
              f"{_speed(lv['critical_speed_mps']):>24} "
              f"{_speed(lv['law_critical_speed_mps']):>24}")
    for sentence in out["why_they_differ"]:
        print(f"  {sentence}")
    print("  levels: " + "; ".join(f"{LEVELS[k]} = {LEVEL_DESCRIPTIONS[k]}" for k in LEVELS))
    return 0
