# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The self-contained HTML report of analysed runs: :func:`write_report` writes
``DIR/index.html``, the PNG plots next to it (:mod:`fourws_analysis.report_figures`) and
``DIR/metrics.json`` with every metric.

What an engineer must know to read the numbers is said once, at the top of the report
(:mod:`fourws_analysis.report_texts`): which front road-wheel angle δf the gains are per (the
driver's command or the applied angle with roll steer), that every gain is also given per
steering-wheel angle δH = N δf, and whether the laws are compared at equal steer or at equal
lateral acceleration. Every table has a unit column; gain units come from
:mod:`fourws_analysis.units`.
"""

from __future__ import annotations

import html
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from fourws_analysis import units
from fourws_analysis.compare import RunAnalysis
from fourws_analysis.figure_jobs import Job, draw_all
from fourws_analysis.report_figures import (EIG_PLOT_MIN_REAL, plot_bode, plot_eigenvalues,
                                            plot_steady_state, plot_step, plot_time_histories)
from fourws_analysis.report_standards import (law_verdicts, plot_free_steer,
                                              plot_sine_with_dwell, standards_tables,
                                              verdict_items)
from fourws_analysis.report_texts import (MODEL_NAMES, car_notes, identification_notes,
                                          law_groups, limit_notes, reading_notes, run_label,
                                          run_step_title, spike_notes, stability_notes)

Progress = Callable[[str], None]
#: The order figures start drawing in (lower first; the rest after): the longest first.
_DRAW_ORDER = {plot_eigenvalues: 0, plot_time_histories: 1}


def _fmt(value: Any, digits: int = 4) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "–"
        return f"{value:.{digits}g}"
    return html.escape(str(value))


@dataclass
class TableRow:
    """One metric of a report table: label, unit (never empty: "–" for none) and one value
    per run (None where the run has none)."""

    label: str
    unit: str
    values: list[Any]


def _collect(runs: Sequence[RunAnalysis],
             specs: Sequence[tuple[str, str, Callable[[RunAnalysis], Any]]]) -> list[TableRow]:
    rows = []
    for label, unit, getter in specs:
        values = []
        for r in runs:
            try:
                values.append(getter(r))
            except (AttributeError, KeyError, TypeError, IndexError):
                values.append(None)
        if any(v is not None for v in values):
            rows.append(TableRow(label, unit or "–", values))
    return rows


def _eig_list(eig: np.ndarray) -> str:
    return ", ".join(f"{e.real:.3f}{e.imag:+.3f}j" for e in eig
                     if abs(e) > 1e-6 and e.real > -EIG_PLOT_MIN_REAL)


def metric_tables(runs: Sequence[RunAnalysis]) -> list[tuple[str, list[TableRow]]]:
    """The report's tables as (title, rows); every row has a unit, every gain is given per
    δf and per δH with its unit from :mod:`fourws_analysis.units`."""
    tables: list[tuple[str, list[TableRow]]] = []
    road, hand = units.ROAD_WHEEL, units.STEERING_WHEEL

    def amplitude_how(r: RunAnalysis) -> str | None:
        amp = r.step_amplitude
        if not amp:
            return None
        if "target_lateral_accel_mps2" in amp:
            return (f"found for steady |a_y| = {amp['target_lateral_accel_mps2']:g} m/s² "
                    f"({amp.get('found_for_law') or 'unresolved'})")
        return "given (equal steer)"

    tables.append(("Runs", _collect(runs, [
        ("maneuver", "–", lambda r: r.run.maneuver or None),
        ("law", "–", lambda r: r.law),
        ("model", "–", lambda r: r.run.config.get("model")),
        ("speed", "m/s", lambda r: r.speed_mps),
        ("gains per δf", "–", lambda r: r.steer_reference),
        ("steering ratio N (δH = N δf)", "rad/rad", lambda r: r.steering_ratio),
        ("step δf", "deg", lambda r: math.degrees(r.step.steer_step)),
        ("step amplitude", "–", amplitude_how),
        ("step steady a_y", "m/s²",
         lambda r: r.step.responses["lateral_accel_mps2"].steady_state),
        ("applied / commanded δf at steady state", "–", lambda r: r.applied_to_commanded),
    ])))

    specs: list[tuple[str, str, Callable[[RunAnalysis], Any]]] = []
    for out in (units.OUTPUTS["yaw_rate_radps"], units.OUTPUTS["lateral_accel_mps2"]):
        c = out.channel
        scale = math.degrees(1.0) if c == "yaw_rate_radps" else 1.0
        specs += [
            (f"{out.label} {out.symbol}: steady state",
             "deg/s" if c == "yaw_rate_radps" else out.unit,
             lambda r, c=c, s=scale: s * r.step.responses[c].steady_state),
            (f"{out.label} {out.symbol}: steady-state gain per {road.symbol}", out.gain_unit,
             lambda r, c=c: r.step.responses[c].steady_state_gain),
            (f"{out.label} {out.symbol}: steady-state gain per {hand.symbol}", out.gain_unit,
             lambda r, c=c: r.step.responses[c].steady_state_gain_steering_wheel),
            (f"{out.label} {out.symbol}: response time (90 %)", "s",
             lambda r, c=c: r.step.responses[c].response_time_s),
            (f"{out.label} {out.symbol}: peak response time", "s",
             lambda r, c=c: r.step.responses[c].peak_response_time_s),
            (f"{out.label} {out.symbol}: overshoot", "%",
             lambda r, c=c: None if r.step.responses[c].overshoot is None
             else 100.0 * r.step.responses[c].overshoot),
            (f"{out.label} {out.symbol}: overshoot is one spike (see the first lines)", "–",
             lambda r, c=c: "yes" if r.step.responses[c].spike else None),
        ]
    specs.append(("TB factor (peak time × steady sideslip)", "s·deg",
                  lambda r: r.step.tb_factor_s_deg))
    tables.append((run_step_title(runs), _collect(runs, specs)))

    specs = []
    for out in units.OUTPUTS.values():
        k_road, k_hand = f"{out.channel}/{road.channel}", f"{out.channel}/{hand.channel}"
        specs += [
            (f"{out.label} {out.symbol}: steady-state gain per {road.symbol}", out.gain_unit,
             lambda r, k=k_road: r.frequency_metrics[k].steady_state_gain),
            (f"{out.label} {out.symbol}: steady-state gain per {hand.symbol}", out.gain_unit,
             lambda r, k=k_hand: r.frequency_metrics[k].steady_state_gain),
            (f"{out.label} {out.symbol}: resonance peak / steady state", "–",
             lambda r, k=k_road: r.frequency_metrics[k].resonance_ratio),
            (f"{out.label} {out.symbol}: resonance frequency", "Hz",
             lambda r, k=k_road: r.frequency_metrics[k].resonance_freq_hz),
            (f"{out.label} {out.symbol}: phase lag at 1 Hz", "deg",
             lambda r, k=k_road: r.frequency_metrics[k].phase_lag_1hz_deg),
            (f"{out.label} {out.symbol}: −3 dB bandwidth", "Hz",
             lambda r, k=k_road: r.frequency_metrics[k].bandwidth_hz),
        ]
    tables.append(("Frequency response", _collect(runs, specs)))

    tables.append(("ISO 4138 steady-state handling", _collect(runs, [
        ("understeer gradient K_us (per δf)", "deg/(m/s²)",
         lambda r: math.degrees(r.steady.understeer_gradient_rad_per_mps2)),
        (f"steer gradient d{road.symbol}/da_y", "deg/(m/s²)",
         lambda r: math.degrees(r.steady.steer_gradient_rad_per_mps2)),
        (f"steering-wheel angle gradient d{hand.symbol}/da_y", "deg/(m/s²)",
         lambda r: math.degrees(r.steady.steering_wheel_gradient_rad_per_mps2)),
        ("sideslip gradient dβ/da_y", "deg/(m/s²)",
         lambda r: math.degrees(r.steady.sideslip_gradient_rad_per_mps2)),
        ("roll gradient dφ/da_y", "deg/(m/s²)",
         lambda r: math.degrees(r.steady.roll_gradient_rad_per_mps2)),
        ("characteristic speed", "m/s", lambda r: r.steady.characteristic_speed_mps),
        ("critical speed", "m/s", lambda r: r.steady.critical_speed_mps),
    ])))

    specs = [("identified from the run", "1/s",
              lambda r: _eig_list(r.modes.eigenvalues) or None)]
    for name in ("2dof", "3dof", "8dof-lin"):
        specs.append((f"{MODEL_NAMES[name]} at the run speed", "1/s",
                      lambda r, n=name: _eig_list(r.models[n].poles()) or None))
    # the same models as the controller closes them: command held over its period
    specs.append(("law's control period T", "s",
                  lambda r: next((v.period_s for v in r.sampled.values()), None)))
    for name in ("2dof", "3dof", "8dof-lin"):
        specs.append((f"{MODEL_NAMES[name]} sampled at T: ln(z)/T", "1/s",
                      lambda r, n=name: _eig_list(r.sampled[n].s_plane) or None))
        specs.append((f"{MODEL_NAMES[name]} sampled at T: largest |z| (modes with s ≠ 0)",
                      "1", lambda r, n=name: r.sampled[n].radius(1e-6)))
    tables.append(("Eigenvalues (slower than −40 1/s)", _collect(runs, specs)))
    return [(title, rows) for title, rows in tables if rows]


def _table_html(title: str, rows: Sequence[TableRow], runs: Sequence[RunAnalysis]) -> str:
    head = "".join(f"<th>{html.escape(run_label(r))}</th>" for r in runs)
    body = "".join(f"<tr><td>{html.escape(row.label)}</td><td>{html.escape(row.unit)}</td>"
                   + "".join(f"<td>{_fmt(v)}</td>" for v in row.values) + "</tr>"
                   for row in rows)
    return (f"<h3>{html.escape(title)}</h3><table><tr><th>metric</th><th>unit</th>{head}"
            f"</tr>{body}</table>")


_CSS = """body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1200px;color:#222}
h1{font-size:1.5em}h2{font-size:1.15em;margin-top:1.8em;border-bottom:1px solid #ccc}
h3{font-size:1em;margin:1.2em 0 .3em}
table{border-collapse:collapse;font-size:.85em}td,th{border:1px solid #ddd;padding:3px 8px;
text-align:right}td:first-child,th:first-child{text-align:left}
td:nth-child(2),th:nth-child(2){text-align:left;color:#555}
tr:nth-child(even){background:#f7f7f7}
.reading{background:#f3f6fb;border-left:4px solid #4a72b0;padding:.4em 1em;margin:1em 0}
img{max-width:100%;border:1px solid #eee;margin:.5em 0}.note{color:#775;font-size:.85em}"""
#: The reports' style sheet (the study report shares it).
REPORT_CSS = _CSS


def _list_html(items: Sequence[str], cls: str = "") -> str:
    attr = f" class='{cls}'" if cls else ""
    return f"<ul{attr}>" + "".join(f"<li>{html.escape(i)}</li>" for i in items) + "</ul>"


def write_report(runs: Sequence[RunAnalysis], out_dir: str | Path,
                 failures: dict[str, str] | None = None,
                 progress: Progress | None = None, plots: bool = True) -> Path:
    """Write ``index.html``, the PNG plots and ``metrics.json`` into ``out_dir``.

    Parameters
    ----------
    runs : sequence of RunAnalysis
    out_dir : str or Path
        Folder (created if needed).
    failures : dict of str to str, optional
        Bags that could not be read -> why (listed in the report and the JSON).
    progress : callable, optional
        Called with a short description before each plot.
    plots : bool
        Draw the PNG plots (False: texts, tables and metrics only, in a fraction of the
        time).

    Returns
    -------
    Path
        The ``index.html``.
    """
    tick = progress or (lambda _msg: None)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sections: list[tuple[str, Any, str, list[str]]] = []  # (title, job index, caption, items)
    figures = (("Frequency response", plot_bode, "bode.png",
                "Measured H1 estimate (solid) over the analytic 2-DOF/3-DOF models closed "
                "with the run's law and the 8-DOF linearized at the run's straight-running "
                "trim; one colour per run, one line style per source. Phase lines are not "
                "joined across a jump of more than 90 deg (a wrap or a zero on the jω axis)."),
               (run_step_title(runs), plot_step, "step.png", ""),
               ("ISO 4138 steady-state handling", plot_steady_state, "steady_state.png", ""))

    jobs: list[Job] = []

    def draw(fn: Callable[[Sequence[RunAnalysis], Path], Path | None],
             members: Sequence[RunAnalysis], fname: str) -> int | None:
        """A figure to draw (below, side by side): its job's index (None without plots)."""
        if not plots:
            tick(f"plot {fname}")
            return None
        jobs.append((fn, members, out / fname))
        return len(jobs) - 1

    if runs:
        # time histories: one figure per maneuver, so a 60 s sweep does not flatten a 5 s step
        groups: dict[str, list[RunAnalysis]] = {}
        for r in runs:
            groups.setdefault(r.run.maneuver or "unrecognized", []).append(r)
        for man, members in groups.items():
            sections.append((f"Time histories: {man}",
                             draw(plot_time_histories, members, f"time_histories_{man}.png"),
                             "Overlaid runs; time from the start of each record. The front "
                             "road-wheel angle is drawn as applied (solid, roll steer "
                             "included) and as the driver commands it (dashed).", []))
        for title, fn, fname, caption in figures:
            sections.append((title, draw(fn, runs, fname), caption, []))
        eig_items = [f"Law {law}: " + " ".join(stability_notes(members))
                     for law, members in law_groups(runs).items()]
        eig_items += identification_notes(runs)
        sections.append(("Stability: eigenvalues",
                         draw(plot_eigenvalues, runs, "eigenvalues.png"),
                         "One panel per law. Modes faster than -40 1/s (wheel spin, tire lag, "
                         "actuator) are left out; a mode right of the imaginary axis "
                         "(shaded) is unstable.", eig_items))
        # the regulation and standard tests (fourws_analysis.report_standards)
        sections.append(("FMVSS No. 126 sine with dwell",
                         draw(plot_sine_with_dwell, runs, "sine_with_dwell.png"),
                         "Left: yaw rate over the second peak yaw rate, from the completion of "
                         "steer; the markers are the limits 0.35 at 1.00 s and 0.20 at 1.75 s. "
                         "Right: lateral displacement (the lateral acceleration integrated "
                         "twice from the beginning of steer); the marker is 1.83 m at 1.07 s "
                         "(runs of 5 A and more).", verdict_items(runs)))
        sections.append(("ISO 17288 free steer", draw(plot_free_steer, runs, "free_steer.png"),
                         "Yaw rate and steering-wheel angle from the release of the steering "
                         "wheel (steering release) or the end of the torque pulse.", []))
    # the longest first (the eigenvalue panels, then the time histories): side by side, the
    # figures take about as long as the longest
    first = sorted(range(len(jobs)), key=lambda k: _DRAW_ORDER.get(jobs[k][0], 2))
    drawn = draw_all(jobs, started=lambda k: tick(f"plot {jobs[k][2].name}"), order=first)
    sections = [(title, None if job is None else drawn[job], caption, items)
                for title, job, caption, items in sections]
    metrics = {"runs": {r.name: r.metrics() for r in runs}, "failed_bags": dict(failures or {})}
    if law_verdicts(runs):
        metrics["fmvss126_law_verdicts"] = [v.to_dict() for v in law_verdicts(runs)]
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>fourws analysis</title>"
             f"<style>{_CSS}</style></head><body><h1>fourws: analysis of "
             f"{len(runs)} recorded run(s)</h1>"]
    first = limit_notes(runs) + car_notes(runs) + spike_notes(runs)
    if first:  # what the car is and what a number is not, before any number
        parts.append("<h2>The car and the runs</h2>" + _list_html(first, "reading"))
    if runs:
        parts.append("<h2>How to read the numbers</h2>"
                     + _list_html(reading_notes(runs), "reading"))
    if failures:
        parts.append("<h2>Bags that could not be analysed</h2><ul>" + "".join(
            f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in failures.items())
            + "</ul>")
    if runs:
        parts.append("<h2>Metrics</h2>" + "".join(
            _table_html(title, rows, runs) for title, rows in metric_tables(runs)) + "".join(
            _table_html(title, _collect(members, specs), members)
            for title, specs, members in standards_tables(runs)))
    for title, png, caption, items in sections:
        if png is None and not items:
            continue
        img = f"<img src='{png.name}' alt='{html.escape(title)}'>" if png is not None else ""
        parts.append(f"<h2>{html.escape(title)}</h2><p class='note'>{html.escape(caption)}</p>"
                     + img + (_list_html(items) if items else ""))
    for r in runs:
        if r.unavailable or r.notes:
            parts.append(f"<h2>Not computed for {html.escape(run_label(r))}</h2><ul>"
                         + "".join(f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>"
                                   for k, v in r.unavailable.items())
                         + "".join(f"<li>{html.escape(n)}</li>" for n in r.notes) + "</ul>")
    parts.append("<p class='note'>Every metric is also in <a href='metrics.json'>"
                 "metrics.json</a>; its gain keys name their units "
                 "(steady_state_gain_&lt;output unit&gt;_per_rad_&lt;road_wheel|"
                 "steering_wheel&gt;).</p></body></html>")
    index = out / "index.html"
    index.write_text("\n".join(parts))
    return index
