"""Plots and the self-contained HTML report of analysed runs (matplotlib Agg).

The analysis layer (:mod:`fourws_analysis.compare`) returns result objects; this module turns
them into words, tables and figures. ``figure_*`` build a matplotlib figure (tests inspect what
is drawn), ``plot_*`` save it; :func:`reading_notes`, :func:`stability_notes` and
:func:`identification_notes` are the report's texts. :func:`write_report` writes
``DIR/index.html``, the PNG plots next to it and ``DIR/metrics.json`` with every metric.

What an engineer must know to read the numbers is said once, at the top of the report: which
front road-wheel angle δf the gains are per (the driver's command or the applied angle with
roll steer), that every gain is also given per steering-wheel angle δH = N δf, and whether
the laws are compared at equal steer or at equal lateral acceleration. Every table has a unit
column; gain units come from :mod:`fourws_analysis.units`.
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
from fourws_analysis.frequency import (COHERENCE_MIN, break_phase_jumps, display_phase_deg)
from fourws_analysis.iso4138 import LINEAR_RANGE_MPS2

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
#: A real part above this is "right of the imaginary axis" (1/s): the zero eigenvalues of
#: position and heading are removed before, and round-off of the others is ~1e-12.
UNSTABLE_REAL_PER_S = 1e-9
#: Line style and name of each model overlay.
_MODEL_STYLES = {"2dof": "--", "3dof": ":", "8dof-lin": "-."}
_MODEL_NAMES = {"2dof": "2-DOF model", "3dof": "3-DOF model", "8dof-lin": "8-DOF linearized"}
_EIG_MARKERS = {"2dof": "s", "3dof": "D", "8dof-lin": "^"}

Progress = Callable[[str], None]


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"figure.dpi": 110, "axes.grid": True, "grid.alpha": 0.3,
                         "axes.spines.top": False, "axes.spines.right": False,
                         "font.size": 9, "legend.fontsize": 8, "legend.framealpha": 0.8})
    return plt


def run_label(r: RunAnalysis) -> str:
    """Legend label of a run: its name, with the law added when the name does not hold it
    (``fws``, not ``fws (fws)``; ``step (sol1)``)."""
    return r.name if r.law in r.name else f"{r.name} ({r.law})"


def _colors(runs: Sequence[RunAnalysis]) -> dict[str, str]:
    """One colour per run, the same in every figure."""
    return {r.name: f"C{k % 10}" for k, r in enumerate(runs)}


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.savefig(path)
    plt.close(fig)
    return path


def _masked(values: np.ndarray, mask: np.ndarray) -> np.ndarray:
    out = np.array(values, dtype=float)
    out[mask] = np.nan
    return out


def _common_ratio(runs: Sequence[RunAnalysis]) -> float | None:
    """The steering ratio N shared by ``runs`` (None if unknown or different)."""
    ratios = {r.steering_ratio for r in runs}
    if len(ratios) != 1:
        return None
    return next(iter(ratios))


# -------------------------------------------------------------------------------- texts

def _deg(rad: float) -> str:
    return f"{math.degrees(rad):.3g} deg"


def reading_notes(runs: Sequence[RunAnalysis]) -> list[str]:
    """What the gains of ``runs`` are per and how the laws are compared (plain text).

    * the front road-wheel angle δf: commanded or applied (roll steer), with the applied /
      commanded ratio at the end of each step;
    * the steering-wheel angle δH = N δf beside it;
    * equal steer (the lateral acceleration then differs between laws: the spread is given)
      or equal lateral acceleration (the ISO 7401 way: the amplitudes found per law).
    """
    notes: list[str] = []
    if not runs:
        return notes
    commanded = [r for r in runs if r.steer_reference == "commanded"]
    applied = [r for r in runs if r.steer_reference == "applied"]
    ratio = _common_ratio(runs)
    hand = (f" and per rad of steering-wheel angle δH = N δf (steering ratio N = {ratio:g}; a "
            f"gain per δH is the gain per δf / N, {20 * math.log10(ratio):.1f} dB lower)"
            if ratio is not None else
            " and, where the steering ratio N is known, per rad of steering-wheel angle "
            "δH = N δf")
    if commanded:
        text = ("Every gain is per rad of the front road-wheel angle δf the driver commands "
                f"(/fourws/driver_input){hand}. The angle applied at the wheels "
                "(/fourws/state, solid in the time histories) also holds roll steer, which "
                "depends on the law")
        ratios = [f"{r.applied_to_commanded:.3g}× ({run_label(r)})" for r in commanded
                  if r.applied_to_commanded is not None]
        if ratios:
            text += (": at the end of the step it is " + ", ".join(ratios) + " the command; "
                     "gains per applied angle would be smaller by that factor")
        notes.append(text + ".")
    if applied:
        names = ", ".join(run_label(r) for r in applied)
        notes.append(f"{names}: no /fourws/driver_input in the bag, so the gains are per the "
                     "applied front angle (roll steer included)"
                     + (f"{hand}" if not commanded else "")
                     + (", not comparable with the per-command gains of the other runs"
                        if commanded else "") + ".")
    notes.extend(_comparison_notes(runs))
    return notes


def _comparison_notes(runs: Sequence[RunAnalysis]) -> list[str]:
    """Equal steer or equal lateral acceleration, for the step runs and for the frequency
    runs of ``runs``."""
    notes = _frequency_comparison(runs)
    steps = [r for r in runs if r.step is not None
             and "lateral_accel_mps2" in r.step.responses]
    if len(steps) < 2:
        return notes
    return _step_comparison(steps) + notes


def _frequency_comparison(runs: Sequence[RunAnalysis]) -> list[str]:
    """The a_y gains of frequency runs with the same input differ between laws: say by how
    much (steady-state gain per δf)."""
    key = f"lateral_accel_mps2/{units.ROAD_WHEEL.channel}"
    fr = {run_label(r): r.frequency_metrics[key].steady_state_gain for r in runs
          if key in r.frequency_metrics and r.frequency_metrics[key].steady_state_gain > 0}
    if len(fr) < 2:
        return []
    lo, hi = min(fr, key=fr.__getitem__), max(fr, key=fr.__getitem__)
    return [f"Frequency responses: a given steer gives each law its own lateral "
            f"acceleration; the steady-state a_y gain ranges from "
            f"{fr[lo]:.4g} (m/s²)/rad ({lo}) to {fr[hi]:.4g} (m/s²)/rad ({hi}), "
            f"×{fr[hi] / fr[lo]:.2f}."]


def _step_comparison(steps: Sequence[RunAnalysis]) -> list[str]:
    """Equal steer or equal lateral acceleration, for step runs (two or more)."""
    targets = [r.step_amplitude.get("target_lateral_accel_mps2") for r in steps]
    if all(t is not None for t in targets):
        amps = ", ".join(f"{_deg(abs(r.step.steer_step))} ({run_label(r)})" for r in steps)
        levels = sorted({float(t) for t in targets if t is not None})
        return [f"Step runs compared at equal steady lateral acceleration, the ISO 7401 way "
                f"(target {', '.join(f'{t:g}' for t in levels)} m/s²): the front road-wheel "
                f"amplitude was found per law before each run: {amps}."]
    ay = {run_label(r): abs(r.step.responses["lateral_accel_mps2"].steady_state)
          for r in steps}
    lo_name, hi_name = min(ay, key=ay.__getitem__), max(ay, key=ay.__getitem__)
    steer = sorted({round(math.degrees(abs(r.step.steer_step)), 3) for r in steps})
    how = (f"Step runs compared at equal steer (the same front road-wheel step, "
           f"{steer[0]:g} deg, for every law)" if len(steer) == 1 else
           "Step runs with given amplitudes (front road-wheel steps of "
           + ", ".join(f"{x:g}" for x in steer) + " deg)")
    spread = ay[hi_name] / ay[lo_name] if ay[lo_name] > 0 else math.inf
    return [f"{how}: the steady lateral "
            f"acceleration then differs between laws, from {ay[lo_name]:.3g} m/s² "
            f"({lo_name}) to {ay[hi_name]:.3g} m/s² ({hi_name}), ×{spread:.2f}, so the "
            "gains come from different points of the tires' curves. ISO 7401 compares at one "
            "steady lateral acceleration instead: give the step_steer maneuver "
            "target_lateral_accel_mps2 (scenario iso7401_step_4mps2) and each law's "
            "amplitude is found before its run."]


def _unstable(eig: np.ndarray) -> np.ndarray:
    eig = np.asarray(eig, dtype=complex)
    return eig[np.isfinite(eig) & (eig.real > UNSTABLE_REAL_PER_S)]


def _fmt_eigs(eigs: Sequence[complex]) -> str:
    """Eigenvalues as text, a complex pair once (``-2.87 ± 2.78j``), in 1/s."""
    parts: list[str] = []
    for e in eigs:
        e = complex(e)
        if abs(e.imag) < 1e-9:
            parts.append(f"{e.real:+.3g}")
        elif e.imag > 0:
            parts.append(f"{e.real:+.3g} ± {e.imag:.3g}j")
    return ", ".join(parts)


def stability_notes(members: Sequence[RunAnalysis]) -> list[str]:
    """Sentences on the modes right of the imaginary axis for one law's runs: the 8-DOF
    linearized over the speed sweep (the speeds where it is unstable), the linear models at
    the run speed and the identified eigenvalues. The first sentence is the headline (short
    enough for a panel title): it starts with ``Unstable`` when any mode lies right of the
    axis."""
    if not members:
        return []
    first = members[0]
    speed = first.speed_mps
    unstable: list[str] = []   # short: what is unstable at the run speed
    elsewhere = ""             # the sweep's unstable speeds
    details: list[str] = []
    sweep = first.eig_sweep
    if sweep is not None:
        ev = np.asarray(sweep.eigenvalues, dtype=complex)
        v = np.asarray(sweep.speed_mps, dtype=float)
        worst = np.array([np.nanmax(row.real) if np.any(np.isfinite(row)) else np.nan
                          for row in ev])
        bad = worst > UNSTABLE_REAL_PER_S
        if np.any(bad):
            k = int(np.nanargmax(worst))
            k0 = int(np.argmax(bad))
            where = (f"from {v[k0]:.3g} m/s ({v[k0] * 3.6:.0f} km/h) up" if np.all(bad[k0:])
                     else "at " + ", ".join(f"{x:.3g}" for x in v[bad]) + " m/s")
            elsewhere = f"8-DOF linearized {where}"
            details.append(f"8-DOF linearized over {v.min():.3g}-{v.max():.3g} m/s: a mode "
                           f"right of the imaginary axis {where}, largest real part "
                           f"{worst[k]:+.3g} 1/s at {v[k]:.3g} m/s.")
        else:
            details.append(f"8-DOF linearized: stable from {v.min():.3g} to {v.max():.3g} "
                           f"m/s (largest real part {np.nanmax(worst):+.3g} 1/s).")
    for name, system in first.models.items():
        bad_e = _unstable(system.eigenvalues)
        if bad_e.size:
            label = _MODEL_NAMES.get(name, name)
            unstable.append(f"{label} at {speed:.3g} m/s")
            details.append(f"{label} at {speed:.3g} m/s: eigenvalue(s) {_fmt_eigs(bad_e)} 1/s "
                           "right of the imaginary axis.")
    for r in members:
        if r.modes is not None and _unstable(r.modes.eigenvalues).size:
            unstable.append(f"identified from {run_label(r)}")
            details.append(f"Identified from {run_label(r)}: "
                           f"{_fmt_eigs(_unstable(r.modes.eigenvalues))} 1/s right of the "
                           "axis: the recorded run itself diverges.")
    if unstable:
        head = "Unstable: " + "; ".join(unstable) + "."
    elif elsewhere:
        head = f"Stable at {speed:.3g} m/s; unstable at other speeds: {elsewhere}."
    else:
        head = f"No mode right of the imaginary axis at {speed:.3g} m/s."
    return [head] + details


def identification_notes(runs: Sequence[RunAnalysis]) -> list[str]:
    """Why the identified eigenvalues differ from the models', with each run's numbers: the
    identified eigenvalues beside the slowest modes of the most complete model (the fit
    finds the dominant, slowest modes), and the run's peak lateral acceleration against the
    tires' near-linear range."""
    with_modes = [r for r in runs if r.modes is not None and r.models]
    if not with_modes:
        return []
    notes = ["The identified eigenvalues are a two-pole fit to the whole recorded response, "
             "not the eigenvalues of a linearization, so they differ from the models' for "
             "these reasons: (1) amplitude: the run works the tires at its own lateral "
             "acceleration, where saturation and the left/right load transfer lower the "
             "effective cornering stiffness below the straight-running value the models "
             "use; (2) lagged load transfer and more modes: in the 8-DOF the load transfer "
             "follows the roll motion with a lag, and roll, tire relaxation and the rear "
             "actuator add modes that a two-pole fit lumps together; (3) a law's actuator "
             "limits (angle, rate) act nonlinearly in a quick step; (4) the 2-DOF and 3-DOF "
             "models leave out roll steer and load transfer altogether."]
    for r in with_modes:
        model = "8dof-lin" if "8dof-lin" in r.models else next(iter(r.models))
        eig = np.asarray(r.models[model].eigenvalues, dtype=complex)
        eig = eig[np.abs(eig) > 1e-6]
        slowest = eig[np.argsort(-eig.real)]
        n_show = r.modes.eigenvalues.size + 1  # one mode more than the fit has
        shown = slowest[:n_show]
        if shown.size and abs(shown[-1].imag) > 1e-9 and n_show < slowest.size:
            shown = slowest[:n_show + 1] if np.isclose(slowest[n_show], shown[-1].conjugate()) \
                else shown
        ay = r.run.channels.get("lateral_accel_mps2")
        peak = float(np.max(np.abs(ay))) if ay is not None and ay.size else math.nan
        if peak > LINEAR_RANGE_MPS2:
            regime = (f"beyond the ~{LINEAR_RANGE_MPS2:g} m/s² of the tires' near-linear "
                      "range, so (1) weighs most")
        else:
            regime = (f"within the tires' near-linear range (< {LINEAR_RANGE_MPS2:g} m/s²), "
                      "so the differences come mostly from (2)-(4)")
        notes.append(f"{run_label(r)}: identified {_fmt_eigs(r.modes.eigenvalues)} 1/s; the "
                     f"slowest {_MODEL_NAMES.get(model, model)} modes at "
                     f"{r.speed_mps:.3g} m/s are {_fmt_eigs(shown)} 1/s; peak |a_y| "
                     f"{peak:.3g} m/s², {regime}.")
    return notes


# -------------------------------------------------------------------------------- figures

def figure_time_histories(runs: Sequence[RunAnalysis]) -> Any:
    """Overlaid time histories (yaw rate, a_y, sideslip, roll, front and rear angles)."""
    plt = _plt()
    colors = _colors(runs)
    fig, axes = plt.subplots(3, 2, figsize=(11, 8.4), sharex=True, layout="constrained")
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
        from matplotlib.lines import Line2D

        handles += [Line2D([], [], color="k", lw=1.3), Line2D([], [], color="k", ls="--")]
        labels += ["δf applied (roll steer included)", "δf commanded by the driver"]
    fig.legend(handles, labels, loc="outside upper center",
               ncol=min(6, max(1, len(labels))), frameon=False)
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
    from matplotlib.lines import Line2D

    plt = _plt()
    colors = _colors(runs)
    fig, axes = plt.subplots(3, len(outputs), figsize=(4.4 * len(outputs), 9.2), sharex=True,
                             gridspec_kw={"height_ratios": [3, 3, 1.3]}, squeeze=False,
                             layout="constrained")
    fr_runs = [r for r in runs if any(f"{o.channel}/{road}" in r.frequency for o in outputs)]
    ratio = _common_ratio(fr_runs)
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
                if out.channel not in system.C:
                    continue
                f_pos = fr.freq_hz[pos]
                f = np.geomspace(max(float(f_pos[0]), 0.02), float(f_pos[-1]), 300)
                model = system.response(out.channel, f)
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
            labels.append(_MODEL_NAMES[name])
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
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4), sharey=True, layout="constrained")
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
    fig.legend(handles, labels, loc="outside lower center", ncol=min(6, max(1, len(labels))),
               frameon=False)
    fig.suptitle("ISO 7401 step response, normalized by the steady state "
                 "(○ 90 % response time, ▽ peak)", fontsize=10)
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


def _law_groups(runs: Sequence[RunAnalysis]) -> dict[str, list[RunAnalysis]]:
    usable = [r for r in runs if r.eig_sweep is not None or r.modes is not None or r.models]
    groups: dict[str, list[RunAnalysis]] = {}
    for r in usable:
        groups.setdefault(r.law, []).append(r)
    return groups


def figure_eigenvalues(runs: Sequence[RunAnalysis]) -> Any | None:
    """Eigenvalues, one panel per law: the 8-DOF linearized vs speed (coloured by speed),
    the linear models at the run speed and the eigenvalues identified from each run. The
    right half-plane is shaded; each panel's title says whether a mode lies there
    (:func:`stability_notes`); one legend under the panels."""
    groups = _law_groups(runs)
    if not groups:
        return None
    from matplotlib.lines import Line2D

    plt = _plt()
    colors = _colors(runs)
    n = len(groups)
    fig, axes = plt.subplots(1, n, figsize=(5.6 * n + 1.2, 5.6), squeeze=False,
                             layout="constrained")
    sc = None
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
            e = m.eigenvalues
            e = e[(np.abs(e) > 1e-6) & (e.real > -EIG_PLOT_MIN_REAL)]
            marker = _EIG_MARKERS.get(name, "o")
            ax.plot(e.real, e.imag, marker, mfc="none", mec="k", ms=9)
            reals.extend(e.real.tolist())
            handles[f"{_MODEL_NAMES.get(name, name)} at the run speed"] = Line2D(
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
        ax.set_title(f"law {law}\n{headline}", loc="left", fontsize=9, fontweight="bold",
                     color="tab:red" if headline.startswith("Unstable") else "k", wrap=True)
    axes[0][0].set_ylabel("imaginary part (rad/s)")
    if sc is not None:
        fig.colorbar(sc, ax=list(axes[0]), label="speed (m/s)", fraction=0.03)
    fig.legend(list(handles.values()), list(handles), loc="outside lower center",
               ncol=min(4, max(1, len(handles))), frameon=False)
    fig.suptitle("Eigenvalues of the lateral, yaw and roll modes (shaded: right of the "
                 f"imaginary axis, unstable; faster than -{EIG_PLOT_MIN_REAL:g} 1/s left out)",
                 fontsize=10)
    return fig


def plot_eigenvalues(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Save :func:`figure_eigenvalues` to ``path`` (None when nothing has eigenvalues)."""
    fig = figure_eigenvalues(runs)
    return None if fig is None else _save(fig, path)


# -------------------------------------------------------------------------------- tables

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
        ]
    specs.append(("TB factor (peak time × steady sideslip)", "s·deg",
                  lambda r: r.step.tb_factor_s_deg))
    tables.append(("ISO 7401 step response", _collect(runs, specs)))

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
        specs.append((f"{_MODEL_NAMES[name]} at the run speed", "1/s",
                      lambda r, n=name: _eig_list(r.models[n].eigenvalues) or None))
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
    sections: list[tuple[str, Path | None, str, list[str]]] = []
    figures = (("Frequency response", plot_bode, "bode.png",
                "Measured H1 estimate (solid) over the analytic 2-DOF/3-DOF models closed "
                "with the run's law and the 8-DOF linearized at the run's straight-running "
                "trim; one colour per run, one line style per source. Phase lines are not "
                "joined across a jump of more than 90 deg (a wrap or a zero on the jω axis)."),
               ("ISO 7401 step response", plot_step, "step.png", ""),
               ("ISO 4138 steady-state handling", plot_steady_state, "steady_state.png", ""))

    def draw(fn: Callable[[Sequence[RunAnalysis], Path], Path | None],
             members: Sequence[RunAnalysis], fname: str) -> Path | None:
        tick(f"plot {fname}")
        return fn(members, out / fname) if plots else None

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
                     for law, members in _law_groups(runs).items()]
        eig_items += identification_notes(runs)
        sections.append(("Stability: eigenvalues",
                         draw(plot_eigenvalues, runs, "eigenvalues.png"),
                         "One panel per law. Modes faster than -40 1/s (wheel spin, tire lag, "
                         "actuator) are left out; a mode right of the imaginary axis "
                         "(shaded) is unstable.", eig_items))
    metrics = {"runs": {r.name: r.metrics() for r in runs}, "failed_bags": dict(failures or {})}
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>fourws analysis</title>"
             f"<style>{_CSS}</style></head><body><h1>fourws: analysis of "
             f"{len(runs)} recorded run(s)</h1>"]
    if runs:
        parts.append("<h2>How to read the numbers</h2>"
                     + _list_html(reading_notes(runs), "reading"))
    if failures:
        parts.append("<h2>Bags that could not be analysed</h2><ul>" + "".join(
            f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in failures.items())
            + "</ul>")
    if runs:
        parts.append("<h2>Metrics</h2>" + "".join(
            _table_html(title, rows, runs) for title, rows in metric_tables(runs)))
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
