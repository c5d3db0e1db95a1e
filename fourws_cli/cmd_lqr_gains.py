# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws lqr-gains``: LQR rear-steer gains versus speed and sideslip weight (ch. 3).

Output (``--json``; keys are stable)::

    {"model", "vehicle", "speeds_mps", "q_values", "weights", "state_names",
     "gain_convention": "delta_r = -K x",
     "gains": {STATE: [[K per q] per speed]}, "eigenvalues": [[[[re, im] ...] per q] per speed]}

``--plot PNG`` draws the gain curves (Figures 3.5/3.6/3.13-3.15/3.23-3.26) and the root locus.
"""

from __future__ import annotations

import argparse
import json

from fourws_cli._bounds import speed_mps
from fourws_sim.errors import ParameterError
from fourws_sim.params import load_vehicle

HELP = "LQR rear-steer gains versus speed and weight q (JSON, table or plot)"
#: Largest LQR weight accepted on the command line.
MAX_WEIGHT = 1e8


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``lqr-gains`` sub-parser."""
    parser.add_argument("--vehicle", required=True,
                        help="vehicle name (file stem under config/vehicles) or YAML path")
    parser.add_argument("--model", default="2dof", choices=("2dof", "2dof-free", "3dof"),
                        help="design model")
    parser.add_argument("--speeds", type=float, nargs="+", default=[10.0, 20.0, 30.0, 40.0],
                        help="forward speeds, m/s")
    parser.add_argument("--q", type=float, nargs="+",
                        default=[0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 30.0, 40.0, 50.0],
                        help="weights on lateral velocity (sideslip), (m/s)^-2")
    parser.add_argument("--p", type=float, default=1.0, help="weight on the rear angle")
    parser.add_argument("--q-steer", type=float, default=0.0,
                        help="weight on the front angle (2dof-free)")
    parser.add_argument("--q-yaw", type=float, default=0.0, help="weight on yaw rate (3dof)")
    parser.add_argument("--q-roll", type=float, default=0.0, help="weight on roll angle (3dof)")
    parser.add_argument("--q-roll-rate", type=float, default=0.0,
                        help="weight on roll rate (3dof)")
    out = parser.add_mutually_exclusive_group()
    out.add_argument("--json", action="store_true", help="print JSON instead of a table")
    out.add_argument("--plot", metavar="PNG", help="draw the gain curves to this PNG")


def run(args: argparse.Namespace) -> int:
    """Compute the sweep and print/plot it; returns the exit code."""
    # scipy, control: not for --help
    from fourws_analysis.lqr_analysis import lqr_sweep, plot_lqr_gains
    from fourws_control.lqr import LqrWeights  # scipy: not for --help

    speeds = [speed_mps("--speeds", u) for u in args.speeds]
    # LQR weights (their signs are checked by LqrWeights and lqr_sweep): only their ratios
    # matter, and beyond MAX_WEIGHT the Riccati equation is ill-conditioned
    for option in ("--q", "--p", "--q-steer", "--q-yaw", "--q-roll", "--q-roll-rate"):
        value = getattr(args, option[2:].replace("-", "_"))
        for v in value if isinstance(value, list) else [value]:
            if abs(v) > MAX_WEIGHT:
                raise ParameterError(option, f"must be at most {MAX_WEIGHT:g}, got {v!r}")
    vehicle = load_vehicle(args.vehicle)
    weights = LqrWeights(1.0, args.q_steer, args.q_yaw, args.q_roll, args.q_roll_rate, args.p)
    sweep = lqr_sweep(args.model, vehicle, speeds, args.q, weights)
    if args.json:
        print(json.dumps(sweep.to_dict(), indent=2))
        return 0
    if args.plot:
        path = plot_lqr_gains(sweep, args.plot)
        print(f"wrote {path}")
        return 0
    print(f"{sweep.vehicle}  model {sweep.model}  LQR gains K of delta_r = -K x "
          f"(p = {weights.p:g})")
    header = f"{'U (m/s)':>8} {'q':>7} " + " ".join(f"{s:>10}" for s in sweep.state_names)
    print(header)
    for i, u in enumerate(sweep.speeds_mps):
        for j, q in enumerate(sweep.q_values):
            print(f"{u:8.2f} {q:7.3g} " + " ".join(f"{k:10.4f}" for k in sweep.gains[i, j]))
    return 0
