# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws analyze BAG... [--report DIR] [--json]``: metrics and report of recorded runs.

Without ``--report`` or ``--json`` it prints, per run, every metric of its maneuver as aligned
``key value`` rows (the key names the unit; values to 6 significant digits, never cut)."""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import sys
import time
from typing import Any, Iterator, Mapping

from fourws_sim.errors import FourwsError, ParameterError, one_line

HELP = "analyse recorded runs (rosbag2 MCAP): frequency response, ISO 7401/4138, stability"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the sub-parser."""
    parser.add_argument("bags", nargs="+", metavar="BAG", help="bag directory or .mcap file")
    parser.add_argument("--report", metavar="DIR",
                        help="write DIR/index.html, PNG plots and DIR/metrics.json")
    parser.add_argument("--json", action="store_true", help="print every metric as JSON")
    parser.add_argument("--dt", type=float, default=None, metavar="S",
                        help="resampling period in s (default: median state period)")
    parser.add_argument("--no-sweep", action="store_true",
                        help="skip the 8-DOF eigenvalues-vs-speed sweep")
    parser.add_argument("--allow-incomplete", action="store_true",
                        help="analyse a bag that is damaged or misses messages (a failed run, "
                             "a killed recorder): its metrics are marked as from an "
                             "incomplete recording")
    parser.add_argument("--timing", action="store_true", help="print the elapsed time")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


class ProgressBar:
    """A one-line progress bar on stderr (only when stderr is a terminal or forced)."""

    def __init__(self, total: int, enabled: bool) -> None:
        self.total = max(total, 1)
        self.done = 0
        self.enabled = enabled

    def __call__(self, message: str) -> None:
        self.done = min(self.done + 1, self.total)
        if not self.enabled:
            return
        width = 24
        filled = int(width * self.done / self.total)
        sys.stderr.write(f"\r[{'#' * filled}{'.' * (width - filled)}] "
                         f"{message[:60]:<60}")
        sys.stderr.flush()

    def close(self) -> None:
        """End the bar's line."""
        if self.enabled:
            sys.stderr.write("\r" + " " * 90 + "\r")
            sys.stderr.flush()


def run(args: argparse.Namespace) -> int:
    """Analyse the bags; exit 0 if all were analysed, 2 if none could be, 1 if some failed."""
    analysis = BagAnalysis(args)
    for path in args.bags:
        analysis.add(path)
    return analysis.finish()


class BagAnalysis:
    """The analysis of ``fourws analyze``, one bag at a time (:meth:`add`), then the report
    and the printed results (:meth:`finish`): ``fourws demo`` analyses each bag while the
    next run goes on."""

    #: Progress-bar steps per bag.
    STEPS_PER_BAG = 7

    def __init__(self, args: argparse.Namespace) -> None:
        if args.dt is not None and not (math.isfinite(args.dt) and args.dt > 0.0):
            raise ParameterError("--dt", f"must be a finite number of seconds > 0, "
                                 f"got {args.dt!r}")
        self.args = args
        self.bar = ProgressBar(len(args.bags) * self.STEPS_PER_BAG + (6 if args.report else 0),
                               enabled=not args.quiet and sys.stderr.isatty())
        self.analyses: list[Any] = []
        self.failures: dict[str, str] = {}
        self.busy_s = 0.0  # the time spent analysing (a demo's runs go on between bags)

    @contextlib.contextmanager
    def _busy(self) -> Iterator[None]:
        """Count the time inside towards :attr:`busy_s`."""
        start = time.perf_counter()
        try:
            yield
        finally:
            self.busy_s += time.perf_counter() - start

    def prepare(self, config: Mapping[str, Any]) -> None:
        """Compute ahead what every bag of a run of ``config`` (its ``/fourws/run_config``)
        shares with the runs of its car and law (:func:`fourws_analysis.compare.prepare`)."""
        from fourws_analysis import compare  # scipy, control: not for --help

        with self._busy():
            compare.prepare(config, eig_sweep=not self.args.no_sweep)

    def add(self, path: str) -> None:
        """Read, resample and analyse one bag (a bag that cannot be read is a failure)."""
        from fourws_analysis import bag as bagmod  # scipy, control: not for --help
        from fourws_analysis.compare import analyze_run  # scipy, control: not for --help

        with self._busy():
            self.bar(f"reading {path}")
            try:
                run_data = bagmod.load_bag(path, bagmod.ANALYSIS_TOPICS,
                                           allow_incomplete=self.args.allow_incomplete)
                uniform = bagmod.resample(run_data, self.args.dt)
            except FourwsError as exc:
                self.failures[path] = one_line(exc)
                return
            base, k = uniform.name, 2
            while uniform.name in {a.name for a in self.analyses}:  # labels key the metrics
                uniform.name, k = f"{base}#{k}", k + 1
            result = analyze_run(uniform, eig_sweep=not self.args.no_sweep, progress=self.bar)
            result.notes.extend(run_data.warnings)
            result.recording = ("complete" if run_data.complete else "unverified"
                                if run_data.complete is None else
                                "INCOMPLETE: " + "; ".join(run_data.problems))
            self.analyses.append(result)

    def finish(self) -> int:
        """Write the report, print the results; the command's exit code."""
        from fourws_analysis.report import write_report  # scipy, control: not for --help

        args, analyses, failures = self.args, self.analyses, self.failures
        index = None
        with self._busy():
            if args.report:
                index = write_report(analyses, args.report, failures, progress=self.bar)
            self.bar.close()
        for path, why in failures.items() if analyses else ():
            # (with no bag analysed the command's one error line below names every reason)
            print(f"fourws analyze: error: {why}", file=sys.stderr)
        for r in analyses:
            for metric, why in r.unavailable.items():
                if _expected(metric, r):
                    continue
                print(f"fourws analyze: {r.name}: {metric} not computed: {why}",
                      file=sys.stderr)
        if args.json:
            print(json.dumps({"runs": {r.name: r.metrics() for r in analyses},
                              "failed_bags": failures}, indent=2))
        elif not args.report:
            for r in analyses:
                _print_summary(r)
        if index is not None:
            print(f"report: {index}")
        if args.timing:
            print(f"analysed {len(analyses)} bag(s) in {self.busy_s:.2f} s", file=sys.stderr)
        if not analyses:
            raise FourwsError("no bag could be analysed: " + "; ".join(failures.values()))
        return 1 if failures else 0


def _expected(metric: str, r: Any) -> bool:
    """Metrics a maneuver is not meant to give are not worth a warning line (those of a run
    past its vehicle limits are: the maneuver was meant to give them)."""
    breach = r.vehicle_breach
    if breach is not None and breach.reason in r.unavailable.get(metric, ""):
        return False
    return metric in ("frequency_response", "iso7401_step", "iso4138_steady_state",
                      "iso3888_lane_change")


def _text(value: Any) -> str:
    """A metric's value as the summary prints it: numbers to 6 significant digits, lists
    whole (eigenvalues as (re, im) pairs), nothing cut."""
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        inner = [f"({', '.join(_text(v) for v in item)})" if isinstance(item, (list, tuple))
                 else _text(item) for item in value]
        return ", ".join(inner) if inner else "none"
    return str(value)


def _rows(value: Any, prefix: str = "") -> list[tuple[str, str]]:
    """(dotted key, text) of every leaf of a metric group; notes become rows of their own,
    empty note lists none."""
    if isinstance(value, dict):
        return [row for key, item in value.items() for row in _rows(item, f"{prefix}{key}.")]
    key = prefix[:-1]
    if key.rsplit(".", 1)[-1] == "notes":
        return [(key, str(note)) for note in value]
    return [(key, _text(value))]


def summary_lines(r: Any) -> list[str]:
    """What ``fourws analyze`` prints per run when neither --json nor --report is given:
    the run, then each metric group of its maneuver as aligned ``key value`` rows, every value
    whole (the key names its unit)."""
    # the analysis package is imported where it is used, as in run(): `fourws --help` stays
    # free of scipy and the bag reader
    from fourws_analysis.standards import STANDARD_KEYS

    metrics = r.metrics()
    speed = metrics["speed_mps"]
    where = f", {speed:.1f} m/s" if speed else ""
    lines = [f"{r.name}: maneuver {metrics['maneuver']}, law {metrics['law']}{where}, "
             f"recording {metrics['recording']}"]
    if "vehicle_limits" in metrics:  # before any number: what the numbers are not
        breach = metrics["vehicle_limits"]
        lines.append(f"  {breach['kind'].upper()} at t = {breach['time_s']:.2f} s: "
                     f"{breach['reason']}; its handling metrics (ISO 7401, ISO 4138, "
                     "ISO 3888-2, frequency response) are not computed")
    for key in ("frequency_response", "iso7401_step", "iso4138_steady_state",
                "iso3888_lane_change", "identified_modes", *STANDARD_KEYS.values()):
        if key in metrics:
            rows = _rows(metrics[key])
            width = max((len(k) for k, _ in rows), default=0)
            lines.append(f"  {key}:")
            lines += [f"    {k:<{width}}  {text}" for k, text in rows]
    return lines


def _print_summary(r: Any) -> None:
    print("\n".join(summary_lines(r)))
