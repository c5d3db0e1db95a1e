# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws identify DATA... --vehicle BASE [--fit FIELD ...] [--level L] [--out V.yaml]
[--report DIR] [--json]``: fit vehicle parameters to test data (fourws bags or measured logs in
the column set of :mod:`fourws_analysis.measured`) by output error
(:mod:`fourws_analysis.fit`).

Prints each fitted value with its 95 % interval, the pairs that cannot be told apart and the
residual of each channel; ``--out`` writes the fitted vehicle file (every fitted value
commented with its interval and data), ``--report`` the HTML report and
``identification.json``. Bad data (missing channels, time that does not increase, a record too
short, units that cannot be right, too little excitation for the fields asked for) is one line
naming it, exit code 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from fourws_sim.errors import ParameterError
from fourws_sim.params import load_vehicle

HELP = "fit vehicle parameters to test data (bags or CSV/Parquet logs) with confidence intervals"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the sub-parser."""
    parser.add_argument("data", nargs="+", metavar="DATA",
                        help="fourws bag (folder or .mcap) or measured log (.csv, .parquet) "
                             "in the documented column set; several are fitted together")
    parser.add_argument("--vehicle", required=True,
                        help="base vehicle: name (config/vehicles) or YAML path")
    parser.add_argument("--fit", nargs="+", metavar="FIELD", default=None,
                        help="vehicle fields to fit (subsystem.field; a,b: linked, one "
                             "factor); default: the level's usual set that the data can pin")
    parser.add_argument("--level", default="auto",
                        help="model level: auto (default), 2dof, 2dof-lagged, 3dof, 8dof")
    parser.add_argument("--tire", default=None,
                        help="tire model of the 8dof level (e.g. linear: the axle cornering "
                             "stiffnesses are then the 8-DOF's)")
    parser.add_argument("--out", metavar="VEHICLE.yaml", help="write the fitted vehicle file")
    parser.add_argument("--name", default=None,
                        help="name of the fitted vehicle (default <base>_fitted)")
    parser.add_argument("--no-bias", action="store_true",
                        help="take the sensors as zeroed: no offset per channel is fitted "
                             "(a steady-state record needs it)")
    parser.add_argument("--report", metavar="DIR",
                        help="write DIR/index.html, PNG plots and DIR/identification.json")
    parser.add_argument("--dt", type=float, default=None, metavar="S",
                        help="resampling period of the logs in s (default: their own)")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")


def run(args: argparse.Namespace) -> int:
    """Identify, print, write what was asked; exit code 0."""
    # scipy and the bag reader: not for `fourws --help`
    from fourws_analysis.fit import identify, vehicle_yaml
    from fourws_analysis.measured import load_log
    from fourws_analysis.report_identify import write_identify_report

    base = load_vehicle(args.vehicle)
    logs = [load_log(p, args.dt) for p in args.data]
    out = Path(args.out) if args.out else None
    if out is not None and out.suffix not in (".yaml", ".yml"):
        raise ParameterError("--out", f"{str(out)!r}: a vehicle file ends in .yaml")

    def progress(message: str) -> None:
        if not args.quiet and not args.json:
            print(f"fourws identify: {message}", file=sys.stderr)

    result = identify(logs, base, level=args.level, fields=args.fit, tire=args.tire,
                      name=args.name, bias=not args.no_bias, progress=progress)
    if out is not None:
        out.write_text(vehicle_yaml(result), encoding="utf-8")
    index = write_identify_report(result, args.report, out) if args.report else None
    if args.json:
        print(json.dumps(result.to_dict(), indent=2))
    else:
        _print(result)
    if out is not None and not args.json:
        print(f"vehicle: {out}")
    if index is not None and not args.json:
        print(f"report: {index}")
    return 0


def _print(result: Any) -> None:
    """The summary lines of a :class:`fourws_analysis.fit.FitResult`."""
    print(f"{result.vehicle.name}: {result.level} level ({result.level_reason}), "
          f"{len(result.logs)} log(s), {result.evaluations} model runs in "
          f"{result.elapsed_s:.2f} s")
    width = max(len(v.path) for v in result.values)
    for v in result.values:
        change = f" ({100 * (v.value / v.base - 1):+.1f} % from {v.base:.6g})" if v.base else ""
        print(f"  {v.path:<{width}}  {v.value:.6g} +- {v.ci95:.3g} {v.unit} (95 %){change}")
    for a, b, r in result.indistinguishable:
        print(f"  cannot be told apart: {a} and {b} (correlation {r:+.3f})")
    for c in result.channels:
        print(f"  residual {c.log}: {c.channel} {c.rms_residual:.4g} {c.unit} RMS "
              f"(signal {c.rms_signal:.4g}, bias {c.bias:+.3g})")
    for f in result.frequency:
        print(f"  frequency response {f.log}: {f.output} over {f.band_hz[0]:.3g}-"
              f"{f.band_hz[1]:.3g} Hz: gain {f.gain_error_db:.2f} dB RMS, phase "
              f"{f.phase_error_deg:.1f} deg RMS")
    for n in result.notes:
        print(f"  note: {n}")
