# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The report of ``fourws identify``: ``DIR/index.html`` (the look of ``fourws analyze``'s),
the PNG plots beside it and ``DIR/identification.json`` (:meth:`FitResult.to_dict`).

Sections: how to read the numbers; the fitted values with their 95 % intervals; the
correlation of the fitted parameters (pairs that cannot be told apart marked); the residual of
each channel; measured against model time histories per log; the measured against model
frequency response where the input was broadband; a closing note with the time the
identification took.
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from fourws_analysis.fit import INDISTINGUISHABLE, MAX_PREDICTED_CI, FitResult
from fourws_analysis.frequency import break_phase_jumps, display_phase_deg
from fourws_analysis.measured import COLUMN_BY_NAME
from fourws_analysis.report import REPORT_CSS, _fmt, _list_html
from fourws_analysis.report_figures import _frequency_ticks, _plt, _save


def reading_notes(result: FitResult) -> list[str]:
    """What a reader must know to read the numbers."""
    level = f"Model level: {result.level} ({result.level_reason})."
    return [
        level,
        "Output error: the model is driven by each log's recorded inputs (steering-wheel angle "
        "over the steering ratio, the rear road-wheel angle of a rear-steer car, and for the "
        "8-DOF the recorded speed, which its speed-hold driver follows) and the fitted values "
        "minimise the weighted squared difference of every channel the log and the model "
        "share (scipy.optimize.least_squares, inside each field's plausibility bounds).",
        ("A constant offset per channel and log (a sensor bias) is fitted with the values; "
         "the channel table gives it." if result.bias else
         "No sensor offsets fitted (--no-bias): the sensors are taken as zeroed."),
        "95 % interval: ±1.96 standard deviations from the Jacobian at the optimum and each "
        "channel's residual noise (never less than its instrument floor; widened where the "
        "residual is correlated from sample to sample, a sign of model error).",
        f"Two fitted values whose correlation exceeds {INDISTINGUISHABLE:g} in magnitude "
        "cannot be told apart by these records: only a combination of them is known.",
        f"A field the records could not pin within ±{100 * MAX_PREDICTED_CI:g} % was refused "
        "before fitting (too little excitation).",
    ]


def _table(head: Sequence[str], rows: Sequence[Sequence[Any]], title: str) -> str:
    th = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{c if isinstance(c, _Raw) else _fmt(c)}</td>"
                                    for c in row) + "</tr>" for row in rows)
    return f"<h3>{html.escape(title)}</h3><table><tr>{th}</tr>{body}</table>"


class _Raw(str):
    """Table cell HTML that is not escaped."""


def value_rows(result: FitResult) -> list[list[Any]]:
    """One row per fitted field: field, unit, base, fitted, ±95 %, relative, change."""
    rows: list[list[Any]] = []
    for v in result.values:
        change = None if not v.base else f"{100.0 * (v.value / v.base - 1.0):+.2f}"
        rows.append([v.path, v.unit, f"{v.base:.6g}", f"{v.value:.6g}", f"{v.ci95:.3g}",
                     f"{100.0 * v.relative_ci95:.3g}", change])
    return rows


def figure_histories(result: FitResult, index: int) -> Any:
    """Measured (solid) and fitted model (dashed, its bias added) channels of one log."""
    plt = _plt()
    log, model = result.logs[index], result.model[index]
    chans = list(model)
    fig, axes = plt.subplots(len(chans) + 1, 1, figsize=(10, 1.9 * (len(chans) + 1)),
                             sharex=True, layout="constrained", squeeze=False)
    t = log.time_s - log.time_s[0]
    ax = axes[0, 0]
    ax.plot(t, log.channels["steering_wheel_angle_rad"] * math.degrees(1.0), color="0.3", lw=1)
    ax.set_title("steering-wheel angle δH (input)", loc="left", fontweight="bold")
    ax.set_ylabel("deg")
    for ax, ch in zip(axes[1:, 0], chans):
        scale, unit = COLUMN_BY_NAME[ch].display
        ax.plot(t, log.channels[ch] * scale, color="C0", lw=1.2, label="measured")
        ax.plot(t, model[ch] * scale, color="C1", lw=1.2, ls="--", label="model (fitted)")
        ax.set_title(COLUMN_BY_NAME[ch].label, loc="left", fontweight="bold")
        ax.set_ylabel(unit)
    axes[-1, 0].set_xlabel("time (s)")
    handles, labels = axes[1, 0].get_legend_handles_labels() if chans else ([], [])
    fig.legend(handles, labels, loc="outside upper center", ncol=2, frameon=False)
    return fig


def figure_frequency(result: FitResult) -> Any | None:
    """Measured (solid) and model (dashed) gain and phase per steering-wheel angle, over the
    trusted band of each broadband log."""
    if not result.frequency:
        return None
    plt = _plt()
    n = len(result.frequency)
    cols = min(3, n)
    blocks = int(math.ceil(n / cols))
    fig, axes = plt.subplots(2 * blocks, cols, figsize=(4.6 * cols, 5.2 * blocks),
                             squeeze=False, layout="constrained")
    for k, fr in enumerate(result.frequency):
        ax_g, ax_p = axes[2 * (k // cols), k % cols], axes[2 * (k // cols) + 1, k % cols]
        mask = fr.measured.trusted() & (fr.measured.freq_hz > 0)
        f = fr.measured.freq_hz[mask]
        scale, unit = COLUMN_BY_NAME[fr.output].display
        for resp, style, label in ((fr.measured, "-", "measured"), (fr.model, "--", "model")):
            gain = 20.0 * np.log10(np.maximum(np.abs(resp.response[mask]) * scale, 1e-300))
            ax_g.semilogx(f, gain, style, lw=1.5, label=label)
            ax_p.semilogx(*break_phase_jumps(f, display_phase_deg(resp)[mask]), style, lw=1.5)
        ax_g.set_title(f"{fr.log}: {fr.output}", loc="left", fontweight="bold", fontsize=9)
        ax_g.set_ylabel(f"dB re 1 {unit}/rad of δH")
        ax_p.set_ylabel("phase (deg)")
        ax_p.set_xlabel("frequency (Hz)")
        for ax in (ax_g, ax_p):
            _frequency_ticks(ax)
    for k in range(n, blocks * cols):
        axes[2 * (k // cols), k % cols].set_visible(False)
        axes[2 * (k // cols) + 1, k % cols].set_visible(False)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncol=2, frameon=False)
    return fig


def write_identify_report(result: FitResult, out_dir: str | Path,
                          yaml_path: str | Path | None = None, plots: bool = True) -> Path:
    """Write ``index.html``, the plots and ``identification.json`` into ``out_dir``.

    Returns
    -------
    Path
        The ``index.html``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "identification.json").write_text(json.dumps(result.to_dict(), indent=2))
    specs = [g.spec for g in result.groups]
    title = (f"fourws: {result.vehicle.name} fitted to {len(result.logs)} log(s) on the "
             f"{result.level} level")
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>fourws identify"
             f"</title><style>{REPORT_CSS}</style></head><body><h1>{html.escape(title)}</h1>",
             "<h2>How to read the numbers</h2>" + _list_html(reading_notes(result), "reading")]
    data_rows = [[g.name, g.source, g.maneuver or "–", g.duration_s, g.dt_s, g.time_s.size]
                 for g in result.logs]
    parts.append("<h2>Data and fit</h2>" + _table(
        ["log", "source", "maneuver", "duration (s)", "sample period (s)", "samples"],
        data_rows, "Logs"))
    parts.append(_table(["field", "unit", "base", "fitted", "± 95 %", "± 95 % (%)",
                         "change from base (%)"], value_rows(result), "Fitted values"))
    corr_rows = []
    for i, spec in enumerate(specs):
        cells: list[Any] = [spec]
        for j in range(len(specs)):
            rho = result.correlation[i, j]
            text = _fmt(float(rho), 3)
            flag = i != j and math.isfinite(rho) and abs(rho) > INDISTINGUISHABLE
            cells.append(_Raw(f"<b>{text}</b>") if flag else float(rho))
        corr_rows.append(cells)
    parts.append(_table(["fitted"] + [f"{k + 1}" for k in range(len(specs))], corr_rows,
                        "Correlation of the fitted values (columns in row order; bold: "
                        "cannot be told apart)"))
    if result.indistinguishable:
        parts.append(_list_html([f"{a} and {b} cannot be told apart (correlation {r:+.3f})"
                                 for a, b, r in result.indistinguishable]))
    parts.append(_table(["log", "channel", "unit", "RMS residual", "signal std", "bias",
                         "noise σ used", "lag-1 autocorrelation"],
                        [[c.log, c.channel, c.unit, c.rms_residual, c.rms_signal, c.bias,
                          c.sigma, c.autocorrelation] for c in result.channels],
                        "Residual per channel (measured minus model)"))
    if result.frequency:
        parts.append(_table(["log", "output", "band (Hz)", "gain error RMS (dB)",
                             "phase error RMS (deg)"],
                            [[f.log, f.output, f"{f.band_hz[0]:.3g}-{f.band_hz[1]:.3g}",
                              f.gain_error_db, f.phase_error_deg] for f in result.frequency],
                            "Frequency response fit (broadband input)"))
    if plots:
        for k, log in enumerate(result.logs):
            png = _save(figure_histories(result, k), out / f"histories_{k + 1}.png")
            parts.append(f"<h2>Time histories: {html.escape(log.name)}</h2><p class='note'>"
                         "Measured (solid) and the fitted model (dashed, with its fitted "
                         f"bias), from the start of the record.</p><img src='{png.name}' "
                         f"alt='time histories {html.escape(log.name)}'>")
        fig = figure_frequency(result)
        if fig is not None:
            png = _save(fig, out / "frequency_response.png")
            parts.append("<h2>Frequency response</h2><p class='note'>H1 estimates per "
                         "steering-wheel angle of the measured channels (solid) and of the "
                         "fitted model's (dashed) from the same input, over the band where "
                         "the measured estimate is trusted (coherence, input power).</p>"
                         f"<img src='{png.name}' alt='frequency response'>")
    notes = list(result.notes) + [n for g in result.logs for n in g.notes]
    if notes:
        parts.append("<h2>Notes</h2>" + _list_html(notes))
    if yaml_path is not None:
        parts.append(f"<p>Fitted vehicle file: <code>{html.escape(str(yaml_path))}</code></p>")
    parts.append(f"<p class='note'>The identification took {result.elapsed_s:.2f} s "
                 f"({result.evaluations} model runs). Every number is also in "
                 "<a href='identification.json'>identification.json</a>.</p></body></html>")
    index = out / "index.html"
    index.write_text("\n".join(parts))
    return index


__all__ = ["figure_frequency", "figure_histories", "reading_notes", "value_rows",
           "write_identify_report"]
