# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws study STUDY [--out DIR] [--workers N] [--backend local|dask] [--scheduler ADDR]
[--resume] [--force] [--json]``: sweeps and Monte Carlo over speed, laws and parameter error.

Also ``fourws study rerun DIR --point ID [--out D]``: one point of a finished study through
the real node graph into a bag, its metrics beside the study's row; and ``fourws study
report DIR``: draw the report again from the results.

A study (``config/studies/*.yaml``, :mod:`fourws_study.spec`) runs every point with the
offline twin of the lockstep graph on all cores (or on a Dask cluster), writes
``DIR/results.parquet`` (a row per point), the study file, the resolved base run and the
versions beside it, and ``DIR/report/index.html``. Blocks of points are written as they
finish; after Ctrl-C or a kill, ``--resume`` runs only what is missing.

Exit code: 0 every point ran (whatever its status: a spun car is a result); 1 a worker
process died (killed, out of memory; one line naming it; the finished blocks are kept); 2 a
bad study file or option (one line naming the field and the file); 130 interrupted (the
finished blocks are kept); for ``rerun`` the exit code of ``fourws run``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from fourws_sim.errors import FourwsError, ParameterError

HELP = "sweeps and Monte Carlo over speed, laws and parameter error (all cores or Dask)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``fourws study``."""
    parser.add_argument("target", nargs="+", metavar="STUDY | rerun DIR | report DIR",
                        help="a study name (config/studies) or YAML path; or 'rerun DIR' "
                             "with --point; or 'report DIR'")
    parser.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help="output folder (default studies/<name>; rerun: DIR/reruns)")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="worker processes (default: every core of this machine)")
    parser.add_argument("--backend", choices=("local", "dask"), default="local",
                        help="local processes (default) or Dask distributed")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="a running Dask scheduler, e.g. tcp://host:8786 (with --backend "
                             "dask; default: a LocalCluster of --workers processes)")
    parser.add_argument("--resume", action="store_true",
                        help="continue the study in --out: run only the missing blocks")
    parser.add_argument("--force", action="store_true",
                        help="run a study of more than 10^6 points")
    parser.add_argument("--no-report", action="store_true", help="skip the HTML report")
    parser.add_argument("--interpreted", action="store_true",
                        help="run every point with the interpreted twin (same rows, slower)")
    parser.add_argument("--point", type=int, default=None, metavar="ID",
                        help="rerun: the point to run through the node graph")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")


def run(args: argparse.Namespace) -> int:
    """Run the study (or rerun a point, or draw a report); returns the exit code."""
    action = args.target[0]
    if action in ("rerun", "report"):
        if len(args.target) != 2:
            raise ParameterError(action, f"usage: fourws study {action} DIR"
                                 + (" --point ID" if action == "rerun" else ""))
        return _rerun(args, Path(args.target[1])) if action == "rerun" \
            else _report(Path(args.target[1]))
    if len(args.target) != 1:
        raise ParameterError("STUDY", "give one study file (or 'rerun DIR', 'report DIR')")
    if args.point is not None:
        raise ParameterError("--point", "only with 'fourws study rerun DIR'")
    return _study(args, args.target[0])


def _study(args: argparse.Namespace, target: str) -> int:
    from fourws_study.execute import check_size, run_study  # numba, pyarrow: not for --help
    # numba, pyarrow: not for --help
    from fourws_study.report import check_report, write_study_report
    from fourws_study.spec import load_study  # numba, pyarrow: not for --help

    study = load_study(target)
    check_report(study)
    check_size(study, args.force)
    out = args.out if args.out is not None else Path("studies") / study.name
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)

    def announce(missing: int) -> None:
        print(f"fourws study {study.name}: {missing} of {study.n_points} points to run in "
              f"blocks of {study.block_size}, {workers} {args.backend} worker(s)"
              + (f" at {args.scheduler}" if args.scheduler else "") + f", into {out}",
              file=sys.stderr, flush=True)

    result = run_study(study, out, workers=workers, backend=args.backend,
                       scheduler=args.scheduler, resume=args.resume, force=args.force,
                       compiled=not args.interpreted, on_start=announce)
    report = None
    if result.done and not args.no_report:
        report = write_study_report(out, study)
    if args.json:
        print(json.dumps({
            "study": study.name, "out": str(out), "points": result.points,
            "done": result.done, "ran": result.ran, "statuses": dict(result.statuses),
            "seconds": result.seconds, "vehicle_steps": result.vehicle_steps,
            "workers": workers, "backend": args.backend, "interrupted": result.interrupted,
            "failed": result.failed or None,
            "results": str(result.results) if result.results else None,
            "report": str(report) if report else None}, indent=2))
    else:
        print(result.summary_line(study.name) + (f"; report {report}" if report else ""))
    if result.interrupted:
        print(f"fourws study: interrupted; the finished blocks are kept: fourws study "
              f"{target} --out {out} --resume", file=sys.stderr)
        return 130
    if result.failed:
        print(f"fourws study: {result.failed}; the finished blocks are kept: fourws study "
              f"{target} --out {out} --resume", file=sys.stderr)
        return 1
    return 0


def _report(root: Path) -> int:
    from fourws_study.report import write_study_report  # numba, pyarrow: not for --help
    from fourws_study.rerun import study_of  # numba, pyarrow: not for --help

    print(f"report: {write_study_report(root, study_of(root))}")
    return 0


def _rerun(args: argparse.Namespace, root: Path) -> int:
    from fourws_ros.domains import domain_for_run  # fourws_ros: not for --help
    from fourws_ros.graph_run import run_graph  # rclpy: not for --help
    from fourws_run.record import Outcome  # rosbags, mcap: not for --help
    from fourws_study.kernel import DURATION  # numba, pyarrow: not for --help
    # numba, pyarrow: not for --help
    from fourws_study.rerun import bag_row, compare_rows, study_of, study_row

    if args.point is None:
        raise ParameterError("--point", "rerun needs the point to run (--point ID)")
    study = study_of(root)
    config = study.config(study.point(args.point))
    try:
        row = study_row(root, study, args.point)
    except FourwsError:
        row = None
    out = args.out if args.out is not None else root / "reruns"
    domain_for_run().release()  # a bad ROS_DOMAIN_ID is exit 2 before the run folder
    record = run_graph(config, out, run_name=f"point-{args.point}", overwrite=True)
    print("\n".join(record.summary_lines()), flush=True)
    if record.bag_path is None or record.outcome not in (Outcome.COMPLETED, Outcome.ABORTED,
                                                         Outcome.DIVERGED):
        return record.exit_code
    end = record.reason if record.outcome == Outcome.DIVERGED else DURATION
    graph = bag_row(study, args.point, config, record.bag_path, end)
    result = {"point": args.point, "bag": str(record.bag_path), "graph_row": graph,
              "study_row": row}
    if row is not None:
        diffs = compare_rows(row, graph)
        worst = max(diffs, key=lambda d: d[3]) if diffs else None
        result["largest_relative_difference"] = None if worst is None else {
            "column": worst[0], "study": worst[1], "graph": worst[2], "relative": worst[3]}
        shown = [d for d in diffs if d[0] in ("status", "max_abs_sideslip_rad",
                                              "max_abs_yaw_rate_radps")
                 or d[0].startswith(("iso7401.yaw_rate", "iso3888.", "iso4138.under"))]
        width = max((len(d[0]) for d in shown), default=6)
        print(f"{'metric':<{width}} {'study':>14} {'graph':>14}")
        for col, a, b, _ in shown:
            print(f"{col:<{width}} {_short(a):>14} {_short(b):>14}")
        if worst is not None and worst[3] > 0.0:
            print(f"largest relative difference: {worst[3]:.3g} ({worst[0]})")
        elif worst is not None:
            print(f"every one of the {len(diffs)} compared columns is identical")
    (record.run_dir / "rerun.json").write_text(json.dumps(result, indent=2, default=str))
    print(f"bag: {record.bag_path}  (fourws analyze {record.bag_path})")
    return record.exit_code


def _short(value: object) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)
