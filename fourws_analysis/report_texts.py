# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The report's texts: what the gains are per, how the laws are compared, the modes right of
the imaginary axis and why identified eigenvalues differ from the models' (plain strings from
:class:`~fourws_analysis.compare.RunAnalysis` results; no plotting, no HTML).
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from fourws_analysis import units
from fourws_analysis.compare import RunAnalysis
from fourws_analysis.critical_speeds import LEVELS, LevelComparison
from fourws_analysis.iso4138 import LINEAR_RANGE_MPS2
from fourws_analysis.iso7401 import ISO_LATERAL_ACCEL_MPS2

#: A real part above this is "right of the imaginary axis" (1/s): the zero eigenvalues of
#: position and heading are removed before, and round-off of the others is ~1e-12.
UNSTABLE_REAL_PER_S = 1e-9
#: Words for each model overlay (the model levels of fourws_analysis.critical_speeds).
MODEL_NAMES = {"2dof": "2-DOF model", "3dof": "3-DOF model", "8dof-lin": LEVELS["8dof-lin"]}
#: Relative tolerance on a step's target lateral acceleration to count as ISO 7401's.
_ISO_TARGET_RTOL = 1e-6


def _kmh(speed_mps: float | None) -> str:
    return "none" if speed_mps is None else f"{speed_mps:.3g} m/s ({speed_mps * 3.6:.0f} km/h)"


def run_step_title(runs: Sequence[RunAnalysis]) -> str:
    """:func:`step_title` of the step runs of ``runs``."""
    steps = [r for r in runs if r.step is not None]
    return step_title([r.run.config.get("maneuver") for r in steps],
                      [r.step.responses["lateral_accel_mps2"].steady_state
                       if "lateral_accel_mps2" in r.step.responses else None for r in steps])


def step_title(maneuvers: Sequence[object], steady_ay_mps2: Sequence[float | None]) -> str:
    """Title of the step-response table and figure: ISO 7401's only when every step run was
    made at its steady lateral acceleration (the maneuver's ``target_lateral_accel_mps2`` is
    :data:`fourws_analysis.iso7401.ISO_LATERAL_ACCEL_MPS2`, as scenario iso7401_step_4mps2
    has it), else a step-steer response that says it is not the ISO condition and what it
    was (the runs' steady |a_y|, m/s^2).

    Parameters
    ----------
    maneuvers : sequence of mapping
        The step runs' maneuver descriptions (run configuration ``maneuver``).
    steady_ay_mps2 : sequence of float or None
        Their steady lateral accelerations, m/s^2.
    """
    iso = ISO_LATERAL_ACCEL_MPS2
    targets = [m.get("target_lateral_accel_mps2") if isinstance(m, Mapping) else None
               for m in maneuvers]
    at_iso = [isinstance(t, (int, float)) and math.isclose(t, iso, rel_tol=_ISO_TARGET_RTOL)
              for t in targets]
    if targets and all(at_iso):
        return f"ISO 7401 step response (steady a_y {iso:g} m/s²)"
    ay = sorted(abs(a) for a in steady_ay_mps2 if a is not None and math.isfinite(a))
    what = ("" if not ay else f"steady a_y {ay[0]:.2g} m/s²" if len(ay) == 1 or
            round(ay[0], 1) == round(ay[-1], 1) else f"steady a_y {ay[0]:.2g}-{ay[-1]:.2g} m/s²")
    given = [t for t in targets if isinstance(t, (int, float))]
    how = (f"target {', '.join(f'{t:g}' for t in sorted(set(given)))} m/s², " if given
           else "a given steer, ")
    return (f"Step-steer response with ISO 7401's metrics — not the ISO 7401 condition "
            f"(steady a_y {iso:g} m/s²): {how}{what}".rstrip(", "))


def level_notes(levels: LevelComparison, vehicle: str) -> list[str]:
    """The report's first lines on the car: where roll steer makes an understeering tire set
    an oversteering car, and the critical and characteristic speeds of every model level
    (FWS), named by level."""
    parts = []
    for lv in levels.levels:
        if lv.unavailable:
            continue
        speed = (f"critical speed {_kmh(lv.critical_speed_mps)}"
                 if lv.steer_character == "oversteer" else
                 f"characteristic speed {_kmh(lv.characteristic_speed_mps)}")
        parts.append(f"{lv.label} {lv.steer_character}, {speed}")
    out = []
    if levels.roll_steer_oversteer:
        out.append(f"{vehicle}: roll steer makes the understeering tire set an oversteering "
                   "car.")
    if parts:
        out.append(f"{vehicle} with FWS, by model level: " + "; ".join(parts) + ". "
                   + " ".join(levels.why))
    return out


def car_notes(runs: Sequence[RunAnalysis]) -> list[str]:
    """:func:`level_notes` of each car of ``runs`` (once per car)."""
    seen: set[str] = set()
    out: list[str] = []
    for r in runs:
        if r.levels is None or r.vehicle is None or r.vehicle.cache_key() in seen:
            continue
        seen.add(r.vehicle.cache_key())
        out += level_notes(r.levels, r.vehicle.name)
    return out


def spike_notes(runs: Sequence[RunAnalysis]) -> list[str]:
    """One sentence per step run whose lateral-acceleration overshoot is a spike
    (:func:`fourws_analysis.iso7401.spike_of`)."""
    out = []
    for r in runs:
        ay = r.step.responses.get("lateral_accel_mps2") if r.step is not None else None
        if ay is not None and ay.spike and ay.overshoot is not None:
            out.append(f"{run_label(r)}: the lateral-acceleration overshoot "
                       f"({100.0 * ay.overshoot:.0f} %) is {ay.spike}.")
    return out


def limit_notes(runs: Sequence[RunAnalysis]) -> list[str]:
    """One sentence per run whose car broke its vehicle limits (it spun, drove backwards or
    left the model's range), with when and why; its handling metrics are not computed."""
    return [f"{run_label(r)}: {r.vehicle_breach.reason} -- the run ended "
            f"{r.vehicle_breach.kind} at t = {r.vehicle_breach.time_s:.2f} s; its handling "
            "metrics (ISO 7401, ISO 4138, ISO 3888-2, frequency response) are not computed."
            for r in runs if r.vehicle_breach is not None]


def run_label(r: RunAnalysis) -> str:
    """Legend label of a run: its name, with the law added when the name does not hold it
    (``fws``, not ``fws (fws)``; ``step (sol1)``)."""
    return r.name if r.law in r.name else f"{r.name} ({r.law})"


def common_ratio(runs: Sequence[RunAnalysis]) -> float | None:
    """The steering ratio N shared by ``runs`` (None if unknown or different)."""
    ratios = {r.steering_ratio for r in runs}
    if len(ratios) != 1:
        return None
    return next(iter(ratios))


def law_groups(runs: Sequence[RunAnalysis]) -> dict[str, list[RunAnalysis]]:
    """The runs with eigenvalues to show, by law."""
    usable = [r for r in runs if r.eig_sweep is not None or r.modes is not None or r.models]
    groups: dict[str, list[RunAnalysis]] = {}
    for r in usable:
        groups.setdefault(r.law, []).append(r)
    return groups


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
    ratio = common_ratio(runs)
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
        crit = None
        if first.levels is not None:
            crit = first.levels.by_level("8dof-lin").law_critical_speed_mps
        if np.any(bad):
            k = int(np.nanargmax(worst))
            k0 = int(np.argmax(bad))
            where = (f"from {v[k0]:.3g} m/s ({v[k0] * 3.6:.0f} km/h) up" if np.all(bad[k0:])
                     else "at " + ", ".join(f"{x:.3g}" for x in v[bad]) + " m/s")
            if crit is not None:
                where += f" (critical speed {_kmh(crit)})"
            elsewhere = f"8-DOF linearized {where}"
            details.append(f"8-DOF linearized over {v.min():.3g}-{v.max():.3g} m/s: a mode "
                           f"right of the imaginary axis {where}, largest real part "
                           f"{worst[k]:+.3g} 1/s at {v[k]:.3g} m/s.")
        else:
            details.append(f"8-DOF linearized: stable from {v.min():.3g} to {v.max():.3g} "
                           f"m/s (largest real part {np.nanmax(worst):+.3g} 1/s).")
    for name, system in first.models.items():
        bad_e = _unstable(system.poles())
        if bad_e.size:
            label = MODEL_NAMES.get(name, name)
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
        eig = r.models[model].poles()
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
                     f"slowest {MODEL_NAMES.get(model, model)} modes at "
                     f"{r.speed_mps:.3g} m/s are {_fmt_eigs(shown)} 1/s; peak |a_y| "
                     f"{peak:.3g} m/s², {regime}.")
    return notes


__all__ = ["MODEL_NAMES", "UNSTABLE_REAL_PER_S", "common_ratio", "identification_notes",
           "law_groups", "limit_notes", "reading_notes", "run_label", "stability_notes"]
