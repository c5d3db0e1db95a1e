# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The study report: ``DIR/report/index.html`` with PNG figures, in the look of the analysis
report (:mod:`fourws_analysis.report`).

For each law:

* a stability map over the two map axes (``report.map_axes``): each cell coloured by the
  share of its points that spun, diverged or failed (green: all ok), hatched where the law
  closed on the 8-DOF linearized at the cell's speed is unstable; when one map axis is the
  speed, the analytic boundary at each value of the other axis is drawn -- the critical
  speed of the 8-DOF linearized closed loop and that of the matching linear model, the
  number ``fourws linear --critical-speed`` gives at that belief (:func:`analytic_boundary`);
* heat maps of the chosen metrics (the cell mean over its points);
* one panel per value of each other grid axis (up to :data:`MAX_PANELS`; beyond, the cells
  pool them), Monte Carlo samples pooled in their cell.

For Monte Carlo studies: histograms and empirical CDFs of the metrics per law. Last, the
worst points by ``report.worst.metric`` with the command that reruns each through the node
graph.
"""

from __future__ import annotations

import html
import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pyarrow as pa
import scipy.optimize

from fourws_analysis import compare, linear
from fourws_analysis.report import REPORT_CSS
from fourws_sim.errors import FourwsError, ParameterError
from fourws_study.point import ZERO_MODE_PER_S, columns, law_for, linear_model_of
from fourws_study.spec import KMH_PER_MPS, Axis, Study
from fourws_study.store import read_results

#: Panels per law figure: more combinations of the other grid axes are pooled in the cells.
MAX_PANELS = 6
#: Heat-map metrics by maneuver type when the study names none.
DEFAULT_METRICS = {
    "step_steer": ("iso7401.yaw_rate_radps.overshoot_fraction",
                   "iso7401.yaw_rate_radps.response_time_s",
                   "iso7401.yaw_rate_radps.steady_state_gain_radps_per_rad_road_wheel",
                   "iso7401.tb_factor_s_deg", "max_abs_sideslip_rad"),
    "double_lane_change": ("iso3888.passed", "iso3888.clearance_m", "max_abs_sideslip_rad",
                           "max_abs_yaw_rate_radps"),
    "slow_ramp_steer": ("iso4138.understeer_gradient_rad_per_mps2", "max_abs_sideslip_rad"),
}
DEFAULT_METRICS["ramp_steer"] = DEFAULT_METRICS["step_steer"]
FALLBACK_METRICS = ("max_abs_sideslip_rad", "max_abs_yaw_rate_radps",
                    "time_at_rear_angle_limit_s")
#: Speed samples of the critical-speed search over a map's speed range.
_BOUNDARY_SAMPLES = 40
SPEED_AXES = {"speed_kmh": KMH_PER_MPS, "speed_mps": 1.0}


def _plt() -> Any:
    import matplotlib  # matplotlib: about 0.5 s to load, only the plots need it

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: about 0.5 s to load, only the plots need it

    plt.rcParams.update({"figure.dpi": 110, "font.size": 9, "axes.spines.top": False,
                         "axes.spines.right": False, "legend.fontsize": 8})
    return plt


@dataclass
class Panel:
    """One panel: the values of the other grid axes it holds fixed, and its rows."""

    title: str
    fixed: tuple[tuple[Axis, Any], ...]
    rows: np.ndarray  # indices into the table


def _column(table: pa.Table, name: str) -> np.ndarray:
    col = table.column(name).to_pylist()
    if col and isinstance(next((v for v in col if v is not None), 0.0), str):
        return np.array(col, dtype=object)
    return np.array([math.nan if v is None else v for v in col], dtype=float)


def _panels(study: Study, table: pa.Table, law_rows: np.ndarray) -> list[Panel]:
    others = [a for a in study.grid if a.numeric and len(a.values) > 1
              and a.key not in study.report.map_axes]
    combos = list(itertools.product(*(a.values for a in others))) if others else [()]
    if len(combos) > MAX_PANELS:
        return [Panel("all values of " + ", ".join(a.key for a in others), (), law_rows)]
    panels = []
    cols = {a.key: _column(table, a.key) for a in others}
    for combo in combos:
        mask = np.ones(law_rows.size, dtype=bool)
        for a, v in zip(others, combo):
            mask &= cols[a.key][law_rows] == v
        title = ", ".join(f"{a.key} = {v:g}" for a, v in zip(others, combo))
        panels.append(Panel(title, tuple(zip(others, combo)), law_rows[mask]))
    return panels


def critical_speed_8dof_lin(vehicle: Any, law: Any, belief: Any, options: Any,
                            lo_mps: float, hi_mps: float, refine: bool = True,
                            samples: int = _BOUNDARY_SAMPLES) -> float | None:
    """Lowest speed in [lo, hi] (m/s) where the law closed on the 8-DOF linearized at
    straight running loses stability (largest real part of its modes crosses 0; the
    coasting-speed and wheel-spin modes at 0 left out): the first sign change over
    ``samples`` speeds, refined with brentq (to 1e-4 m/s), or with ``refine`` False
    interpolated linearly between the two samples (for drawing); ``lo`` if it is unstable
    there, None if stable throughout."""
    def margin(u: float) -> float:
        eig = np.linalg.eigvals(compare.eightdof_linear_system(vehicle, u, law, belief,
                                                               options).A)
        eig = eig[np.abs(eig) > ZERO_MODE_PER_S]
        return -float(np.max(eig.real))

    speeds = np.linspace(lo_mps, hi_mps, samples)
    prev = margin(float(speeds[0]))
    if prev <= 0.0:
        return float(lo_mps)
    for a, b in zip(speeds[:-1], speeds[1:]):
        m = margin(float(b))
        if m <= 0.0:
            if refine:
                return float(scipy.optimize.brentq(margin, float(a), float(b), xtol=1e-4))
            return float(a + (b - a) * prev / (prev - m))
        prev = m
    return None


def analytic_boundary(study: Study, law: str, settings: Sequence[tuple[Axis, Any]],
                      lo_mps: float, hi_mps: float) -> dict[str, float | None]:
    """Critical speeds (m/s) of the law at the base run with ``settings`` applied (the
    non-speed axis values of a map cell): ``8dof_lin`` (:func:`critical_speed_8dof_lin`)
    and that of the matching linear model (:func:`fourws_analysis.linear.critical_speed`,
    what ``fourws linear --critical-speed`` gives), searched over [lo, hi]."""
    law_axis = [a for a in study.grid if not a.numeric]
    full = list(settings) + ([(law_axis[0], law)] if law_axis else [])
    config = study._config(tuple(full))
    law_obj = law_for(config)
    out: dict[str, float | None] = {}
    model = linear_model_of(config)
    try:
        if config.vehicle.body is not None and config.vehicle.roll is not None:
            out["8dof_lin"] = critical_speed_8dof_lin(config.vehicle, law_obj, config.belief,
                                                      config.law_options, lo_mps, hi_mps,
                                                      refine=False)
    except (FourwsError, np.linalg.LinAlgError, ValueError):
        out["8dof_lin"] = None
    try:
        cs = linear.critical_speed(model, config.vehicle, law_obj, (lo_mps, hi_mps))
        out[model] = cs.critical_speed_mps
    except (FourwsError, np.linalg.LinAlgError):
        out[model] = None
    return out


def _status_share(status: np.ndarray) -> tuple[float, str]:
    """Share of points not ok, and the cell's mark (most common bad status)."""
    bad = [s for s in status if s != "ok"]
    if not bad:
        return 0.0, ""
    top = max(set(bad), key=bad.count)
    return len(bad) / len(status), {"spun": "S", "diverged": "D", "error": "E"}.get(top, "?")


def _cells(study: Study, table: pa.Table, rows: np.ndarray) -> tuple[list[Any], list[Any],
                                                                     dict[tuple[int, int],
                                                                          np.ndarray]]:
    axes = [next(a for a in study.grid if a.key == k) for k in study.report.map_axes]
    xs = list(axes[0].values)
    ys = list(axes[1].values) if len(axes) > 1 else [None]
    cx = _column(table, axes[0].key)[rows]
    cy = _column(table, axes[1].key)[rows] if len(axes) > 1 else None
    cells = {}
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            mask = cx == x
            if cy is not None:
                mask &= cy == y
            cells[(i, j)] = rows[mask]
    return xs, ys, cells


def _panel_axes(n: int, height: float) -> tuple[Any, list[Any]]:
    """A figure with ``n`` panels in rows of at most three (unused axes hidden)."""
    plt = _plt()
    cols = min(n, 3)
    rows = -(-n // cols)
    fig, axs = plt.subplots(rows, cols, figsize=(4.4 * cols + 1.2, height * rows + 0.6),
                            squeeze=False, constrained_layout=True)
    flat = list(axs.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def figure_stability(study: Study, table: pa.Table, law: str, rows: np.ndarray,
                     boundaries: bool = True) -> Any:
    """The stability map figure of one law (module docstring)."""
    plt = _plt()
    # matplotlib: about 0.5 s to load, only the plots need it
    from matplotlib.colors import LinearSegmentedColormap

    cmap = LinearSegmentedColormap.from_list("okbad", ["#4caf50", "#ffc107", "#e53935"])
    panels = _panels(study, table, rows)
    fig, axs = _panel_axes(len(panels), 3.9)
    status = _column(table, "status")
    stable8 = _column(table, "stable_8dof_lin")
    x_key = study.report.map_axes[0]
    y_key = study.report.map_axes[1] if len(study.report.map_axes) > 1 else None
    image = None
    for ax, panel in zip(axs, panels):
        xs, ys, cells = _cells(study, table, panel.rows)
        grid = np.full((len(ys), len(xs)), np.nan)
        for (i, j), idx in cells.items():
            if idx.size == 0:
                continue
            share, mark = _status_share(list(status[idx]))
            grid[j, i] = share
            if mark:
                ax.text(i, j, mark, ha="center", va="center", fontsize=7, color="k")
            lin = stable8[idx]
            if np.any(lin == 0.0):
                ax.add_patch(plt.Rectangle((i - 0.5, j - 0.5), 1, 1, fill=False, hatch="///",
                                           edgecolor="#333", lw=0))
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap=cmap, vmin=0.0, vmax=1.0)
        ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs], rotation=90)
        ax.set_yticks(range(len(ys)), [f"{y:g}" if y is not None else "" for y in ys])
        ax.set_xlabel(x_key)
        ax.set_ylabel(y_key or "")
        ax.set_title(panel.title or law, fontsize=8)
        if boundaries and y_key is not None and (x_key in SPEED_AXES or y_key in SPEED_AXES):
            _draw_boundaries(ax, study, table, law, panel, xs, ys, x_key, y_key)
    fig.colorbar(image, ax=axs, label="share of points spun / diverged / failed")
    fig.suptitle(f"law {law}: stability over {x_key}" + (f" x {y_key}" if y_key else "")
                 + "\n(S spun, D diverged, E error; /// 8-DOF linearized unstable)",
                 fontsize=9)
    return fig


def _draw_boundaries(ax: Any, study: Study, table: pa.Table, law: str, panel: Panel,
                     xs: list[Any], ys: list[Any], x_key: str, y_key: str) -> None:
    """Critical speed at each value of the other map axis, in cell coordinates."""
    speed_on_x = x_key in SPEED_AXES
    speeds, others = (xs, ys) if speed_on_x else (ys, xs)
    other_axis = next(a for a in study.grid if a.key == (y_key if speed_on_x else x_key))
    per_unit = SPEED_AXES[x_key if speed_on_x else y_key]
    lo, hi = min(speeds) / per_unit, max(speeds) / per_unit
    curves: dict[str, list[tuple[float, float]]] = {}
    other_col = _column(table, other_axis.key)[panel.rows]
    verdicts = np.concatenate([_column(table, "stable_8dof_lin")[panel.rows, None],
                               _column(table, "stable_linear")[panel.rows, None]], axis=1)
    for k, value in enumerate(others):
        if np.all(verdicts[other_col == value] == 1.0):
            continue  # stable at every speed of the map in both models: no boundary in it
        found = analytic_boundary(study, law, (*panel.fixed, (other_axis, value)), lo, hi)
        for model, vc in found.items():
            if vc is None:
                continue
            pos = float(np.interp(vc * per_unit, speeds, np.arange(len(speeds))))
            curves.setdefault(model, []).append((pos, float(k)))
    styles = {"8dof_lin": ("k--", "8-DOF linearized"), "3dof": ("b:", "3-DOF (fourws linear)"),
              "2dof": ("b:", "2-DOF (fourws linear)")}
    for model, pts in curves.items():
        a, b = np.array(pts).T
        style, label = styles.get(model, ("c-", model))
        if speed_on_x:
            ax.plot(a, b, style, marker="|", lw=1.5, label=f"critical speed, {label}")
        else:
            ax.plot(b, a, style, marker="_", lw=1.5, label=f"critical speed, {label}")
    if curves:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.28), fontsize=7, frameon=False)


def figure_heat(study: Study, table: pa.Table, law: str, rows: np.ndarray,
                metric: str) -> Any:
    """Heat map of ``metric`` (cell means) for one law."""
    panels = _panels(study, table, rows)
    values = _column(table, metric)
    fig, axs = _panel_axes(len(panels), 3.4)
    finite = values[rows][np.isfinite(values[rows])]
    vmin, vmax = (float(np.min(finite)), float(np.max(finite))) if finite.size else (0, 1)
    image = None
    for ax, panel in zip(axs, panels):
        xs, ys, cells = _cells(study, table, panel.rows)
        grid = np.full((len(ys), len(xs)), np.nan)
        for (i, j), idx in cells.items():
            v = values[idx]
            v = v[np.isfinite(v)]
            if v.size:
                grid[j, i] = float(np.mean(v))
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis", vmin=vmin,
                          vmax=vmax if vmax > vmin else vmin + 1e-12)
        ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs], rotation=90)
        ax.set_yticks(range(len(ys)), [f"{y:g}" if y is not None else "" for y in ys])
        ax.set_xlabel(study.report.map_axes[0])
        ax.set_ylabel(study.report.map_axes[1] if len(study.report.map_axes) > 1 else "")
        ax.set_title(panel.title or law, fontsize=8)
    fig.colorbar(image, ax=axs, label=metric)
    fig.suptitle(f"law {law}: {metric} (cell mean; blank: no value)", fontsize=9)
    return fig


def figure_distributions(table: pa.Table, laws: Sequence[str], metric: str) -> Any:
    """Histogram of ``metric`` per law (a panel each, its own bins) and the empirical CDFs of
    all laws in the last panel, over the points whose status is ``ok`` (a spun run's
    metrics describe the spin, not the car; their count is in each title)."""
    law_col = _column(table, "law")
    values = _column(table, metric)
    ok = _column(table, "status") == "ok"
    fig, axs = _panel_axes(len(laws) + 1, 2.6)
    cdf = axs[-1]
    for k, (ax, law) in enumerate(zip(axs, laws)):
        mine = law_col == law
        v = values[mine & ok & np.isfinite(values)]
        left_out = int(np.count_nonzero(mine & ~ok))
        ax.set_title(f"{law}: {v.size} points" + (f", {left_out} not ok left out"
                                                  if left_out else ""), fontsize=8)
        if not v.size:
            continue
        ax.hist(v, bins=30, color=f"C{k % 10}")
        ax.set_ylabel("points")
        s = np.sort(v)
        cdf.step(s, np.arange(1, s.size + 1) / s.size, where="post", color=f"C{k % 10}",
                 label=law)
    cdf.set_title("empirical CDF", fontsize=8)
    cdf.legend(loc="lower right", fontsize=6, frameon=False)
    fig.suptitle(metric, fontsize=9)
    return fig


def worst_points(table: pa.Table, metric: str, count: int) -> list[dict[str, Any]]:
    """The ``count`` rows with the largest ``metric`` (NaN and errors last)."""
    values = _column(table, metric)
    key = np.where(np.isfinite(values), values, -np.inf)
    order = np.argsort(-key, kind="stable")[:count]
    rows = table.take(pa.array(order)).to_pylist()
    return rows


def _fmt(v: Any) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return "–" if not math.isfinite(v) else f"{v:.4g}"
    return html.escape(str(v))


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt  # matplotlib: about 0.5 s to load, only the plots need it

    fig.savefig(path)
    plt.close(fig)
    return path


def check_report(study: Study) -> None:
    """Refuse a report metric (``report.metrics``, ``report.worst.metric``) that is no
    numeric result column of ``study`` (the report drew nothing for it, without a word).

    Raises
    ------
    ParameterError
        Naming the field, the metric, the study file and every valid name.
    """
    numeric = [name for name, kind in columns(study) if kind in ("float64", "int64", "bool")]
    for field, names in (("report.metrics", study.report.metrics),
                         ("report.worst.metric", (study.report.worst_metric,))):
        for name in names:
            if name not in numeric:
                raise ParameterError(field, f"{name!r} is not a numeric result column "
                                     f"(valid: {', '.join(numeric)})", study.source)


def write_study_report(root: str | Path, study: Study, plots: bool = True) -> Path:
    """Write ``root/report/index.html`` and its PNGs from the finished rows of ``root``.

    Raises
    ------
    ParameterError
        A report metric is no result column (:func:`check_report`), or a block is damaged.
    """
    check_report(study)
    root = Path(root)
    out = root / "report"
    out.mkdir(parents=True, exist_ok=True)
    table = read_results(root, study)
    laws = sorted(set(_column(table, "law")), key=str)
    status = list(_column(table, "status"))
    counts = {s: status.count(s) for s in ("ok", "spun", "diverged", "error")}
    maneuver = study.base.scenario.maneuver.type
    limits = study.base.scenario.vehicle_limits or study.base.scenario.maneuver.vehicle_limits
    metrics = [m for m in (study.report.metrics or DEFAULT_METRICS.get(maneuver,
                                                                       FALLBACK_METRICS))
               if m in table.column_names]
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>fourws study "
             f"{html.escape(study.name)}</title><style>{REPORT_CSS}</style></head><body>",
             f"<h1>fourws study: {html.escape(study.name)}</h1>",
             f"<p>{html.escape(study.description)}</p>",
             f"<p>{table.num_rows} of {study.n_points} points finished: "
             + ", ".join(f"{k} {v}" for k, v in counts.items()) + ". Base scenario "
             f"{html.escape(study.base.scenario.name)}, maneuver "
             f"{html.escape(study.base.scenario.maneuver.name)} ({html.escape(maneuver)}), "
             f"model {html.escape(study.base.scenario.model)}.</p>",
             "<h2>How to read it</h2><ul class='reading'>"
             "<li>Each point is one closed-loop run of the offline twin of the lockstep node "
             "graph; its metrics are those of <code>fourws analyze</code>.</li>"
             f"<li>Status: <b>spun</b> when |sideslip| exceeds "
             f"{math.degrees(limits.max_sideslip_rad):.0f} deg or the forward speed falls "
             f"below {limits.min_forward_speed_mps:g} m/s, <b>diverged</b> when |roll| exceeds "
             f"{math.degrees(limits.max_roll_rad):.0f} deg or the state became non-finite "
             "(the maneuver's vehicle limits, by which every run ends there; its ISO metrics "
             "are left empty), <b>error</b> when the point could not be built or run (the "
             "reason is in the table).</li>"
             "<li>Linear stability: the law (designed on the controller's belief) closed on "
             "the 8-DOF linearized at straight running at the point's speed, and on the "
             "matching linear model (3-DOF with roll data, else 2-DOF), both on the true "
             "car; modes at 0 (coasting speed, wheel spin) left out.</li>"
             "<li>Critical-speed lines: where that closed loop loses stability at each value "
             "of the other map axis (the 3-DOF/2-DOF line is what "
             "<code>fourws linear --critical-speed</code> gives).</li></ul>"]
    if plots and study.report.map_axes:
        law_col = _column(table, "law")
        for law in laws:
            rows = np.nonzero(law_col == law)[0]
            parts.append(f"<h2>Law {html.escape(str(law))}</h2>")
            png = _save(figure_stability(study, table, law, rows),
                        out / f"stability_{law}.png")
            parts.append(f"<h3>Stability map</h3><img src='{png.name}' alt='stability'>")
            for metric in metrics:
                png = _save(figure_heat(study, table, law, rows, metric),
                            out / f"heat_{law}_{metric.replace('.', '_')}.png")
                parts.append(f"<h3>{html.escape(metric)}</h3><img src='{png.name}' "
                             f"alt='{html.escape(metric)}'>")
    if plots and study.monte_carlo is not None:
        parts.append("<h2>Distributions over the Monte Carlo samples</h2>")
        for metric in metrics + [f"{a.key}" for a in study.monte_carlo.fields]:
            if metric not in table.column_names:
                continue
            png = _save(figure_distributions(table, laws, metric),
                        out / f"distribution_{metric.replace('.', '_').replace(',', '')}.png")
            parts.append(f"<h3>{html.escape(metric)}</h3><img src='{png.name}' "
                         f"alt='{html.escape(metric)}'>")
    metric = study.report.worst_metric
    if metric in table.column_names:
        keys = [a.key for a in study.axes if a.key != "law"]
        head = "".join(f"<th>{html.escape(h)}</th>" for h in
                       ["point", "law", *keys, "status", metric, "reason", "rerun"])
        body = []
        for r in worst_points(table, metric, study.report.worst_count):
            cells = [r["point"], r["law"], *(r.get(k) for k in keys), r["status"],
                     r.get(metric), r.get("status_reason") or ""]
            cmd = f"fourws study rerun {root} --point {r['point']}"
            body.append("<tr>" + "".join(f"<td>{_fmt(c)}</td>" for c in cells)
                        + f"<td><code>{html.escape(cmd)}</code></td></tr>")
        parts.append(f"<h2>Worst points by {html.escape(metric)}</h2><table><tr>{head}</tr>"
                     + "".join(body) + "</table>")
    parts.append("<p class='note'>Every row is in <code>results.parquet</code> beside this "
                 "folder; the study file, the resolved base run and the software versions "
                 "are in <code>study.yaml</code>, <code>base_run_config.json</code> and "
                 "<code>versions.json</code>.</p></body></html>")
    index = out / "index.html"
    index.write_text("\n".join(parts))
    return index


__all__ = ["DEFAULT_METRICS", "MAX_PANELS", "analytic_boundary", "check_report",
           "critical_speed_8dof_lin",
           "figure_distributions", "figure_heat", "figure_stability", "worst_points",
           "write_study_report"]
