# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws linear``: eigenvalues, damping, Routh-Hurwitz, steady-state gains of a linear model
closed with a rear-steer law.

Output (``--json``; keys are stable)::

    {"vehicle", "model", "law", "speed_mps", "speed_kmh",
     "eigenvalues": [[re, im], ...]            (1/s),
     "natural_frequencies_hz": [...], "damping_ratios": [...], "stable": bool,
     "steady_state_gains": {"output/input": gain} or null,
     "routh_hurwitz": {"coefficients", "first_column", "conditions", "sign_changes", "stable",
                       "array"},
     "controllability": {...}, "law_gains": {...},
     "lyapunov": {"stable", "leading_minors"}   (chapter 5: A^T P + P A = -I, Sylvester),
     "critical_speed_mps": float or null        (with --critical-speed),
     "critical_speed_model_level": the model   (with --critical-speed: the level of that
                                                 number, as fourws handling names it),
     "critical_speed_8dof_free": {...}          (with --model 2dof-free --critical-speed: the
                                                 free-control critical speed of the linearized
                                                 8-DOF with its steering system, same car and
                                                 law, or why it is unavailable),
     "transfer_functions": [...]                (with --transfer-functions),
     "bode": {"frequencies_hz", "magnitude", "phase_deg", "units"}  (with --bode),
     "bode_plot": PNG path                       (with --bode-plot)}
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from fourws_cli._bounds import KMH_PER_MPS, speed_kmh, speed_mps
from fourws_cli._law_args import add_law_arguments, build_law
from fourws_sim.errors import ParameterError
from fourws_sim.params import load_vehicle

HELP = "eigenvalues, damping, Routh-Hurwitz and steady-state gains of a linear model with a law"
MODELS = ("2dof", "2dof-free", "2dof-lagged", "3dof")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``linear`` sub-parser."""
    parser.add_argument("--vehicle", required=True,
                        help="vehicle name (file stem under config/vehicles) or YAML path")
    parser.add_argument("--model", required=True, choices=MODELS, help="linear model")
    add_law_arguments(parser)
    parser.add_argument("--speed-kmh", required=True, type=float,
                        help="forward speed in km/h (> 0)")
    parser.add_argument("--critical-speed", action="store_true",
                        help="also search --speed-range-mps for the speed where stability "
                             "is lost")
    parser.add_argument("--speed-range-mps", type=float, nargs=2, default=[1.0, 100.0],
                        metavar=("LO", "HI"), help="critical-speed search range, m/s")
    parser.add_argument("--transfer-functions", action="store_true",
                        help="include the transfer functions (JSON)")
    parser.add_argument("--bode", action="store_true",
                        help="include Bode data, 0.01-10 Hz (JSON)")
    parser.add_argument("--bode-plot", metavar="PNG",
                        help="draw the Bode plots of this law and of FWS to a PNG")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def _c(z: list[float]) -> str:
    re, im = z
    return f"{re:10.4f}" if im == 0.0 else f"{re:10.4f} {im:+.4f}j"


def run(args: argparse.Namespace) -> int:
    """Run the analysis and print it; returns the exit code."""
    from fourws_analysis import linear  # scipy, control: not for --help
    from fourws_analysis.critical_speeds import LEVELS

    speed = speed_kmh("--speed-kmh", args.speed_kmh) / KMH_PER_MPS
    low, high = (speed_mps("--speed-range-mps", v) for v in args.speed_range_mps)
    if not low < high:
        raise ParameterError("--speed-range-mps", f"LO must be below HI, got {low!r} {high!r}")
    vehicle = load_vehicle(args.vehicle)
    law = build_law(args, vehicle)
    report = linear.linear_report(args.model, vehicle, law, speed,
                                  with_critical_speed=args.critical_speed,
                                  speed_range_mps=(low, high))
    out = report.to_dict()
    if args.critical_speed and args.model == "2dof-free":
        out["critical_speed_8dof_free"] = _eightdof_free(vehicle, law, args.speed_range_mps)
    if args.transfer_functions or args.bode or args.bode_plot:
        cl = linear.closed_loop(args.model, vehicle, law, speed)
        if args.transfer_functions:
            out["transfer_functions"] = [t.to_dict() for t in linear.transfer_functions(cl)]
        if args.bode:
            out["bode"] = linear.bode(cl).to_dict()
        if args.bode_plot:
            fws = linear.closed_loop(args.model, vehicle, "fws", speed)
            out["bode_plot"] = str(linear.plot_bode(
                [(law.name, linear.bode(cl)), ("fws", linear.bode(fws))], args.bode_plot))
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print(f"{out['vehicle']}  model {out['model']}  law {out['law']}  "
          f"U = {out['speed_kmh']:g} km/h ({out['speed_mps']:.3f} m/s)")
    if out["law_gains"]:
        print("law gains: " + ", ".join(f"{k} {v:.5g}" for k, v in out["law_gains"].items()))
    print(f"{'eigenvalue (1/s)':>28} {'f_n (Hz)':>10} {'damping':>9}")
    for z, f, d in zip(out["eigenvalues"], out["natural_frequencies_hz"],
                       out["damping_ratios"]):
        print(f"{_c(z):>28} {f:10.4f} {d:9.4f}")
    print(f"stable: {'yes' if out['stable'] else 'NO'}")
    rh = out["routh_hurwitz"]
    print("Routh-Hurwitz: " + "; ".join(
        f"{c['name']} ({c['value']:.5g}) {'ok' if c['satisfied'] else 'VIOLATED'}"
        for c in rh["conditions"]))
    ly = out["lyapunov"]
    pd = "positive definite" if ly["stable"] else "NOT positive definite"
    print(f"Lyapunov (A'P + PA = -I): P {pd}")
    ctrb = out["controllability"]
    print(f"controllable by rear steer: {'yes' if ctrb['controllable'] else 'no'} "
          f"(rank {ctrb['rank']}/{ctrb['n_states']})")
    gains = out["steady_state_gains"]
    if gains is None:
        print("steady-state gains: none (zero eigenvalue)")
    else:
        print("steady-state gains:" + ("" if out["stable"] else " (not reached: unstable)"))
        for k, v in gains.items():
            print(f"  {k:<28} {v:12.6g}")
    if "bode_plot" in out:
        print(f"Bode plot: {out['bode_plot']}")
    if args.critical_speed:
        cs = out["critical_speed_mps"]
        lo, hi = out["critical_speed_search"]["searched_range_mps"]
        level = LEVELS.get(args.model, f"{args.model} model")
        print(f"critical speed ({level}): " + (
            f"{cs:.3f} m/s ({cs * KMH_PER_MPS:.1f} km/h)" if cs is not None
            else f"none (stable {lo:g}-{hi:g} m/s)"))
    if "critical_speed_8dof_free" in out:
        free = out["critical_speed_8dof_free"]
        cs = free["critical_speed_mps"]
        what = (free["unavailable"] if free["unavailable"] else
                f"{cs:.3f} m/s ({cs * KMH_PER_MPS:.1f} km/h)" if cs is not None else
                f"none (stable {lo:g}-{hi:g} m/s)")
        print(f"critical speed of the linearized 8-DOF with its steering system "
              f"(8dof-free, Coulomb friction left out): {what}")
    return 0


def _eightdof_free(vehicle: Any, law: Any, speed_range: list[float]) -> dict[str, Any]:
    """The 8dof-free critical speed of the same car and law, or why it is unavailable."""
    from fourws_analysis import free_control  # scipy, control: not for --help

    try:
        crit = free_control.eightdof_free_critical_speed(vehicle, law,
                                                         speed_range_mps=tuple(speed_range))
    except ParameterError as exc:
        return {"critical_speed_mps": None, "unavailable": str(exc)}
    return {**crit.to_dict(), "unavailable": None,
            "coulomb_friction": "left out of the linearization (no small-signal form)"}
