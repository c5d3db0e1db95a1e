# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws tire-curves``: normalized lateral tire force in the axes of Figures C.1 and C.2.

Output (``--json``)::

    {"vehicle": NAME, "axle": "front"|"rear", "tire_model": str, "fz_n": Fz, "mu": mu,
     "cornering_stiffness_n_per_rad": C (per tire, at Fz),
     "fig_c1_vs_slip_angle_deg": [{"label", "x", "fy_over_fz", "fx_over_fz",
                                   "peak_fy_over_fz", "x_at_peak"}, ...],
     "fig_c2_vs_slip_ratio": [...same...]}

Without ``--json`` a summary table (peak ``Fy/Fz`` and where it occurs) is printed.
``--png FILE`` draws both figures.
"""

from __future__ import annotations

import argparse
import json

from fourws_cli._bounds import bounded
from fourws_sim.params import load_vehicle

HELP = "normalized lateral tire force vs slip angle / slip ratio (Figures C.1, C.2)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``tire-curves`` sub-parser."""
    parser.add_argument("--vehicle", required=True,
                        help="vehicle name (file stem under config/vehicles) or YAML path, "
                             "e.g. table_8_1")
    parser.add_argument("--axle", choices=("front", "rear"), default="front",
                        help="axle whose tire coefficients and static load are used")
    parser.add_argument("--fz-n", type=float, default=None,
                        help="normal load in N (default: FZT for the sti tire, else the "
                             "static load of one tire on the axle)")
    parser.add_argument("--tire", default=None,
                        help="tire model name overriding the vehicle's (linear, sti, "
                             "magic_formula)")
    parser.add_argument("--png", metavar="FILE", help="draw Figures C.1/C.2 to this PNG")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace) -> int:
    """Compute, print and optionally plot the curves; returns the exit code."""
    # scipy, control: not for --help
    from fourws_analysis.tire_curves import plot_tire_curves, tire_curves
    from fourws_sim.tires import cornering_stiffness, get_tire  # numba: not for --help

    if args.fz_n is not None:
        bounded("--fz-n", args.fz_n, 0.0, 1e6, " N", low_open=True)
    vehicle = load_vehicle(args.vehicle)
    curves = tire_curves(vehicle, axle=args.axle, fz_n=args.fz_n, tire_model=args.tire)
    coeffs = get_tire(curves.tire_model).pack(vehicle, args.axle)
    c_alpha = cornering_stiffness(curves.tire_model, coeffs, curves.fz_n, curves.mu)
    out = {"vehicle": vehicle.name, "axle": args.axle, "cornering_stiffness_n_per_rad": c_alpha}
    out.update(curves.to_dict())
    if args.png:
        out["png"] = str(plot_tire_curves(curves, args.png))
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{vehicle.name}: {curves.tire_model} tire, {args.axle} axle, Fz = {curves.fz_n:.1f} N, "
          f"mu = {curves.mu:g}, cornering stiffness {c_alpha:.0f} N/rad per tire")
    print("Figure C.1 (Fy/Fz vs slip angle):")
    for c in curves.vs_slip_angle:
        print(f"  {c.label:<20} peak Fy/Fz {c.peak:.3f} at {c.x_at_peak:.1f} deg")
    print("Figure C.2 (Fy/Fz vs longitudinal slip):")
    for c in curves.vs_slip_ratio:
        print(f"  {c.label:<20} Fy/Fz {c.fy_over_fz[0]:.3f} at s = 0, "
              f"{c.fy_over_fz[-1]:.3f} at s = 1 (locked)")
    if args.png:
        print(f"plot: {out['png']}")
    return 0
