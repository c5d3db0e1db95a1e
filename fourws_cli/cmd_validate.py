# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws validate SIM REFERENCE [--standard auto|iso19364|iso19365|band] [--report DIR]
[--json]``: a simulated run against a reference (a measured log or another bag) in tolerance
bands (:mod:`fourws_analysis.validate`).

Prints each curve's share inside its band and its verdict; exit code 0 when every curve (and,
for a sine with dwell, every FMVSS 126 metric) passes, 1 when one fails, 2 on bad input.
"""

from __future__ import annotations

import argparse
import json

HELP = "validate a simulated run against a reference in ISO 19364-style tolerance bands"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the sub-parser."""
    parser.add_argument("simulation", metavar="SIM",
                        help="the simulated run: fourws bag (folder or .mcap) or log")
    parser.add_argument("reference", metavar="REFERENCE",
                        help="the reference: measured log (.csv, .parquet) or a bag")
    parser.add_argument("--standard", default="auto",
                        help="iso19364 (steady-state circular driving cross-plots), iso19365 "
                             "(sine with dwell), band (time histories); default auto: by "
                             "the runs' maneuver")
    parser.add_argument("--min-share", type=float, default=None, metavar="F",
                        help="share of each curve that must lie in its band, 0-1 (default "
                             "1: the whole curve)")
    parser.add_argument("--band", action="append", default=[], metavar="CURVE=AX,BX,AY,BY",
                        help="a band other than the default: eps_x = AX + BX|x|, eps_y = AY + "
                             "BY|y| in the curve's units (curves: steering_wheel_angle, "
                             "sideslip, roll, yaw_rate_gain, or a channel for time histories)")
    parser.add_argument("--report", metavar="DIR",
                        help="write DIR/index.html, DIR/curves.png and DIR/validation.json")
    parser.add_argument("--dt", type=float, default=None, metavar="S",
                        help="resampling period of the logs in s (default: their own)")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def run(args: argparse.Namespace) -> int:
    """Validate; exit code 0 passed, 1 failed."""
    # scipy and the bag reader: not for `fourws --help`
    from fourws_analysis.measured import load_log
    from fourws_analysis.report_validate import write_validate_report
    from fourws_analysis.validate import DEFAULT_REQUIRED_SHARE, parse_band, validate

    bands = dict(parse_band(text) for text in args.band)
    sim = load_log(args.simulation, args.dt)
    ref = load_log(args.reference, args.dt)
    share = DEFAULT_REQUIRED_SHARE if args.min_share is None else args.min_share
    result = validate(sim, ref, args.standard, share, bands)
    index = write_validate_report(result, args.report) if args.report else None
    if args.json:
        print(json.dumps(result.to_dict(), indent=2))
    else:
        print(f"{sim.name} against {ref.name}: {result.standard}, "
              f"{'PASSED' if result.passed else 'FAILED'}")
        for c in result.curves:
            print(f"  {c.label}: {100 * c.share_inside:.1f} % inside the band (required "
                  f"{100 * c.required_share:g} %): {'pass' if c.passed else 'FAIL'}")
        for m in result.metrics:
            print(f"  {m.key}: simulation {m.simulation:.4g}, reference {m.reference:.4g} "
                  f"{m.unit} (tolerance {m.tolerance:.3g}): {'pass' if m.passed else 'FAIL'}")
        for key, why in result.skipped.items():
            print(f"  {key}: not compared ({why})")
        for note in result.notes:
            print(f"  note: {note}")
        if index is not None:
            print(f"report: {index}")
    return 0 if result.passed else 1
