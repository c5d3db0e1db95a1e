# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The report's figures (matplotlib, Agg): ``figure_*`` build a figure from
:class:`~fourws_analysis.compare.RunAnalysis` results (tests inspect what is drawn),
``plot_*`` save it as PNG. One colour per run in every figure; legends sit outside the
plotting areas; phase curves are never joined across a jump.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from fourws_analysis import units
from fourws_analysis.compare import RunAnalysis
from fourws_analysis.frequency import (COHERENCE_MIN, break_phase_jumps, display_phase_deg,
                                       model_response)
from fourws_analysis.report_texts import (MODEL_NAMES, common_ratio, law_groups, run_label,
                                          stability_notes)

#: Time-history panels: channel, label, scale to display unit, unit.
HISTORY_PANELS = (
    ("yaw_rate_radps", "yaw rate r", math.degrees(1.0), "deg/s"),
    ("lateral_accel_mps2", "lateral acceleration a_y", 1.0, "m/s²"),
    ("sideslip_rad", "sideslip β", math.degrees(1.0), "deg"),
    ("roll_rad", "roll φ", math.degrees(1.0), "deg"),
    ("front_wheel_angle_rad", "front road-wheel angle δf", math.degrees(1.0), "deg"),
    ("rear_wheel_angle_rad", "rear road-wheel angle δr (applied)", math.degrees(1.0), "deg"),
)
#: Model gains are drawn no lower than this below the lowest trusted measured gain, dB.
GAIN_FLOOR_BELOW_DB = 20.0
#: Eigenvalues with real part below minus this (wheel spin, tire lag, actuator) are not drawn.
EIG_PLOT_MIN_REAL = 40.0
#: Line style and eigenvalue marker of each model overlay.
_MODEL_STYLES = {"2dof": "--", "3dof": ":", "8dof-lin": "-."}
_EIG_MARKERS = {"2dof": "s", "3dof": "D", "8dof-lin": "^"}


def _plt() -> Any:
    import matplotlib  # matplotlib: about 0.5 s to load, only the plots need it

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: about 0.5 s to load, only the plots need it

    plt.rcParams.update({"figure.dpi": 110, "axes.grid": True, "grid.alpha": 0.3,
                         "axes.spines.top": False, "axes.spines.right": False,
                         "font.size": 9, "legend.fontsize": 8, "legend.framealpha": 0.8})
    return plt


def _colors(runs: Sequence[RunAnalysis]) -> dict[str, str]:
    """One colour per run, the same in every figure."""
    return {r.name: f"C{k % 10}" for k, r in enumerate(runs)}


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt  # matplotlib: about 0.5 s to load, only the plots need it

    fig.savefig(path)
    plt.close(fig)
    return path


# Margins of the figures laid out by :func:`_fixed_layout`, inches, for the 9-point text of
# :func:`_plt` (tick labels of at most about six characters: matplotlib's default formatter
# moves larger magnitudes into an offset text).
#: Left of an axes with tick labels and a y label.
_Y_LABELS_IN = 0.75
#: Under an axes with tick labels and an x label.
_X_LABELS_IN = 0.5
#: Above an axes: its title.
_TITLE_IN = 0.3
#: A row of a figure legend (8 points), and the legend's padding.
_LEGEND_ROW_IN = 0.2
_LEGEND_PAD_IN = 0.15
#: The figure's title (suptitle).
_SUPTITLE_IN = 0.25
#: The figure's right edge.
_RIGHT_IN = 0.2
#: A line of a 9-point title.
_TITLE_LINE_IN = 0.16
#: A character of the 10-point figure title (wrapped to the figure's width), of an 8-point
#: legend label, and a legend entry's marker and spacing.
_SUPTITLE_CHAR_IN, _LEGEND_CHAR_IN, _LEGEND_ENTRY_IN = 0.085, 0.065, 0.8
#: A colour bar right of the axes: its gap, its width, and the space right of it (tick
#: labels and label).
_COLORBAR_GAP_IN, _COLORBAR_IN, _COLORBAR_LABELS_IN = 0.2, 0.15, 0.65


def _legend_rows(n_labels: int, ncol: int) -> int:
    return max(1, math.ceil(n_labels / max(1, ncol)))


def _legend_columns(fig: Any, labels: Sequence[str], most: int) -> int:
    """Columns of a figure legend of ``labels``: at most ``most``, and as many as fit the
    figure's width (a legend wider than the figure is cut at both edges)."""
    widest = max((len(label) for label in labels), default=0)
    fit = int(fig.get_size_inches()[0] // (_LEGEND_ENTRY_IN + widest * _LEGEND_CHAR_IN))
    return max(1, min(most, len(labels), fit))


def _fixed_layout(fig: Any, nrows: int, ncols: int, *, top_in: float, bottom_in: float,
                  row_gap_in: float, col_gap_in: float, left_in: float = _Y_LABELS_IN,
                  right_in: float = _RIGHT_IN) -> None:
    """Place a grid of ``nrows`` x ``ncols`` axes with margins and gaps given in inches.

    What a figure of a fixed arrangement needs around its axes (titles, labels, a legend
    outside) is known from its text sizes, so it is set here instead of measured:
    matplotlib's constrained layout measures every axes' text on each draw, which doubled
    the time to save the report's time histories (0.76-1.26 s against 0.42-0.63 s here)."""
    w, h = fig.get_size_inches()
    left, right = left_in / w, 1.0 - right_in / w
    bottom, top = bottom_in / h, 1.0 - top_in / h
    ax_w = (w * (right - left) - (ncols - 1) * col_gap_in) / ncols
    ax_h = (h * (top - bottom) - (nrows - 1) * row_gap_in) / nrows
    fig.subplots_adjust(left=left, right=right, bottom=bottom, top=top,
                        wspace=col_gap_in / ax_w, hspace=row_gap_in / ax_h)


def _masked(values: np.ndarray, mask: np.ndarray) -> np.ndarray:
    out = np.array(values, dtype=float)
    out[mask] = np.nan
    return out


def figure_time_histories(runs: Sequence[RunAnalysis]) -> Any:
    """Overlaid time histories (yaw rate, a_y, sideslip, roll, front and rear angles)."""
    plt = _plt()
    colors = _colors(runs)
    fig, axes = plt.subplots(3, 2, figsize=(11, 8.4), sharex=True)
    for ax, (chan, label, scale, unit) in zip(axes.flat, HISTORY_PANELS):
        for r in runs:
            y = r.run.channels.get(chan)
            if y is None:
                continue
            t = r.run.time_s - r.run.time_s[0]
            ax.plot(t, y * scale, lw=1.3, color=colors[r.name], label=run_label(r))
            cmd = r.run.channels.get("front_wheel_angle_cmd_rad")
            if chan == "front_wheel_angle_rad" and cmd is not None:
                ax.plot(t, cmd * scale, lw=1.0, ls="--", color=colors[r.name])
        ax.set_title(label, loc="left", fontweight="bold")
        ax.set_ylabel(unit)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    if any("front_wheel_angle_cmd_rad" in r.run.channels for r in runs):
        # matplotlib: about 0.5 s to load, only the plots need it
        from matplotlib.lines import Line2D

        handles += [Line2D([], [], color="k", lw=1.3), Line2D([], [], color="k", ls="--")]
        labels += ["δf applied (roll steer included)", "δf commanded by the driver"]
    ncol = _legend_columns(fig, labels, 6)
    rows = _legend_rows(len(labels), ncol)
    h = fig.get_size_inches()[1]
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 1.0 - 0.05 / h),
               ncol=ncol, frameon=False)
    # (the inner panels show no x tick labels: sharex)
    _fixed_layout(fig, 3, 2, top_in=_LEGEND_PAD_IN + rows * _LEGEND_ROW_IN + _TITLE_IN,
                  bottom_in=_X_LABELS_IN, row_gap_in=_TITLE_IN + 0.1,
                  col_gap_in=_Y_LABELS_IN)
    return fig


def plot_time_histories(runs: Sequence[RunAnalysis], path: Path) -> Path:
    """Save :func:`figure_time_histories` to ``path``."""
    return _save(figure_time_histories(runs), path)


def _limits(values: list[np.ndarray], pad_fraction: float, min_pad: float
            ) -> tuple[float, float] | None:
    finite = [v[np.isfinite(v)] for v in values if np.size(v)]
    finite = [v for v in finite if v.size]
    if not finite:
        return None
    lo = min(float(v.min()) for v in finite)
    hi = max(float(v.max()) for v in finite)
    pad = max(min_pad, pad_fraction * (hi - lo))
    return lo - pad, hi + pad


def _frequency_ticks(ax: Any) -> None:
    """Plain-number frequency ticks at 1, 2, 5 per decade (no crowded minor labels when the
    band spans little more than a decade)."""
    # matplotlib: about 0.5 s to load, only the plots need it
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    ax.xaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())


def figure_bode(runs: Sequence[RunAnalysis]) -> Any | None:
    """Gain, phase and coherence per output, per front road-wheel angle δf; measured (solid,
    faded where not trusted) over the model responses (one line style per model).

    Phases are drawn as :func:`~fourws_analysis.frequency.display_phase_deg` gives them and
    never joined across a jump (:func:`~fourws_analysis.frequency.break_phase_jumps`); a
    model's phase is left out where its gain is below the drawn floor (a zero gain has no
    phase). The axis limits follow the trusted points and the models, so the faded points
    (an input zero can put them 300 dB up) do not squash the curves. The right gain axis
    reads the same curves per steering-wheel angle δH when the runs share one steering
    ratio.
    """
    road = units.ROAD_WHEEL.channel
    outputs = [o for o in units.OUTPUTS.values()
               if any(f"{o.channel}/{road}" in r.frequency for r in runs)]
    if not outputs:
        return None
    from matplotlib.lines import Line2D  # matplotlib: about 0.5 s to load, only the plots need it

    plt = _plt()
    colors = _colors(runs)
    fig, axes = plt.subplots(3, len(outputs), figsize=(4.4 * len(outputs), 9.2), sharex=True,
                             gridspec_kw={"height_ratios": [3, 3, 1.3]}, squeeze=False,
                             layout="constrained")
    fr_runs = [r for r in runs if any(f"{o.channel}/{road}" in r.frequency for o in outputs)]
    ratio = common_ratio(fr_runs)
    used_models: set[str] = set()
    for col, out in enumerate(outputs):
        ax_g, ax_p, ax_c = axes[:, col]
        key = f"{out.channel}/{road}"
        members = [r for r in runs if key in r.frequency]
        trusted_db = [r.frequency[key].gain_db[r.frequency[key].trusted()
                                               & (r.frequency[key].freq_hz > 0.0)]
                      for r in members]
        floor_db = min((float(np.nanmin(g)) for g in trusted_db if g.size),
                       default=-100.0) - GAIN_FLOOR_BELOW_DB
        gains: list[np.ndarray] = list(trusted_db)
        phases: list[np.ndarray] = []
        for r in members:
            fr = r.frequency[key]
            color = colors[r.name]
            pos = fr.freq_hz > 0.0  # the 0 Hz point of a transient estimate is off the axis
            ok = fr.trusted() & pos
            phase = display_phase_deg(fr)
            phases.append(phase[ok])
            for mask, lw, alpha in ((ok, 1.8, 1.0), (~ok & pos, 0.8, 0.3)):
                ax_g.semilogx(fr.freq_hz, _masked(fr.gain_db, ~mask), color=color, lw=lw,
                              alpha=alpha)
                ax_p.semilogx(*break_phase_jumps(fr.freq_hz, _masked(phase, ~mask)),
                              color=color, lw=lw, alpha=alpha)
            if fr.coherence is not None:
                ax_c.semilogx(fr.freq_hz, _masked(fr.coherence, ~pos), color=color, lw=1.2)
            for name, system in r.models.items():
                if out.channel not in system.output_labels:
                    continue
                f_pos = fr.freq_hz[pos]
                f = np.geomspace(max(float(f_pos[0]), 0.02), float(f_pos[-1]), 300)
                model = model_response(system, out.channel, f)
                style = _MODEL_STYLES.get(name, "--")
                used_models.add(name)
                # a model whose gain is zero (e.g. sideslip under a zero-sideslip law) would
                # squash the axis to -300 dB: it is drawn at the floor, without a phase
                gain = np.maximum(model.gain_db, floor_db)
                ax_g.semilogx(f, gain, style, color=color, lw=1.2)
                ph = _masked(model.phase_deg, model.gain_db < floor_db)
                ax_p.semilogx(*break_phase_jumps(f, ph), style, color=color, lw=1.2)
                gains.append(gain)
                phases.append(ph)
        for ax, vals, pad, min_pad in ((ax_g, gains, 0.06, 3.0), (ax_p, phases, 0.06, 10.0)):
            lims = _limits(vals, pad, min_pad)
            if lims is not None:
                ax.set_ylim(*lims)
        ax_g.set_title(f"{out.label} {out.symbol} / δf", loc="left", fontweight="bold")
        ax_g.set_ylabel(f"gain, dB re 1 {out.gain_unit} of δf")
        if ratio is not None:
            off = 20.0 * math.log10(ratio)
            sec = ax_g.secondary_yaxis("right", functions=(lambda d, o=off: d - o,
                                                           lambda d, o=off: d + o))
            sec.set_ylabel(f"dB re 1 {out.gain_unit} of δH", fontsize=8)
        ax_p.set_ylabel("phase (deg)")
        ax_c.set_ylabel("coherence")
        ax_c.axhline(COHERENCE_MIN, color="0.5", lw=0.8, ls=":")
        ax_c.set_ylim(0, 1.05)
        ax_c.set_xlabel("frequency (Hz)")
        _frequency_ticks(ax_c)
    handles = [Line2D([], [], color=colors[r.name], lw=2.0) for r in fr_runs]
    labels = [run_label(r) for r in fr_runs]
    handles.append(Line2D([], [], color="k", lw=1.8))
    labels.append(f"measured (faded: coherence < {COHERENCE_MIN} or input not excited)")
    for name in ("2dof", "3dof", "8dof-lin"):
        if name in used_models:
            handles.append(Line2D([], [], color="k", lw=1.2, ls=_MODEL_STYLES[name]))
            labels.append(MODEL_NAMES[name])
    fig.legend(handles, labels, loc="outside lower center", ncol=min(4, len(labels)),
               frameon=False)
    per_hand = (f"; right axes: per steering-wheel angle δH = {ratio:g} δf "
                f"({20 * math.log10(ratio):.1f} dB lower)" if ratio is not None else "")
    fig.suptitle("Frequency response per commanded front road-wheel angle δf (left axes)"
                 + per_hand, fontsize=10)
    return fig


def plot_bode(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Save :func:`figure_bode` to ``path`` (None when no run has a frequency response)."""
    fig = figure_bode(runs)
    return None if fig is None else _save(fig, path)


def figure_step(runs: Sequence[RunAnalysis]) -> Any | None:
    """Step responses normalized by their steady state, with ISO 7401 markers."""
    steps = [r for r in runs if r.step is not None]
    if not steps:
        return None
    plt = _plt()
    colors = _colors(runs)
    chans = (("yaw_rate_radps", "yaw rate r"), ("lateral_accel_mps2", "lateral acceleration a_y"))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4), sharey=True)
    for ax, (chan, title) in zip(axes, chans):
        for r in steps:
            m = r.step.responses.get(chan)
            if m is None or m.steady_state == 0.0:
                continue
            color = colors[r.name]
            t = r.run.time_s - r.step.t0_s
            y = r.run.channels[chan]
            y0 = float(np.mean(y[t < 0])) if np.any(t < 0) else float(y[0])
            sel = (t > -0.5) & (t < 4.0)
            ax.plot(t[sel], (y[sel] - y0) / m.steady_state, color=color, lw=1.5,
                    label=run_label(r))
            if m.response_time_s is not None:
                ax.plot(m.response_time_s, 0.9, "o", color=color, ms=5)
            if m.peak_response_time_s is not None and m.overshoot is not None:
                ax.plot(m.peak_response_time_s, 1 + m.overshoot, "v", color=color, ms=6)
        ax.axhline(1.0, color="0.5", lw=0.8)
        ax.axhline(0.9, color="0.5", lw=0.6, ls=":")
        ax.axvline(0.0, color="0.5", lw=0.6, ls=":")
        ax.set_title(title, loc="left", fontweight="bold")
        ax.set_xlabel("time from 50 % steer (s)")
    axes[0].set_ylabel("response / steady state")
    handles, labels = axes[0].get_legend_handles_labels()
    ncol = _legend_columns(fig, labels, 6)
    rows = _legend_rows(len(labels), ncol)
    fig.legend(handles, labels, loc="lower center", bbox_to_anchor=(0.5, 0.0), ncol=ncol,
               frameon=False)
    fig.suptitle("ISO 7401 step response, normalized by the steady state "
                 "(○ 90 % response time, ▽ peak)", fontsize=10)
    # (the right panel shows no y tick labels: sharey)
    _fixed_layout(fig, 1, 2, top_in=_SUPTITLE_IN + _TITLE_IN,
                  bottom_in=_X_LABELS_IN + rows * _LEGEND_ROW_IN + 0.05,
                  row_gap_in=0.0, col_gap_in=0.3)
    return fig


def plot_step(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Save :func:`figure_step` to ``path`` (None when no run is a step)."""
    fig = figure_step(runs)
    return None if fig is None else _save(fig, path)


def figure_steady_state(runs: Sequence[RunAnalysis]) -> Any | None:
    """ISO 4138 curves: steer, sideslip and roll vs lateral acceleration with the fits; the
    fitted gradients in a legend under each panel."""
    steady = [r for r in runs if r.steady is not None]
    if not steady:
        return None
    plt = _plt()
    colors = _colors(runs)
    panels = (("steer_rad", "front road-wheel angle δf (commanded)",
               "steer_gradient_rad_per_mps2"),
              ("sideslip_rad", "sideslip β", "sideslip_gradient_rad_per_mps2"),
              ("roll_rad", "roll φ", "roll_gradient_rad_per_mps2"))
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.8), layout="constrained")
    for ax, (key, title, grad) in zip(axes, panels):
        for r in steady:
            c = r.steady.curves
            if key not in c:
                continue
            color = colors[r.name]
            ax.plot(c["ay_mps2"], np.degrees(c[key]), ".", ms=2, color=color, alpha=0.5)
            g = getattr(r.steady, grad)
            if g is not None:
                ay = np.linspace(min(c["ay_mps2"]), max(c["ay_mps2"]), 2)
                fit = np.polyfit(c["ay_mps2"], c[key], 1)
                ax.plot(ay, np.degrees(np.polyval(fit, ay)), color=color, lw=1.5,
                        label=f"{run_label(r)}: {math.degrees(g):.3f} deg/(m/s²)")
        ax.set_title(title, loc="left", fontweight="bold")
        ax.set_xlabel("lateral acceleration (m/s²)")
        ax.set_ylabel("deg")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), frameon=False)
    return fig


def plot_steady_state(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Save :func:`figure_steady_state` to ``path`` (None without a steady-state run)."""
    fig = figure_steady_state(runs)
    return None if fig is None else _save(fig, path)


def figure_eigenvalues(runs: Sequence[RunAnalysis]) -> Any | None:
    """Eigenvalues, one panel per law: the 8-DOF linearized vs speed (coloured by speed),
    the linear models at the run speed and the eigenvalues identified from each run. The
    right half-plane is shaded; each panel's title says whether a mode lies there
    (:func:`stability_notes`); one legend under the panels."""
    groups = law_groups(runs)
    if not groups:
        return None
    from matplotlib.lines import Line2D  # matplotlib: about 0.5 s to load, only the plots need it

    plt = _plt()
    colors = _colors(runs)
    n = len(groups)
    fig, axes = plt.subplots(1, n, figsize=(5.6 * n + 1.2, 5.6), squeeze=False)
    sc = None
    title_lines = 1
    handles: dict[str, Any] = {}
    for ax, (law, members) in zip(axes[0], groups.items()):
        first = members[0]
        reals: list[float] = [0.0]
        if first.eig_sweep is not None:
            ev = first.eig_sweep.eigenvalues
            speeds = np.repeat(first.eig_sweep.speed_mps[:, None], ev.shape[1], axis=1)
            ok = np.isfinite(ev) & (ev.real > -EIG_PLOT_MIN_REAL)
            sc = ax.scatter(ev.real[ok], ev.imag[ok], c=speeds[ok], cmap="viridis", s=14,
                            vmin=min(first.eig_sweep.speed_mps),
                            vmax=max(first.eig_sweep.speed_mps))
            reals.extend(ev.real[ok].tolist())
            handles["8-DOF linearized vs speed (colour: speed)"] = Line2D(
                [], [], ls="", marker="o", ms=5, color="tab:green")
        for name, m in first.models.items():
            e = m.poles()
            e = e[(np.abs(e) > 1e-6) & (e.real > -EIG_PLOT_MIN_REAL)]
            marker = _EIG_MARKERS.get(name, "o")
            ax.plot(e.real, e.imag, marker, mfc="none", mec="k", ms=9)
            reals.extend(e.real.tolist())
            handles[f"{MODEL_NAMES.get(name, name)} at the run speed"] = Line2D(
                [], [], ls="", marker=marker, mfc="none", mec="k", ms=8)
        for r in members:
            if r.modes is not None:
                e = r.modes.eigenvalues
                e = e[e.real > -EIG_PLOT_MIN_REAL]
                ax.plot(e.real, e.imag, "X", mfc=colors[r.name], mec="k", mew=0.8, ms=12)
                reals.extend(e.real.tolist())
                handles[f"identified from {run_label(r)}"] = Line2D(
                    [], [], ls="", marker="X", mfc=colors[r.name], mec="k", mew=0.8, ms=10)
        hi = max(reals)
        right = max(2.0, 1.15 * hi) if hi > 0 else 2.0
        ax.set_xlim(-EIG_PLOT_MIN_REAL - 1.0, right)
        ax.axvspan(0.0, right, color="tab:red", alpha=0.07, lw=0)
        ax.axvline(0.0, color="k", lw=0.8)
        ax.set_xlabel("real part (1/s)")
        headline = stability_notes(members)[0]
        # wrapped to the panel's width (~70 characters at 9 pt over 5.6 in)
        title = f"law {law}\n" + textwrap.fill(headline, 66)
        title_lines = max(title_lines, title.count("\n") + 1)
        ax.set_title(title, loc="left", fontsize=9, fontweight="bold",
                     color="tab:red" if headline.startswith("Unstable") else "k")
    axes[0][0].set_ylabel("imaginary part (rad/s)")
    # legend columns and the title's lines as wide as the figure (one panel is 6.8 in wide)
    w = fig.get_size_inches()[0]
    ncol = _legend_columns(fig, list(handles), 4)
    fig.legend(list(handles.values()), list(handles), loc="lower center",
               bbox_to_anchor=(0.5, 0.0), ncol=ncol, frameon=False)
    sup = textwrap.fill("Eigenvalues of the lateral, yaw and roll modes (shaded: right of the "
                        f"imaginary axis, unstable; faster than -{EIG_PLOT_MIN_REAL:g} 1/s left "
                        "out)", max(40, int(w / _SUPTITLE_CHAR_IN)))
    fig.suptitle(sup, fontsize=10)
    bar_in = _COLORBAR_GAP_IN + _COLORBAR_IN + _COLORBAR_LABELS_IN
    # (each panel has its own y tick labels, only the first a y label)
    _fixed_layout(fig, 1, n, top_in=(sup.count("\n") + 1) * _SUPTITLE_IN
                  + title_lines * _TITLE_LINE_IN + 0.12,
                  bottom_in=_X_LABELS_IN + _legend_rows(len(handles), ncol) * _LEGEND_ROW_IN
                  + 0.05, row_gap_in=0.0, col_gap_in=0.6,
                  right_in=bar_in if sc is not None else _RIGHT_IN)
    if sc is not None:
        box = axes[0][-1].get_position()
        cax = fig.add_axes((box.x1 + _COLORBAR_GAP_IN / w, box.y0, _COLORBAR_IN / w,
                            box.height))
        fig.colorbar(sc, cax=cax, label="speed (m/s)")
    return fig


def plot_eigenvalues(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Save :func:`figure_eigenvalues` to ``path`` (None when nothing has eigenvalues)."""
    fig = figure_eigenvalues(runs)
    return None if fig is None else _save(fig, path)


__all__ = ["EIG_PLOT_MIN_REAL", "GAIN_FLOOR_BELOW_DB", "HISTORY_PANELS", "figure_bode",
           "figure_eigenvalues", "figure_step", "figure_steady_state", "figure_time_histories",
           "plot_bode", "plot_eigenvalues", "plot_step", "plot_steady_state",
           "plot_time_histories"]
