# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The report of ``fourws validate``: ``DIR/index.html`` (the look of ``fourws analyze``'s),
``DIR/curves.png`` (every curve over its reference and band) and ``DIR/validation.json``
(:meth:`ValidationResult.to_dict`)."""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from fourws_analysis.report import REPORT_CSS, _fmt, _list_html
from fourws_analysis.report_figures import _plt, _save
from fourws_analysis.validate import ValidationResult


def reading_notes(result: ValidationResult) -> list[str]:
    """What a reader must know to read the verdicts."""
    notes = [f"Standard: {result.standard}. Simulation: {result.simulation.name} "
             f"({result.simulation.source}); reference: {result.reference.name} "
             f"({result.reference.source})."]
    if result.standard == "iso19364":
        notes.append("Cross-plots against lateral acceleration of the quasi-steady samples "
                     "of each run, averaged in bins of |a_y|; every reference bin is a point "
                     "of the reference curve and the simulation's bin at the same |a_y| is "
                     "tested (a bin the simulation does not reach counts as outside).")
    elif result.standard == "iso19365":
        notes.append("Time histories from each run's beginning of steer (FMVSS 126 BOS) to "
                     "1.75 s after the reference's completion of steer; the regulation's "
                     "metrics side by side, each with its tolerance.")
    else:
        notes.append("Time histories from the start of each record over the shorter one.")
    notes.append("The band around the reference: at each point an ellipse of semi-axes "
                 "ε_x = a_x + b_x|x| and ε_y = a_y + b_y|y|; a simulated point is inside when "
                 "it lies in one of them (band distance ≤ 1). A curve passes when at least "
                 "its required share of points lies inside.")
    return notes


def figure_curves(result: ValidationResult) -> Any | None:
    """One panel per curve: the band (shaded), the reference (black) and the simulation
    (blue, red where outside the band)."""
    if not result.curves:
        return None
    plt = _plt()
    n = len(result.curves)
    cols = 2 if n > 1 else 1
    rows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(5.6 * cols, 3.8 * rows), squeeze=False,
                             layout="constrained")
    for ax, c in zip(axes.flat, result.curves):
        e = c.edges()
        poly_x = np.concatenate((e["upper_x"], e["lower_x"][::-1]))
        poly_y = np.concatenate((e["upper_y"], e["lower_y"][::-1]))
        ax.fill(poly_x, poly_y, color="0.85", lw=0, label="band")
        ax.plot(c.reference_x, c.reference_y, color="k", lw=1.4,
                marker="o" if c.x_unit != "s" else None, ms=3, label="reference")
        ax.plot(c.x, c.y, color="C0", lw=1.2, marker="o" if c.x_unit != "s" else None, ms=3,
                label="simulation")
        out = ~c.inside & np.isfinite(c.y)
        if np.any(out):
            ax.plot(c.x[out], c.y[out], "x", color="C3", ms=5, label="outside the band")
        verdict = "pass" if c.passed else "FAIL"
        ax.set_title(f"{c.label}: {100 * c.share_inside:.0f} % inside ({verdict})",
                     loc="left", fontweight="bold", fontsize=9)
        ax.set_xlabel(f"{c.x_label} ({c.x_unit})")
        ax.set_ylabel(c.y_unit)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    handles, labels = {}, {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
            labels[lab] = lab
    fig.legend(list(handles.values()), list(labels), loc="outside upper center",
               ncol=len(labels), frameon=False)
    return fig


def write_validate_report(result: ValidationResult, out_dir: str | Path,
                          plots: bool = True) -> Path:
    """Write ``index.html``, ``curves.png`` and ``validation.json`` into ``out_dir``.

    Returns
    -------
    Path
        The ``index.html``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "validation.json").write_text(json.dumps(result.to_dict(), indent=2))
    verdict = "PASSED" if result.passed else "FAILED"
    title = (f"fourws: validation of {result.simulation.name} against {result.reference.name}"
             f" ({result.standard}): {verdict}")
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>fourws validate"
             f"</title><style>{REPORT_CSS}</style></head><body><h1>{html.escape(title)}</h1>",
             "<h2>How to read the verdicts</h2>" + _list_html(reading_notes(result), "reading")]
    rows = "".join(
        f"<tr><td>{html.escape(c.label)}</td><td>{html.escape(c.y_unit)}</td>"
        f"<td>{_fmt(c.band.x_offset)} + {_fmt(c.band.x_gain)}·|x| {html.escape(c.x_unit)}</td>"
        f"<td>{_fmt(c.band.y_offset)} + {_fmt(c.band.y_gain)}·|y| {html.escape(c.y_unit)}</td>"
        f"<td>{_fmt(100 * c.share_inside)}</td><td>{_fmt(100 * c.required_share)}</td>"
        f"<td>{'pass' if c.passed else '<b>FAIL</b>'}</td></tr>" for c in result.curves)
    parts.append("<h2>Curves</h2><table><tr><th>curve</th><th>unit</th><th>band ε_x</th>"
                 "<th>band ε_y</th><th>inside (%)</th><th>required (%)</th><th>verdict</th>"
                 f"</tr>{rows}</table>")
    if result.metrics:
        rows = "".join(
            f"<tr><td>{html.escape(m.key)}</td><td>{html.escape(m.unit)}</td>"
            f"<td>{_fmt(m.simulation)}</td><td>{_fmt(m.reference)}</td>"
            f"<td>{_fmt(m.tolerance)}</td><td>{'pass' if m.passed else '<b>FAIL</b>'}</td>"
            "</tr>" for m in result.metrics)
        verdicts = ""
        if result.verdicts:
            sim, ref = (("pass" if result.verdicts.get(k) else "fail")
                        for k in ("simulation", "reference"))
            verdicts = (f"<tr><td>FMVSS 126 verdict</td><td>–</td><td>{sim}</td><td>{ref}</td>"
                        "<td>–</td><td>–</td></tr>")
        parts.append("<h2>FMVSS 126 metrics side by side</h2><table><tr><th>metric</th>"
                     "<th>unit</th><th>simulation</th><th>reference</th><th>tolerance</th>"
                     f"<th>verdict</th></tr>{rows}{verdicts}</table>")
    if plots:
        fig = figure_curves(result)
        if fig is not None:
            png = _save(fig, out / "curves.png")
            parts.append("<h2>Curves and bands</h2><p class='note'>Band shaded, reference "
                         "black, simulation blue (red crosses: outside the band).</p>"
                         f"<img src='{png.name}' alt='curves'>")
    sources = sorted({f"{c.label}: {c.band.source}" for c in result.curves})
    parts.append("<h2>Where the band numbers come from</h2>" + _list_html(sources))
    extra = [f"{k}: {v}" for k, v in result.skipped.items()] + list(result.notes)
    if extra:
        parts.append("<h2>Notes</h2>" + _list_html(extra))
    parts.append("<p class='note'>Every number is also in <a href='validation.json'>"
                 "validation.json</a>.</p></body></html>")
    index = out / "index.html"
    index.write_text("\n".join(parts))
    return index


__all__ = ["figure_curves", "reading_notes", "write_validate_report"]
