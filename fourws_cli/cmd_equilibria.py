# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws equilibria``: equilibria and stability region of the cubic-tire 2-DOF model (ch. 7).

Output (``--json``)::

    {"vehicle": NAME, "speed_mps": U,
     "equilibria": [{"v_mps": V, "r_radps": r, "eigenvalues": [[re, im], ...],
                     "stable": bool, "kind": str}, ...]}

``--region PNG`` also computes the Lyapunov/tangency estimate and the trajectory-reversal
boundary, draws them to PNG and adds ``"region": {"png", "lyapunov_level",
"tangency_points", "lyapunov_multiplier", "reversal_closed"}`` to the JSON.
"""

from __future__ import annotations

import argparse
import json
import math

from fourws_cli._bounds import speed_mps
from fourws_sim.models import check_speed
from fourws_sim.params import load_vehicle

HELP = "equilibria and stability region of the nonlinear cubic-tire 2-DOF model (ch. 7)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``equilibria`` sub-parser."""
    parser.add_argument("--vehicle", required=True,
                        help="vehicle name (file stem under config/vehicles) or YAML path, "
                             "e.g. table_7_1_set_1")
    parser.add_argument("--speed-mps", required=True, type=float,
                        help="constant forward speed U in m/s (> 0)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--region", metavar="PNG",
                        help="also estimate the stability region and draw it to this PNG")


def _format_eig(eig: list[list[float]]) -> str:
    parts = []
    for re, im in eig:
        parts.append(f"{re:.4g}" if im == 0.0 else f"{re:.4g}{im:+.4g}j")
    return ", ".join(parts)


def run(args: argparse.Namespace) -> int:
    """Compute and print the equilibria (and the region); returns the exit code."""
    from fourws_analysis import nonlinear2dof  # scipy, control: not for --help

    speed = speed_mps("--speed-mps", check_speed(args.speed_mps, "--speed-mps"))
    vehicle = load_vehicle(args.vehicle)
    eqs = nonlinear2dof.equilibria(vehicle, speed)
    out: dict = {"vehicle": vehicle.name, "speed_mps": speed,
                 "equilibria": [e.to_dict() for e in eqs]}
    if args.region:
        region = nonlinear2dof.stability_region(vehicle, speed)
        png = nonlinear2dof.plot_stability_region(region, args.region)
        lyap = region.lyapunov
        out["region"] = {
            "png": str(png),
            "lyapunov_level": lyap.level,
            "tangency_points": [[float(x[0]), float(x[1])] for x in lyap.tangency_points],
            "lyapunov_multiplier": lyap.multiplier,
            "reversal_closed": region.reversal.polygon is not None,
        }
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print(f"{vehicle.name}: cubic-tire 2-DOF equilibria at U = {speed:g} m/s (zero steer)")
    print(f"{'V (m/s)':>10} {'r (rad/s)':>10}  {'kind':<14} eigenvalues (1/s)")
    for e in out["equilibria"]:
        v = 0.0 if math.isclose(e["v_mps"], 0.0, abs_tol=1e-12) else e["v_mps"]
        r = 0.0 if math.isclose(e["r_radps"], 0.0, abs_tol=1e-12) else e["r_radps"]
        print(f"{v:>10.4f} {r:>10.4f}  {e['kind']:<14} {_format_eig(e['eigenvalues'])}")
    if "region" in out:
        reg = out["region"]
        tp = ", ".join(f"({x:.4g}, {y:.4g})" for x, y in reg["tangency_points"])
        print(f"Lyapunov estimate V1 = x'Px < C = {reg['lyapunov_level']:.4g}, "
              f"tangency points {tp}, multiplier {reg['lyapunov_multiplier']:.4g}")
        print(f"trajectory-reversal boundary "
              f"{'closed' if reg['reversal_closed'] else 'not closed'}; plot: {reg['png']}")
    return 0
