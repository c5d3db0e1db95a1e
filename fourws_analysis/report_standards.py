"""The report's part for the regulation and standard tests (FMVSS No. 126 sine with dwell and
slowly increasing steer, ISO 17288 steering release and pulse): tables with pass/fail per run
and per law, and the plots the regulation's graders look at -- the yaw rate over its second
peak against the time from the completion of steer with the 35 % and 20 % limits at 1.00 s and
1.75 s, and the lateral displacement against the time from the beginning of steer with the
1.83 m limit at 1.07 s -- and the free-steer returns.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from fourws_analysis import fmvss126
from fourws_analysis.compare import RunAnalysis
from fourws_analysis.report_figures import _colors, _plt, _save
from fourws_analysis.report_texts import run_label
from fourws_analysis.standards import STANDARD_KEYS

SWD = STANDARD_KEYS["sine_with_dwell"]
SIS = STANDARD_KEYS["slowly_increasing_steer"]
RELEASE = STANDARD_KEYS["steering_release"]
PULSE = STANDARD_KEYS["steering_pulse"]

Row = tuple[str, str, Callable[[RunAnalysis], Any]]
Table = tuple[str, list[Row], list[RunAnalysis]]


def _yes_no(value: bool | None) -> str | None:
    return None if value is None else ("pass" if value else "FAIL")


def _swd(r: RunAnalysis) -> fmvss126.SineWithDwellResult:
    return r.standards[SWD]


def sine_with_dwell_runs(runs: Sequence[RunAnalysis]) -> list[RunAnalysis]:
    """The runs with FMVSS No. 126 sine-with-dwell metrics."""
    return [r for r in runs if SWD in r.standards]


def law_verdicts(runs: Sequence[RunAnalysis]) -> list[fmvss126.LawVerdict]:
    """Pass/fail per law over its sine-with-dwell runs."""
    return fmvss126.law_verdicts([(r.law, r.name, _swd(r)) for r in sine_with_dwell_runs(runs)])


def standards_tables(runs: Sequence[RunAnalysis]) -> list[Table]:
    """The tables of the standard tests as (title, row specs, the runs they cover); rows are
    ``(label, unit, getter)`` like the report's other tables."""
    tables: list[Table] = []
    swd = sine_with_dwell_runs(runs)
    if swd:
        tables.append(("FMVSS No. 126 sine with dwell (per run)", [
            ("first half wave", "–", lambda r: "left" if _swd(r).direction > 0 else "right"),
            ("amplitude", "deg", lambda r: math.degrees(_swd(r).amplitude_rad)),
            ("amplitude / A", "–", lambda r: _swd(r).amplitude_factor),
            ("A (found for the law)", "deg",
             lambda r: None if _swd(r).reference_amplitude_rad is None
             else math.degrees(_swd(r).reference_amplitude_rad)),
            ("beginning of steer BOS", "s", lambda r: _swd(r).bos_s),
            ("completion of steer COS", "s", lambda r: _swd(r).cos_s),
            ("second peak yaw rate", "deg/s", lambda r: math.degrees(_swd(r).peak_yaw_rate_radps)),
            ("yaw rate / peak at COS + 1.00 s (limit 0.35)", "–",
             lambda r: _swd(r).yaw_ratios[0]),
            ("yaw rate / peak at COS + 1.75 s (limit 0.20)", "–",
             lambda r: _swd(r).yaw_ratios[1]),
            ("lateral stability", "–", lambda r: _yes_no(all(_swd(r).yaw_ratio_pass))),
            ("lateral displacement at BOS + 1.07 s", "m",
             lambda r: _swd(r).lateral_displacement_m),
            ("  the same from the track (geometric)", "m", lambda r: _swd(r).path_displacement_m),
            ("responsiveness (>= 1.83 m, runs >= 5 A)", "–",
             lambda r: _yes_no(_swd(r).displacement_pass)),
            ("run", "–", lambda r: _yes_no(_swd(r).passed)),
        ], swd))
    sis = [r for r in runs if SIS in r.standards]
    if sis:
        tables.append(("FMVSS No. 126 slowly increasing steer", [
            ("steering-wheel angle at 0.3 g (A of the run)", "deg",
             lambda r: math.degrees(r.standards[SIS].steering_wheel_at_reference_rad)),
        ], sis))
    rel = [r for r in runs if RELEASE in r.standards]
    if rel:
        def g(name: str, scale: float = 1.0) -> Callable[[RunAnalysis], Any]:
            def get(r: RunAnalysis) -> Any:
                value = getattr(r.standards[RELEASE], name)
                return None if value is None else scale * value
            return get
        deg = math.degrees(1.0)
        tables.append(("ISO 17288-1 steering release", [
            ("yaw rate before the release", "deg/s", g("yaw_rate_initial_radps", deg)),
            ("steering-wheel angle before the release", "deg",
             g("steering_wheel_initial_rad", deg)),
            ("lateral acceleration before the release", "m/s²", g("lateral_accel_initial_mps2")),
            ("yaw-rate overshoot", "–", g("yaw_rate_overshoot")),
            ("steering-wheel angle overshoot", "–", g("steering_wheel_overshoot")),
            ("first yaw-rate zero after the release", "s", g("yaw_rate_zero_time_s")),
            ("time to settle (5 %)", "s", g("settling_time_s")),
            ("residual yaw rate 3 s after the release", "deg/s",
             g("residual_yaw_rate_radps", deg)),
            ("residual / initial yaw rate", "–", g("residual_fraction")),
            ("yaw oscillation damping ratio", "–",
             lambda r: r.standards[RELEASE].yaw.damping_ratio),
            ("yaw oscillation frequency", "Hz", lambda r: r.standards[RELEASE].yaw.frequency_hz),
        ], rel))
    pulse = [r for r in runs if PULSE in r.standards]
    if pulse:
        tables.append(("ISO 17288-2 steering pulse", [
            ("peak yaw rate", "deg/s",
             lambda r: math.degrees(r.standards[PULSE].peak_yaw_rate_radps)),
            ("peak steering-wheel angle", "deg",
             lambda r: math.degrees(r.standards[PULSE].peak_steering_wheel_rad)),
            ("yaw oscillation damping ratio", "–",
             lambda r: r.standards[PULSE].yaw.damping_ratio),
            ("yaw oscillation frequency", "Hz", lambda r: r.standards[PULSE].yaw.frequency_hz),
            ("steering oscillation damping ratio", "–",
             lambda r: r.standards[PULSE].steering.damping_ratio),
            ("time to settle (5 % of the peak)", "s",
             lambda r: r.standards[PULSE].settling_time_s),
            ("residual yaw rate 3 s after the pulse", "deg/s",
             lambda r: math.degrees(r.standards[PULSE].residual_yaw_rate_radps)),
        ], pulse))
    return tables


def verdict_items(runs: Sequence[RunAnalysis]) -> list[str]:
    """One line per law: passes or fails FMVSS No. 126 over its sine-with-dwell runs."""
    return [f"Law {v.law}: {'PASSES' if v.passed else 'FAILS'} over {v.runs} sine-with-dwell "
            f"run(s)" + (f"; failing: {', '.join(v.failed)}" if v.failed else "")
            for v in law_verdicts(runs)]


def figure_sine_with_dwell(runs: Sequence[RunAnalysis]) -> Any | None:
    """The graders' plots: yaw rate over its second peak from COS, lateral displacement from
    BOS, every sine-with-dwell run overlaid (one colour per run)."""
    swd = sine_with_dwell_runs(runs)
    if not swd:
        return None
    plt = _plt()
    colors = _colors(runs)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    for r in swd:
        m = _swd(r)
        t_cos = m.t_rel_bos_s - (m.cos_s - m.bos_s)
        ratio = m.yaw_rate_filtered_radps / m.peak_yaw_rate_radps
        ax1.plot(t_cos, ratio, color=colors[r.name], lw=1.0, label=run_label(r))
        ax2.plot(m.t_rel_bos_s, m.displacement_curve_m, color=colors[r.name], lw=1.0)
    for t_mark, limit in zip(fmvss126.YAW_RATIO_TIMES_S, fmvss126.YAW_RATIO_LIMITS):
        ax1.plot([t_mark], [limit], marker="v", color="k", ls="none")
        ax1.axvline(t_mark, color="0.5", lw=0.6, ls="--")
    ax1.set_xlim(-2.0, 2.5)
    ax1.set_ylim(-1.0, 1.5)
    ax1.set_xlabel("time from completion of steer (s)")
    ax1.set_ylabel("yaw rate / second peak yaw rate (1)")
    ax1.set_title("lateral stability: limits 0.35 at 1.00 s, 0.20 at 1.75 s")
    ax2.axvline(fmvss126.DISPLACEMENT_TIME_S, color="0.5", lw=0.6, ls="--")
    ax2.plot([fmvss126.DISPLACEMENT_TIME_S], [fmvss126.DISPLACEMENT_LIMIT_M], marker="^",
             color="k", ls="none")
    ax2.set_xlim(-0.2, 2.0)
    ax2.set_xlabel("time from beginning of steer (s)")
    ax2.set_ylabel("lateral displacement (m)")
    ax2.set_title("responsiveness: >= 1.83 m at 1.07 s (runs >= 5 A)")
    if len(swd) <= 12:
        fig.legend(loc="outside lower center", ncol=3)
    return fig


def plot_sine_with_dwell(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Save :func:`figure_sine_with_dwell` as PNG (None when there is no such run)."""
    fig = figure_sine_with_dwell(runs)
    return None if fig is None else _save(fig, path)


def figure_free_steer(runs: Sequence[RunAnalysis]) -> Any | None:
    """Yaw rate and steering-wheel angle of the steering-release and pulse runs from the
    release (or the end of the pulse)."""
    free = [r for r in runs if RELEASE in r.standards or PULSE in r.standards]
    if not free:
        return None
    plt = _plt()
    colors = _colors(runs)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 6), sharex=True, layout="constrained")
    for r in free:
        res = r.standards.get(RELEASE) or r.standards[PULSE]
        t0 = res.release_s if RELEASE in r.standards else res.pulse_end_s
        t = r.run.time_s - t0
        ch = r.run.channels
        ax1.plot(t, np.degrees(ch["yaw_rate_radps"]), color=colors[r.name], lw=1.0,
                 label=run_label(r))
        if "steering_wheel_angle_rad" in ch:
            ax2.plot(t, np.degrees(ch["steering_wheel_angle_rad"]), color=colors[r.name], lw=1.0)
    ax1.set_ylabel("yaw rate (deg/s)")
    ax2.set_ylabel("steering-wheel angle (deg)")
    ax2.set_xlabel("time from the release / end of the pulse (s)")
    ax1.legend(loc="upper right")
    return fig


def plot_free_steer(runs: Sequence[RunAnalysis], path: Path) -> Path | None:
    """Save :func:`figure_free_steer` as PNG."""
    fig = figure_free_steer(runs)
    return None if fig is None else _save(fig, path)


__all__ = ["figure_free_steer", "figure_sine_with_dwell", "law_verdicts", "plot_free_steer",
           "plot_sine_with_dwell", "sine_with_dwell_runs", "standards_tables", "verdict_items"]
