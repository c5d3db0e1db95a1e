# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws export BAG... --format csv|parquet [--topics TOPIC ...] [--out DIR]``: recorded
runs as tables in the measured-log column set (:data:`fourws_analysis.measured.COLUMNS`, SI),
the same kind of file ``fourws identify`` and ``fourws validate`` read, for pandas or MATLAB.

One file per bag, ``DIR/<run name>.<format>``; ``--topics`` adds every numeric field of those
topics (``state.normal_load_n_fl``, ...) on the same time grid.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from fourws_sim.errors import ParameterError

HELP = "write recorded runs as CSV or Parquet tables in the measured-log column set"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the sub-parser."""
    parser.add_argument("bags", nargs="+", metavar="BAG", help="bag directory or .mcap file")
    parser.add_argument("--format", required=True, metavar="FORMAT",
                        help="csv or parquet")
    parser.add_argument("--topics", nargs="+", default=(), metavar="TOPIC",
                        help="also every numeric field of these topics (e.g. /fourws/state)")
    parser.add_argument("--out", default=".", metavar="DIR",
                        help="folder of the tables (default: the current one)")
    parser.add_argument("--dt", type=float, default=None, metavar="S",
                        help="time step of the table in s (default: the state period)")
    parser.add_argument("--allow-incomplete", action="store_true",
                        help="export what a damaged or incomplete bag holds")


def run(args: argparse.Namespace) -> int:
    """Export every bag; exit code 0."""
    # the bag reader and numpy: not for `fourws --help`
    from fourws_analysis.bag import load_bag
    from fourws_analysis.measured import FORMATS, log_from_run, topic_columns, write_table

    if args.format not in FORMATS:
        raise ParameterError("--format", f"unknown format {args.format!r} (valid: "
                             f"{', '.join(FORMATS)})")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {}
    for path in args.bags:
        run_data = load_bag(path, allow_incomplete=args.allow_incomplete)
        log = log_from_run(run_data, args.dt)
        extra = topic_columns(run_data, args.topics, log.time_s)
        name, k = log.name, 2
        while name in written:  # two bags of one run name
            name, k = f"{log.name}#{k}", k + 1
        written[name] = write_table(log, out / f"{name}.{args.format}", args.format, extra)
        print(f"{path}: {written[name]}")
    return 0
