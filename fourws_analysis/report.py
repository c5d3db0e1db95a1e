"""Plots and the self-contained HTML report of analysed runs (matplotlib Agg).

The analysis layer (:mod:`fourws_analysis.compare`) returns result objects; this module only
draws them. :func:`write_report` writes ``DIR/index.html``, the PNG plots next to it and
``DIR/metrics.json`` with every metric.
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from fourws_analysis.compare import RunAnalysis
from fourws_analysis.frequency import COHERENCE_MIN

#: Time-history panels: channel, label, scale to display unit, unit.
HISTORY_PANELS = (
    ("yaw_rate_radps", "yaw rate", math.degrees(1.0), "deg/s"),
    ("lateral_accel_mps2", "lateral acceleration", 1.0, "m/s²"),
    ("sideslip_rad", "sideslip β", math.degrees(1.0), "deg"),
    ("roll_rad", "roll φ", math.degrees(1.0), "deg"),
    ("front_wheel_angle_rad", "front road-wheel angle δf", math.degrees(1.0), "deg"),
    ("rear_wheel_angle_rad", "rear road-wheel angle δr", math.degrees(1.0), "deg"),
)
#: Bode outputs: channel, title, display gain unit (per rad of front road-wheel angle).
BODE_OUTPUTS = (
    ("yaw_rate_radps", "yaw rate / δf", "1/s"),
    ("lateral_accel_mps2", "lateral acceleration / δf", "m/s²/rad"),
    ("sideslip_rad", "sideslip / δf", "rad/rad"),
    ("roll_rad", "roll / δf", "rad/rad"),
)
#: Model gains are drawn no lower than this below the lowest measured gain, dB.
GAIN_FLOOR_BELOW_DB = 20.0
#: Eigenvalues with real part below minus this (wheel spin, tire lag, actuator) are not drawn.
EIG_PLOT_MIN_REAL = 40.0
_MODEL_STYLES = {"2dof": ("--", "0.25"), "3dof": (":", "0.1"), "8dof-lin": ("-.", "tab:red")}

Progress = Callable[[str], None]


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"figure.dpi": 110, "axes.grid": True, "grid.alpha": 0.3,
                         "axes.spines.top": False, "axes.spines.right": False,
                         "font.size": 9, "legend.fontsize": 8, "legend.framealpha": 0.8})
    return plt


def plot_time_histories(runs: Sequence[RunAnalysis], path: Path) -> Path:
    """Overlaid time histories (yaw rate, a_y, sideslip, roll, front and rear angles)."""
    plt = _plt()
    fig, axes = plt.subplots(3, 2, figsize=(11, 8), sharex=True)
    for ax, (chan, label, scale, unit) in zip(axes.flat, HISTORY_PANELS):
        for k, r in enumerate(runs):
            y = r.run.channels.get(chan)
            if y is None:
                continue
            ax.plot(r.run.time_s - r.run.time_s[0], y * scale, lw=1.3, color=f"C{k}",
                    label=f"{r.name} ({r.law})")
        ax.set_title(label, loc="left", fontweight="bold")
        ax.set_ylabel(unit)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=min(4, max(1, len(labels))),
               frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    fig.savefig(path)
    plt.close(fig)
    return path


def plot_bode(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Gain, phase and coherence per output; measured (solid, grey where coherence is low)
    over the model responses (dashed)."""
    outputs = [o for o in BODE_OUTPUTS
               if any(f"{o[0]}/front_wheel_angle_rad" in r.frequency for r in runs)]
    if not outputs:
        return None
    plt = _plt()
    fig, axes = plt.subplots(3, len(outputs), figsize=(4.2 * len(outputs), 8.5), sharex=True,
                             gridspec_kw={"height_ratios": [3, 3, 1.3]}, squeeze=False)
    for col, (chan, title, unit) in enumerate(outputs):
        ax_g, ax_p, ax_c = axes[:, col]
        floor_db = min((float(np.nanmin(r.frequency[f"{chan}/front_wheel_angle_rad"].gain_db))
                        for r in runs if f"{chan}/front_wheel_angle_rad" in r.frequency),
                       default=-100.0) - GAIN_FLOOR_BELOW_DB
        for k, r in enumerate(runs):
            fr = r.frequency.get(f"{chan}/front_wheel_angle_rad")
            if fr is None:
                continue
            ok = fr.trusted()
            off_axis = fr.freq_hz <= 0.0  # the 0 Hz point of a transient estimate
            color = f"C{k}"
            ax_g.semilogx(fr.freq_hz, _masked(fr.gain_db, ~ok | off_axis), color=color, lw=1.8,
                          label=f"{r.name} measured")
            ax_g.semilogx(fr.freq_hz, _masked(fr.gain_db, ok | off_axis), color=color, lw=0.8,
                          alpha=0.3)
            ax_p.semilogx(fr.freq_hz, _masked(fr.phase_deg, ~ok | off_axis), color=color,
                          lw=1.8)
            ax_p.semilogx(fr.freq_hz, _masked(fr.phase_deg, ok | off_axis), color=color,
                          lw=0.8, alpha=0.3)
            if fr.coherence is not None:
                ax_c.semilogx(fr.freq_hz, _masked(fr.coherence, off_axis), color=color, lw=1.2)
            for name, system in r.models.items():
                if chan not in system.C:
                    continue
                f = np.geomspace(max(fr.freq_hz[0], 0.02), fr.freq_hz[-1], 300)
                model = system.response(chan, f)
                style, mcolor = _MODEL_STYLES.get(name, ("--", "0.4"))
                lbl = f"{name} model" + (f" ({r.name})" if len(runs) > 1 else "")
                # a model whose gain is zero (e.g. sideslip under a zero-sideslip law) would
                # squash the axis to -300 dB: show it at the floor instead
                line_color = mcolor if len(runs) == 1 else color
                ax_g.semilogx(f, np.maximum(model.gain_db, floor_db), style, color=line_color,
                              lw=1.2, label=lbl)
                ph = model.phase_deg
                ax_p.semilogx(f, ph, style, color=mcolor if len(runs) == 1 else color, lw=1.2)
        ax_g.set_title(title, loc="left", fontweight="bold")
        ax_g.set_ylabel(f"gain (dB re 1 {unit})")
        ax_p.set_ylabel("phase (deg)")
        ax_c.set_ylabel("coherence")
        ax_c.axhline(COHERENCE_MIN, color="0.5", lw=0.8, ls=":")
        ax_c.set_ylim(0, 1.05)
        ax_c.set_xlabel("frequency (Hz)")
        ax_g.legend(loc="lower left")
    fig.suptitle("Frequency response per front road-wheel angle (faded: coherence < "
                 f"{COHERENCE_MIN} or input not excited)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _masked(values: np.ndarray, mask: np.ndarray) -> np.ndarray:
    out = np.array(values, dtype=float)
    out[mask] = np.nan
    return out


def plot_step(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Step responses normalized by their steady state, with ISO 7401 markers."""
    steps = [r for r in runs if r.step is not None]
    if not steps:
        return None
    plt = _plt()
    chans = (("yaw_rate_radps", "yaw rate"), ("lateral_accel_mps2", "lateral acceleration"))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    for ax, (chan, title) in zip(axes, chans):
        for k, r in enumerate(steps):
            m = r.step.responses.get(chan)
            if m is None or m.steady_state == 0.0:
                continue
            t = r.run.time_s - r.step.t0_s
            y = r.run.channels[chan]
            y0 = float(np.mean(y[t < 0])) if np.any(t < 0) else float(y[0])
            sel = (t > -0.5) & (t < 4.0)
            ax.plot(t[sel], (y[sel] - y0) / m.steady_state, color=f"C{k}", lw=1.5,
                    label=f"{r.name} ({r.law})")
            if m.response_time_s is not None:
                ax.plot(m.response_time_s, 0.9, "o", color=f"C{k}", ms=5)
            if m.peak_response_time_s is not None and m.overshoot is not None:
                ax.plot(m.peak_response_time_s, 1 + m.overshoot, "v", color=f"C{k}", ms=6)
        ax.axhline(1.0, color="0.5", lw=0.8)
        ax.axhline(0.9, color="0.5", lw=0.6, ls=":")
        ax.axvline(0.0, color="0.5", lw=0.6, ls=":")
        ax.set_title(title, loc="left", fontweight="bold")
        ax.set_xlabel("time from 50 % steer (s)")
    axes[0].set_ylabel("response / steady state")
    axes[0].legend(loc="lower right")
    fig.suptitle("ISO 7401 step response, normalized by the steady state "
                 "(○ 90 % response time, ▽ peak)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def plot_steady_state(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """ISO 4138 curves: steer, sideslip and roll vs lateral acceleration with the fits."""
    steady = [r for r in runs if r.steady is not None]
    if not steady:
        return None
    plt = _plt()
    panels = (("steer_rad", "front road-wheel angle δf", "steer_gradient_rad_per_mps2"),
              ("sideslip_rad", "sideslip β", "sideslip_gradient_rad_per_mps2"),
              ("roll_rad", "roll φ", "roll_gradient_rad_per_mps2"))
    fig, axes = plt.subplots(1, 3, figsize=(12, 4))
    for ax, (key, title, grad) in zip(axes, panels):
        for k, r in enumerate(steady):
            c = r.steady.curves
            if key not in c:
                continue
            ax.plot(c["ay_mps2"], np.degrees(c[key]), ".", ms=2, color=f"C{k}", alpha=0.5)
            g = getattr(r.steady, grad)
            if g is not None:
                ay = np.linspace(min(c["ay_mps2"]), max(c["ay_mps2"]), 2)
                fit = np.polyfit(c["ay_mps2"], c[key], 1)
                ax.plot(ay, np.degrees(np.polyval(fit, ay)), color=f"C{k}", lw=1.5,
                        label=f"{r.name}: {math.degrees(g):.3f} deg/(m/s²)")
        ax.set_title(title, loc="left", fontweight="bold")
        ax.set_xlabel("lateral acceleration (m/s²)")
        ax.set_ylabel("deg")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def plot_eigenvalues(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Eigenvalues, one panel per law: the 8-DOF linearized vs speed (coloured by speed),
    the linear models at the run speed and the eigenvalues identified from each run."""
    usable = [r for r in runs if r.eig_sweep is not None or r.modes is not None or r.models]
    if not usable:
        return None
    groups: dict[str, list[RunAnalysis]] = {}
    for r in usable:
        groups.setdefault(r.law, []).append(r)
    plt = _plt()
    n = len(groups)
    fig, axes = plt.subplots(1, n, figsize=(6.2 * n + 1.2, 5.2), squeeze=False)
    markers = {"2dof": "s", "3dof": "D", "8dof-lin": "^"}
    sc = None
    for ax, (law, members) in zip(axes[0], groups.items()):
        first = members[0]
        if first.eig_sweep is not None:
            ev = first.eig_sweep.eigenvalues
            speeds = np.repeat(first.eig_sweep.speed_mps[:, None], ev.shape[1], axis=1)
            ok = np.isfinite(ev) & (ev.real > -EIG_PLOT_MIN_REAL)
            sc = ax.scatter(ev.real[ok], ev.imag[ok], c=speeds[ok], cmap="viridis", s=14,
                            vmin=min(first.eig_sweep.speed_mps),
                            vmax=max(first.eig_sweep.speed_mps),
                            label="8-DOF linearized vs speed")
        for name, m in first.models.items():
            e = m.eigenvalues
            e = e[(np.abs(e) > 1e-6) & (e.real > -EIG_PLOT_MIN_REAL)]
            ax.plot(e.real, e.imag, markers.get(name, "o"), mfc="none", mec="k", ms=9,
                    label=f"{name} at {first.speed_mps:.1f} m/s")
        for k, r in enumerate(members):
            if r.modes is not None:
                e = r.modes.eigenvalues
                e = e[e.real > -EIG_PLOT_MIN_REAL]
                ax.plot(e.real, e.imag, "x", color=f"C{k + 1}", ms=11, mew=2.2,
                        label=f"identified: {r.name}")
        ax.axvline(0.0, color="k", lw=0.8)
        ax.set_xlabel("real part (1/s)")
        ax.set_title(f"law {law}", loc="left", fontweight="bold")
        ax.legend(loc="upper left", fontsize=7)
    axes[0][0].set_ylabel("imaginary part (rad/s)")
    if sc is not None:
        fig.colorbar(sc, ax=list(axes[0]), label="speed (m/s)", fraction=0.03)
    fig.suptitle("Eigenvalues of the lateral, yaw and roll modes (faster than "
                 f"-{EIG_PLOT_MIN_REAL:g} 1/s left out)", fontsize=10)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return path


def _fmt(value: Any, digits: int = 4) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "–"
        return f"{value:.{digits}g}"
    return html.escape(str(value))


def _metrics_table(runs: Sequence[RunAnalysis]) -> str:
    """Rows: metrics; columns: runs."""
    rows: list[tuple[str, list[Any]]] = []

    def add(label: str, getter: Callable[[RunAnalysis], Any]) -> None:
        values = []
        for r in runs:
            try:
                values.append(getter(r))
            except (AttributeError, KeyError, TypeError):
                values.append(None)
        if any(v is not None for v in values):
            rows.append((label, values))

    add("maneuver", lambda r: r.run.maneuver)
    add("law", lambda r: r.law)
    add("speed (m/s)", lambda r: r.speed_mps)
    for chan, title, unit in BODE_OUTPUTS:
        key = f"{chan}/front_wheel_angle_rad"
        add(f"{title}: steady-state gain ({unit})",
            lambda r, k=key: r.frequency_metrics[k].steady_state_gain)
        add(f"{title}: resonance peak / steady state",
            lambda r, k=key: r.frequency_metrics[k].resonance_ratio)
        add(f"{title}: resonance frequency (Hz)",
            lambda r, k=key: r.frequency_metrics[k].resonance_freq_hz)
        add(f"{title}: phase lag at 1 Hz (deg)",
            lambda r, k=key: r.frequency_metrics[k].phase_lag_1hz_deg)
        add(f"{title}: −3 dB bandwidth (Hz)",
            lambda r, k=key: r.frequency_metrics[k].bandwidth_hz)
    for chan, title in (("yaw_rate_radps", "yaw rate"), ("lateral_accel_mps2", "a_y")):
        add(f"step {title}: response time (s)",
            lambda r, c=chan: r.step.responses[c].response_time_s)
        add(f"step {title}: peak response time (s)",
            lambda r, c=chan: r.step.responses[c].peak_response_time_s)
        add(f"step {title}: overshoot (%)",
            lambda r, c=chan: None if r.step.responses[c].overshoot is None
            else 100 * r.step.responses[c].overshoot)
        add(f"step {title}: steady-state gain (per rad δf)",
            lambda r, c=chan: r.step.responses[c].steady_state_gain)
    add("TB factor (s·deg)", lambda r: r.step.tb_factor_s_deg)
    add("understeer gradient (deg/(m/s²))",
        lambda r: math.degrees(r.steady.understeer_gradient_rad_per_mps2))
    add("sideslip gradient (deg/(m/s²))",
        lambda r: math.degrees(r.steady.sideslip_gradient_rad_per_mps2))
    add("roll gradient (deg/(m/s²))", lambda r: math.degrees(r.steady.roll_gradient_rad_per_mps2))
    add("characteristic speed (m/s)", lambda r: r.steady.characteristic_speed_mps)
    add("critical speed (m/s)", lambda r: r.steady.critical_speed_mps)
    add("identified eigenvalues (1/s)", lambda r: ", ".join(
        f"{e.real:.3f}{e.imag:+.3f}j" for e in r.modes.eigenvalues))
    for name in ("2dof", "3dof", "8dof-lin"):
        add(f"{name} model eigenvalues (1/s)", lambda r, n=name: ", ".join(
            f"{e.real:.3f}{e.imag:+.3f}j" for e in r.models[n].eigenvalues
            if abs(e) > 1e-6 and e.real > -40))
    # the same models as the controller closes them: command held over its period
    add("law's control period T (s)",
        lambda r: next((v.period_s for v in r.sampled.values()), None))
    for name in ("2dof", "3dof", "8dof-lin"):
        add(f"{name} sampled at T: ln(z)/T (1/s)", lambda r, n=name: ", ".join(
            f"{e.real:.3f}{e.imag:+.3f}j" for e in r.sampled[n].s_plane
            if abs(e) > 1e-6 and e.real > -40))
        add(f"{name} sampled at T: largest |z| (modes with s ≠ 0)",
            lambda r, n=name: r.sampled[n].radius(1e-6))
    head = "".join(f"<th>{html.escape(r.name)}</th>" for r in runs)
    body = "".join(f"<tr><td>{html.escape(label)}</td>"
                   + "".join(f"<td>{_fmt(v)}</td>" for v in values) + "</tr>"
                   for label, values in rows)
    return f"<table><tr><th>metric</th>{head}</tr>{body}</table>"


_CSS = """body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1200px;color:#222}
h1{font-size:1.5em}h2{font-size:1.15em;margin-top:1.8em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;font-size:.85em}td,th{border:1px solid #ddd;padding:3px 8px;
text-align:right}td:first-child,th:first-child{text-align:left}
tr:nth-child(even){background:#f7f7f7}
img{max-width:100%;border:1px solid #eee;margin:.5em 0}.note{color:#775;font-size:.85em}"""


def write_report(runs: Sequence[RunAnalysis], out_dir: str | Path,
                 failures: dict[str, str] | None = None,
                 progress: Progress | None = None) -> Path:
    """Write ``index.html``, the PNG plots and ``metrics.json`` into ``out_dir``.

    Parameters
    ----------
    runs : sequence of RunAnalysis
    out_dir : str or Path
        Folder (created if needed).
    failures : dict of str to str, optional
        Bags that could not be read -> why (listed in the report and the JSON).

    Returns
    -------
    Path
        The ``index.html``.
    """
    tick = progress or (lambda _msg: None)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sections: list[tuple[str, Path | None, str]] = []
    plots = (("Time histories", plot_time_histories, "time_histories.png",
              "Overlaid runs; time from the start of each record."),
             ("Frequency response", plot_bode, "bode.png",
              "Measured H1 estimate (solid) over the analytic 2-DOF/3-DOF models closed with "
              "the run's law and the 8-DOF linearized at the run's straight-running trim."),
             ("ISO 7401 step response", plot_step, "step.png", ""),
             ("ISO 4138 steady-state handling", plot_steady_state, "steady_state.png", ""),
             ("Stability: eigenvalues", plot_eigenvalues, "eigenvalues.png",
              "One panel per law. Modes faster than -40 1/s (wheel spin, tire lag, actuator) "
              "are left out; an eigenvalue right of the axis is an unstable mode."))
    if runs:
        # time histories: one figure per maneuver, so a 60 s sweep does not flatten a 5 s step
        groups: dict[str, list[RunAnalysis]] = {}
        for r in runs:
            groups.setdefault(r.run.maneuver or "unrecognized", []).append(r)
        for man, members in groups.items():
            tick(f"plot time histories {man}")
            sections.append((f"Time histories: {man}",
                             plot_time_histories(members, out / f"time_histories_{man}.png"),
                             "Overlaid runs; time from the start of each record; angles as "
                             "applied (front includes roll steer)."))
        for title, fn, fname, caption in plots[1:]:
            tick(f"plot {fname}")
            sections.append((title, fn(runs, out / fname), caption))
    metrics = {"runs": {r.name: r.metrics() for r in runs}, "failed_bags": dict(failures or {})}
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>fourws analysis</title>"
             f"<style>{_CSS}</style></head><body><h1>fourws: analysis of "
             f"{len(runs)} recorded run(s)</h1>"]
    if failures:
        parts.append("<h2>Bags that could not be analysed</h2><ul>" + "".join(
            f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in failures.items())
            + "</ul>")
    if runs:
        parts.append("<h2>Metrics</h2>" + _metrics_table(runs))
    for title, png, caption in sections:
        if png is None:
            continue
        parts.append(f"<h2>{html.escape(title)}</h2><p class='note'>{html.escape(caption)}</p>"
                     f"<img src='{png.name}' alt='{html.escape(title)}'>")
    for r in runs:
        if r.unavailable or r.notes:
            parts.append(f"<h2>Not computed for {html.escape(r.name)}</h2><ul>" + "".join(
                f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>"
                for k, v in r.unavailable.items()) + "".join(
                f"<li>{html.escape(n)}</li>" for n in r.notes) + "</ul>")
    parts.append("<p class='note'>Every metric is also in <a href='metrics.json'>"
                 "metrics.json</a>.</p></body></html>")
    index = out / "index.html"
    index.write_text("\n".join(parts))
    return index
