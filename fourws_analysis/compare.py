# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Analysis of recorded runs: which metrics a run can give, computed, and compared.

:func:`analyze_run` recognizes the maneuver from the run configuration and computes what it
can give; a metric it cannot give is recorded with the reason (``RunAnalysis.unavailable``)
instead of stopping the others:

==========================================  =============================================
maneuver                                    metrics
==========================================  =============================================
``swept_sine``, ``pulse``, ``sine``         frequency response (full-record H1), modes
``random_steer``                            frequency response (Welch H1)
``step_steer``, ``ramp_steer``              ISO 7401 step metrics, identified eigenvalues
``slow_ramp_steer``, ``constant_radius``    ISO 4138 gradients, understeer, char. speed
``double_lane_change``                      ISO 3888-2 clearance to the cones, pass/fail
``sine_with_dwell``, ``steering_release``,  the regulation's or standard's test
``slowly_increasing_steer``,                (:mod:`fourws_analysis.standards`: FMVSS 126,
``steering_pulse``                          ISO 17288)
every run with a vehicle                    eigenvalues of the linearized 8-DOF vs speed
==========================================  =============================================

A run whose car broke its maneuver's :class:`~fourws_sim.outcome.VehicleLimits` (it spun,
drove backwards or left the model's range: :attr:`fourws_analysis.bag.UniformRun.vehicle_breach`,
the rule that ends a graph run and the offline twin ``spun``/``diverged``) is flagged: its
metrics say so under ``vehicle_limits`` (kind, time, reason), and the metrics of a handling
response -- the frequency response, the ISO 7401 step metrics and identified modes, the
ISO 4138 gradients, the ISO 3888-2 lane change -- are not computed (``unavailable`` names the
breach): they would describe the spin, not the car. The regulation and standard tests
(:mod:`fourws_analysis.standards`) judge a car that may spin and are kept.

Model overlays (analytic 2-DOF/3-DOF closed with the run's law, and the 8-DOF linearized
numerically at the run's straight-running trim) need the vehicle mapping of the run config.
The law is rebuilt for the period it ran at (``controller_period_s`` of the run config, else
``control_period_s``), and each model is also closed as the controller closes it, the command
held over that period (:func:`fourws_analysis.linear.sample_loop`: eigenvalues z and
``ln(z)/T``).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import control
import numpy as np

from fourws_analysis import frequency as fq
from fourws_analysis import (critical_speeds, identify, iso4138, iso7401, lane_change, linear,
                             linearize, standards, units)
from fourws_analysis.bag import MetricUnavailableError, UniformRun
from fourws_analysis.memo import Memo
from fourws_control import Law, LinearGains, make_law
from fourws_sim.errors import FourwsError
from fourws_sim.models import get_model
from fourws_sim.outcome import Violation
from fourws_sim.params import vehicle_from_mapping

STEP_MANEUVERS = ("step_steer", "ramp_steer")
STEADY_MANEUVERS = ("slow_ramp_steer", "constant_radius")
#: Speeds of the 8-DOF eigenvalue sweep, m/s (walking pace excluded; up to 144 km/h).
SWEEP_SPEEDS_MPS = tuple(float(v) for v in np.arange(5.0, 40.01, 2.5))
#: Driver inputs the frequency response is taken against.
FR_INPUTS = ("front_wheel_angle_rad", "steering_wheel_angle_rad")

#: What the front road-wheel angle δf of the gains is, by ``RunAnalysis.steer_reference``.
STEER_REFERENCES = {
    "commanded": "the driver's front road-wheel command (/fourws/driver_input); the applied "
                 "angle adds roll steer",
    "applied": "the applied front road-wheel angle (/fourws/state), roll steer included: the "
               "bag has no /fourws/driver_input",
}

Progress = Callable[[str], None]
#: Results kept per memo below, the most recently used (a sweep is about 2 kB).
_CACHE_SIZE = 256
#: Eigenvalue sweeps already computed in this process, by vehicle/law/belief/options.
_SWEEP_CACHE: Memo[linearize.EigenSweep] = Memo(_CACHE_SIZE)
#: Level comparisons (critical speeds per model level) likewise.
_LEVELS_CACHE: Memo[critical_speeds.LevelComparison] = Memo(_CACHE_SIZE)


@dataclass
class RunAnalysis:
    """Everything computed for one run.

    Attributes
    ----------
    run : UniformRun
    speed_mps : float
        Forward speed of the run (configuration, else median of the record), m/s.
    frequency : dict of str to FrequencyResponse
        Keyed ``"<output>/<input>"``.
    frequency_metrics : dict of str to ResponseMetrics
    models : dict of str to control.StateSpace
        Linear models for the overlays (``"2dof"``, ``"3dof"``, ``"8dof-lin"``): input the
        front road-wheel angle, outputs named by run channel
        (:func:`fourws_analysis.linear.linear_system`, :func:`eightdof_linear_system`).
    step : iso7401.StepResult or None
    steady : iso4138.SteadyStateHandling or None
    modes : identify.IdentifiedModes or None
    sampled : dict of str to linear.SampledLoop
        The models of ``models`` closed with the law held over its control period.
    eig_sweep : linearize.EigenSweep or None
    levels : critical_speeds.LevelComparison or None
        The critical and characteristic speeds of the run's car per model level, FWS and
        with the run's law (with the model overlays).
    unavailable : dict of str to str
        Metric -> why it could not be computed.
    notes : list of str
    steer_reference : str
        Which front road-wheel angle δf the gains are per: ``"commanded"`` (the driver's
        command, ``/fourws/driver_input``) or ``"applied"`` (``/fourws/state``, roll steer
        included: the bag has no driver input).
    steering_ratio : float or None
        N of the run's vehicle (steering-wheel angle δH = N δf).
    applied_to_commanded : float or None
        Applied over commanded front angle at the end of a step's hold: 1 + the roll-steer
        share (step runs with both angles recorded).
    standards : dict
        The regulation or standard test of the maneuver (:mod:`fourws_analysis.standards`).
    """

    run: UniformRun
    speed_mps: float
    vehicle: Any = None
    frequency: dict[str, fq.FrequencyResponse] = field(default_factory=dict)
    frequency_metrics: dict[str, fq.ResponseMetrics] = field(default_factory=dict)
    models: dict[str, control.StateSpace] = field(default_factory=dict)
    step: iso7401.StepResult | None = None
    steady: iso4138.SteadyStateHandling | None = None
    lane_change: lane_change.LaneChangeResult | None = None
    modes: identify.IdentifiedModes | None = None
    sampled: dict[str, linear.SampledLoop] = field(default_factory=dict)
    eig_sweep: linearize.EigenSweep | None = None
    levels: critical_speeds.LevelComparison | None = None
    unavailable: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    #: What the bag says of its completeness: ``complete``, ``unverified`` (no accounting in
    #: the bag) or ``INCOMPLETE: ...`` (analysed with ``--allow-incomplete``: every metric of
    #: this run comes from a bag that misses messages).
    recording: str = "unverified"
    steer_reference: str = "applied"
    steering_ratio: float | None = None
    applied_to_commanded: float | None = None
    standards: dict[str, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        """Run label."""
        return self.run.name

    @property
    def vehicle_breach(self) -> Violation | None:
        """The first state past the run's vehicle limits (None: none), see the module
        docstring."""
        return self.run.vehicle_breach

    @property
    def law(self) -> str:
        """Rear-steer law of the run as its bag describes it (``unknown`` when the bag does
        not say: a law is never guessed)."""
        law = self.run.config.get("law", "")
        if isinstance(law, Mapping):
            law = law.get("name", law.get("type", ""))
        return str(law or "unknown")

    @property
    def step_amplitude(self) -> dict[str, Any]:
        """How the step amplitude of a step_steer run was chosen (empty for other runs):
        ``amplitude_rad`` (in ``steer_input`` units), ``steer_input``, and with a target
        ``target_lateral_accel_mps2`` and ``found_for_law``."""
        man = self.run.config.get("maneuver")
        if not isinstance(man, Mapping) or man.get("type") != "step_steer":
            return {}
        out = {"amplitude_rad": man.get("amplitude_rad"),
               "steer_input": man.get("steer_input", "road_wheel")}
        if man.get("target_lateral_accel_mps2") is not None:
            out["target_lateral_accel_mps2"] = man["target_lateral_accel_mps2"]
            out["found_for_law"] = man.get("amplitude_law") or None
        return out

    def metrics(self) -> dict[str, Any]:
        """Every metric as a JSON-ready mapping."""
        out: dict[str, Any] = {
            "maneuver": self.run.maneuver or None, "law": self.law,
            "recording": self.recording,
            "model": self.run.config.get("model"), "speed_mps": self.speed_mps,
            "duration_s": float(self.run.time_s[-1] - self.run.time_s[0]),
            "sample_period_s": self.run.dt_s,
            "gain_reference": {
                "road_wheel_angle": self.steer_reference,
                "road_wheel_angle_meaning": STEER_REFERENCES[self.steer_reference],
                "steering_ratio": self.steering_ratio,
                "steering_wheel_angle": "delta_H = steering_ratio * delta_f",
                "applied_to_commanded_front_angle": self.applied_to_commanded,
            },
        }
        if self.vehicle_breach is not None:
            out["vehicle_limits"] = {"kind": self.vehicle_breach.kind,
                                     "time_s": self.vehicle_breach.time_s,
                                     "reason": self.vehicle_breach.reason}
        if self.step_amplitude:
            out["step_amplitude"] = self.step_amplitude
        if self.frequency_metrics:
            out["frequency_response"] = {k: v.to_dict()
                                         for k, v in self.frequency_metrics.items()}
        if self.step is not None:
            out["iso7401_step"] = self.step.to_dict()
        if self.steady is not None:
            out["iso4138_steady_state"] = self.steady.to_dict()
        if self.lane_change is not None:
            out["iso3888_lane_change"] = self.lane_change.to_dict()
        if self.modes is not None:
            out["identified_modes"] = self.modes.to_dict()
        if self.levels is not None:
            out["critical_speeds_by_model_level"] = self.levels.to_dict()
        if self.models:
            out["model_eigenvalues_per_s"] = {
                k: [[float(e.real), float(e.imag)] for e in _lateral_modes(m.poles())]
                for k, m in self.models.items()}
            out["model_steady_state_gains"] = {
                k: {o: fq.dc_gain(m, o) for o in m.output_labels}
                for k, m in self.models.items()}
        if self.sampled:
            out["model_sampled_eigenvalues"] = {k: v.to_dict() for k, v in self.sampled.items()}
        if self.modes is not None and self.models:
            out["identified_vs_model"] = {
                k: [{"identified": [e.real, e.imag], "model": [p.real, p.imag],
                     "relative_difference": rel}
                    for e, p, rel in identify.match_eigenvalues(
                        self.modes.eigenvalues, _lateral_modes(m.poles()))]
                for k, m in self.models.items()}
        if self.eig_sweep is not None:
            out["eigenvalues_vs_speed"] = self.eig_sweep.to_dict()
        for key, value in self.standards.items():
            out[key] = value.to_dict()
        out["unavailable"] = dict(self.unavailable)
        out["notes"] = list(self.notes)
        return _jsonable(out)


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, Mapping):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        value = float(obj)
        return value if math.isfinite(value) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    return obj


def _lateral_modes(eig: np.ndarray) -> np.ndarray:
    """Drop the zero eigenvalues (position, heading) and NaNs."""
    eig = np.asarray(eig, dtype=complex)
    keep = np.isfinite(eig) & (np.abs(eig) > 1e-6)
    return eig[keep][np.argsort(-eig[keep].real)]


def _vehicle(run: UniformRun, key: str = "vehicle") -> Any:
    """The vehicle (or the controller's ``belief_vehicle``) of the run configuration."""
    data = run.config.get(key)
    if not isinstance(data, Mapping):
        raise MetricUnavailableError(f"run_config has no {key!r} mapping: model overlays and "
                                     "eigenvalues need it")
    return vehicle_from_mapping(data, source=f"{run.name}:/fourws/run_config:{key}")


def _speed(run: UniformRun) -> float:
    for key in ("speed_mps", "initial_speed_mps"):
        value = run.config.get(key)
        if isinstance(value, (int, float)) and value > 0:
            return float(value)
    man = run.config.get("maneuver")
    if isinstance(man, Mapping):
        for key in ("speed_mps", "initial_speed_mps"):
            value = man.get(key)
            if isinstance(value, (int, float)) and value > 0:
                return float(value)
    speed = run.channels.get("speed_mps")
    if speed is None or not np.any(speed > 0):
        raise MetricUnavailableError("no forward speed in the run (config or state)")
    return float(np.median(speed))


def _eightdof_loop(vehicle: Any, speed_mps: float, law: Any, belief_vehicle: Any,
                   law_options: Mapping[str, Any] | None
                   ) -> tuple[np.ndarray, np.ndarray, LinearGains, Any]:
    """Open-loop 8-DOF Jacobians at straight running and the law written in its state and
    input order (:meth:`fourws_control.base.Law.linear_gains` on ``8dof``):
    ``(a, b, gains, model module)``, ``delta_r = K_x x + K_u u``. ``law`` is a name (built on
    the belief vehicle with ``law_options``) or a built law."""
    mod = get_model("8dof")
    a, b = linearize.straight_running_jacobians(vehicle, speed_mps, "8dof")
    law_obj = law if isinstance(law, Law) else make_law(
        law, belief_vehicle if belief_vehicle is not None else vehicle,
        **dict(law_options or {}))
    return a, b, law_obj.linear_gains("8dof", vehicle, speed_mps), mod


def _coupled(a_cl: np.ndarray) -> np.ndarray:
    """Indices of the states with a nonzero column in ``a_cl``: all but the earth-frame
    position, which nothing depends on (its eigenvalues s = 0, z = 1 are left out). The
    heading stays: it moves the lateral position, and it keeps one zero eigenvalue."""
    return np.nonzero(np.any(np.abs(a_cl) > 0.0, axis=0))[0]


def eightdof_closed_matrices(vehicle: Any, speed_mps: float, law: Any = "fws",
                             belief_vehicle: Any = None,
                             law_options: Mapping[str, Any] | None = None
                             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, LinearGains, Any]:
    """The matrices of :func:`eightdof_linear_system` without its state-space object (a
    study's eigenvalues need A alone): ``(A_cl, B_cl, kept state indices, the law's gains,
    the model module)``, A and B reduced to the kept states."""
    a, b, g, mod = _eightdof_loop(vehicle, speed_mps, law, belief_vehicle, law_options)
    i = mod.INPUT
    a_cl, b_cl = linear.close_loop(a, b, g, i.DELTA_R, [i.DELTA_F])
    keep = _coupled(a_cl)
    return a_cl[np.ix_(keep, keep)], b_cl[keep], keep, g, mod


def eightdof_linear_system(vehicle: Any, speed_mps: float, law: Any = "fws",
                           belief_vehicle: Any = None,
                           law_options: Mapping[str, Any] | None = None
                           ) -> control.StateSpace:
    """The 8-DOF model linearized at straight running (finite differences), law closed.

    The law enters through its own linear gains in the 8-DOF's state order
    (:meth:`fourws_control.base.Law.linear_gains`, :func:`fourws_analysis.linear.close_loop`);
    the actuator limits are inactive for small signals. The earth-frame position, which
    nothing depends on, is left out. A stays singular (heading; the speed and wheel-spin
    modes at a trim without drag), but no output sees those modes:
    :func:`fourws_analysis.frequency.dc_gain` takes the limit at a tiny frequency. ``law`` is
    a name or a built :class:`fourws_control.Law`.

    Returns
    -------
    control.StateSpace
        Input ``front_wheel_angle_rad`` (rad); states named by the 8-DOF's ``STATE``; outputs
        ``yaw_rate_radps``, ``sideslip_rad`` (V/U), ``lateral_accel_mps2`` (dV/dt + U r),
        ``roll_rad`` and ``rear_wheel_angle_rad`` (the law's command).
    """
    a_cl, b_cl, keep, g, mod = eightdof_closed_matrices(vehicle, speed_mps, law,
                                                        belief_vehicle, law_options)
    s, i = mod.STATE, mod.INPUT
    k_x = g.K_x[keep]
    e = np.eye(g.K_x.size)[:, keep]  # row j: state j in the reduced coordinates
    i_v = list(keep).index(s.V)
    outputs = {"yaw_rate_radps": (e[s.R], 0.0), "sideslip_rad": (e[s.V] / speed_mps, 0.0),
               "lateral_accel_mps2": (a_cl[i_v] + speed_mps * e[s.R], float(b_cl[i_v, 0])),
               "roll_rad": (e[s.PHI], 0.0),
               "rear_wheel_angle_rad": (k_x, float(g.K_u[i.DELTA_F]))}
    C = np.array([c for c, _ in outputs.values()])
    D = np.array([[d] for _, d in outputs.values()])
    name = law.name if isinstance(law, Law) else law
    return control.ss(a_cl, b_cl, C, D, inputs=[units.ROAD_WHEEL.channel],
                      outputs=list(outputs), states=[s(k).name for k in keep],
                      name=f"8dof linearized {name}")


def eightdof_sampled_loop(vehicle: Any, speed_mps: float, period_s: float, law: Any = "fws",
                          belief_vehicle: Any = None,
                          law_options: Mapping[str, Any] | None = None) -> linear.SampledLoop:
    """The linearized 8-DOF of :func:`eightdof_linear_system` with the law's command held over
    each control period ``period_s`` (s). ``law`` is a name or a built
    :class:`fourws_control.Law`. The earth-frame position, which nothing depends on, is left
    out (it would add eigenvalues z = 1); the heading, speed and wheel-spin modes stay (z = 1
    at a trim without drag, ``ln(z)/T = 0``)."""
    a, b, g, mod = _eightdof_loop(vehicle, speed_mps, law, belief_vehicle, law_options)
    b_r = b[:, mod.INPUT.DELTA_R]
    keep = _coupled(a + np.outer(b_r, g.K_x))
    return linear.sample_loop(a[np.ix_(keep, keep)], b_r[keep], g.K_x[keep], period_s)


def _law_period(run: UniformRun) -> float | None:
    """The period the run's law was built for and its command held, s (run config)."""
    for key in ("controller_period_s", "control_period_s"):
        value = run.config.get(key)
        if isinstance(value, (int, float)) and not isinstance(value, bool) \
                and math.isfinite(value) and value > 0:
            return float(value)
    return None


def _sampled_models(res: RunAnalysis, vehicle: Any, speed: float, period: float,
                    belief: Any, options: Mapping[str, Any]) -> None:
    """Fill ``res.sampled`` for the models of ``res.models``."""
    def analytic(model: str) -> linear.SampledLoop:
        law = make_law(res.law, belief if belief is not None else vehicle, **dict(options))
        return linear.sampled_closed_loop(model, vehicle, law, speed, period)

    def eightdof() -> linear.SampledLoop:
        return eightdof_sampled_loop(vehicle, speed, period, res.law, belief, options)

    for model in res.models:
        loop = _try(res, f"model_{model}_sampled",
                    eightdof if model == "8dof-lin" else lambda m=model: analytic(m))
        if loop is not None:
            res.sampled[model] = loop


def _law_key(res: RunAnalysis, vehicle: Any, belief: Any, options: Mapping[str, Any]) -> str:
    """The key of what depends on the car, the run's law, its belief and its options."""
    return json.dumps([vehicle.cache_key(), res.law,
                       belief.cache_key() if belief is not None else None, dict(options)],
                      sort_keys=True, default=str)


def _levels(res: RunAnalysis, vehicle: Any, belief: Any,
            options: Mapping[str, Any]) -> critical_speeds.LevelComparison | None:
    """Every model level's critical and characteristic speeds of the run's car, FWS and its
    law (built as the run built it), shared by the runs of one car and law."""
    def levels() -> critical_speeds.LevelComparison:
        law = make_law(res.law, belief if belief is not None else vehicle, **dict(options))
        return critical_speeds.compare_levels(vehicle, law)

    return _LEVELS_CACHE.get(_law_key(res, vehicle, belief, options),
                             lambda: _try(res, "critical_speeds", levels))


def prepare(config: Mapping[str, Any], *, eig_sweep: bool = True) -> None:
    """Compute ahead what the analysis of every bag recorded with the run configuration
    ``config`` (the mapping of ``/fourws/run_config``) shares with the other runs of its car
    and law, into this process's caches: the critical speeds per model level and the 8-DOF
    eigenvalues vs speed. :func:`analyze_run` of such a bag then finds them; the results are
    the same either way. ``fourws demo`` calls it while the run is recorded. What cannot be
    computed is left out here, so the analysis of the bag computes it and says why."""
    run = UniformRun(name="", time_s=np.zeros(1), dt_s=1.0, channels={}, config=dict(config))
    res = RunAnalysis(run=run, speed_mps=math.nan)
    setting = _law_setting(res)
    if setting.vehicle is None:
        return
    _levels(res, setting.vehicle, setting.belief, setting.options)
    if eig_sweep and setting.vehicle.body is not None:
        _eigen_sweep(res, setting)


def _past_limits(res: RunAnalysis, metric: str) -> bool:
    """True (and ``metric`` marked unavailable with the reason) if the run's car broke its
    vehicle limits: a handling metric of it would describe the spin."""
    breach = res.vehicle_breach
    if breach is None:
        return False
    res.unavailable[metric] = (f"{breach.reason}; the run ended {breach.kind} there and "
                               "its record is no handling response")
    return True


def _try(result: RunAnalysis, metric: str, fn: Callable[[], Any]) -> Any:
    try:
        return fn()
    except FourwsError as exc:  # MetricUnavailableError, ParameterError, ...
        result.unavailable[metric] = str(exc)
    except np.linalg.LinAlgError as exc:
        result.unavailable[metric] = f"linear algebra failed: {exc}"
    return None


def analyze_run(run: UniformRun, *, eig_sweep: bool = True, models: bool = True,
                progress: Progress | None = None) -> RunAnalysis:
    """Compute every metric ``run`` can give (see the module docstring).

    Parameters
    ----------
    run : UniformRun
    eig_sweep : bool
        Also compute the eigenvalues of the linearized 8-DOF vs speed.
    models : bool
        Also build the linear model overlays (2-DOF, 3-DOF, 8-DOF linearized, each also
        sampled); False gives the metrics of the record alone.
    progress : callable, optional
        Called with a short description before each step.
    """
    tick = progress or (lambda _msg: None)
    res, ch = _start(run)
    tick(f"{run.name}: linear models")
    setting = _law_setting(res)
    if models and setting.vehicle is not None and math.isfinite(res.speed_mps):
        _overlays(res, setting)
        tick(f"{run.name}: critical speeds per model level")
        res.levels = _levels(res, setting.vehicle, setting.belief, setting.options)
    elif not models:
        res.notes.append("linear model overlays not asked for")
    _frequency_response(res, ch, tick)
    _step_response(res, ch, tick)
    _steady_state(res, ch, setting.vehicle, tick)
    _iso3888(res, ch, tick)
    found, why = standards.standard_metrics(run, ch, setting.vehicle)  # FMVSS 126, ISO 17288
    res.standards.update(found)
    res.unavailable.update(why)
    if eig_sweep and setting.vehicle is not None and setting.vehicle.body is not None:
        tick(f"{run.name}: 8-DOF eigenvalues vs speed")
        res.eig_sweep = _eigen_sweep(res, setting)
    return res


def _start(run: UniformRun) -> tuple[RunAnalysis, dict[str, np.ndarray]]:
    """The analysis of ``run`` before any metric (its speed, whether its maneuver is known)
    and the channels the metrics read: the recorded ones, with the driver's front road-wheel
    command as the front angle where the run has it (the models' input; the applied angle
    adds roll steer)."""
    try:
        speed = _speed(run)
    except MetricUnavailableError as exc:
        speed = math.nan
        notes = [str(exc)]
    else:
        notes = []
    res = RunAnalysis(run=run, speed_mps=speed, notes=notes)
    if run.vehicle_breach is not None:
        res.notes.append(f"{run.vehicle_breach.reason}: the run ended "
                         f"{run.vehicle_breach.kind} at t = {run.vehicle_breach.time_s:.2f} s")
    if not run.maneuver:
        res.notes.append("maneuver not recognized (run_config has no maneuver.type): "
                         "metrics chosen from the data are skipped")
    ch = dict(run.channels)
    if "front_wheel_angle_cmd_rad" in ch:
        ch["front_wheel_angle_rad"] = ch["front_wheel_angle_cmd_rad"]
        res.steer_reference = "commanded"
    return res, ch


@dataclass(frozen=True)
class _LawSetting:
    """What the run's law is rebuilt from (run config): the true vehicle (None: not in the
    config), the controller's belief (None: the true one), the law's options with the period
    it ran at (s; None: not in the config)."""

    vehicle: Any
    belief: Any
    options: Mapping[str, Any]
    period: float | None


def _law_setting(res: RunAnalysis) -> _LawSetting:
    """The run's :class:`_LawSetting`; sets ``res.vehicle`` and ``res.steering_ratio``."""
    run = res.run
    vehicle = _try(res, "model_overlays", lambda: _vehicle(run))
    res.vehicle = vehicle
    if vehicle is not None and vehicle.steering is not None:
        res.steering_ratio = float(vehicle.steering.ratio)
    belief = _try(res, "belief_vehicle", lambda: _vehicle(run, "belief_vehicle")) \
        if isinstance(run.config.get("belief_vehicle"), Mapping) else None
    options = run.config.get("law_options") or {}
    if not isinstance(options, Mapping):
        options = {}
    period = _law_period(run)
    if period is not None:
        options = {**options, "control_period_s": period}
    return _LawSetting(vehicle, belief, options, period)


def _overlays(res: RunAnalysis, setting: _LawSetting) -> None:
    """The linear models closed with the run's law (``res.models``: the 2-DOF, the 3-DOF
    with roll data, the linearized 8-DOF with body data) and each sampled at the law's
    period (``res.sampled``)."""
    vehicle, belief, options, speed = (setting.vehicle, setting.belief, setting.options,
                                       res.speed_mps)
    for model in ("2dof", "3dof"):
        if model == "3dof" and vehicle.roll is None:
            continue
        sys_ = _try(res, f"model_{model}",
                    lambda m=model: linear.linear_system(vehicle, m, speed, res.law,
                                                         belief, options))
        if sys_ is not None:
            res.models[model] = sys_
    if vehicle.body is not None:
        sys8 = _try(res, "model_8dof_linearized",
                    lambda: eightdof_linear_system(vehicle, speed, res.law, belief, options))
        if sys8 is not None:
            res.models["8dof-lin"] = sys8
    if setting.period is not None:
        _sampled_models(res, vehicle, speed, setting.period, belief, options)


def _frequency_response(res: RunAnalysis, ch: Mapping[str, np.ndarray],
                        tick: Progress) -> None:
    """Frequency responses and their metrics of a run with an excitation band."""
    run, man = res.run, res.run.maneuver
    if man not in fq.FREQUENCY_MANEUVERS:
        res.unavailable["frequency_response"] = (
            f"needs a {', '.join(fq.FREQUENCY_MANEUVERS)} run (an excitation band); "
            f"this run is {man or 'unrecognized'}")
        return
    if _past_limits(res, "frequency_response"):
        return
    tick(f"{run.name}: frequency response")
    method = "transient" if man in fq.TRANSIENT_MANEUVERS else "welch"
    for inp in FR_INPUTS:
        if inp not in ch:
            res.unavailable[f"frequency_response/{inp}"] = f"no {inp} recorded"
            continue
        for out in fq.OUTPUTS:
            if out not in ch or (out == "roll_rad" and not np.any(ch[out])):
                continue
            key = f"{out}/{inp}"
            fr = _try(res, f"frequency_response/{key}", lambda o=out, i=inp: (
                fq.estimate_response(ch[i], ch[o], run.dt_s, method=method, output=o,
                                     input_name=i)))
            if fr is None:
                continue
            res.frequency[key] = fr
            met = _try(res, f"frequency_metrics/{key}", lambda f=fr: fq.response_metrics(f))
            if met is not None:
                res.frequency_metrics[key] = met


def _step_response(res: RunAnalysis, ch: Mapping[str, np.ndarray], tick: Progress) -> None:
    """ISO 7401 step metrics (with the applied over commanded front angle) and the
    identified modes of a step or pulse run."""
    run, man, t = res.run, res.run.maneuver, res.run.time_s
    if man not in STEP_MANEUVERS and man != "pulse":
        res.unavailable["iso7401_step"] = (f"needs a step_steer or ramp_steer run; this run is "
                                           f"{man or 'unrecognized'}")
        return
    if res.vehicle_breach is not None:
        _past_limits(res, "identified_modes")
        if man in STEP_MANEUVERS:
            _past_limits(res, "iso7401_step")
        return
    tick(f"{run.name}: step metrics and modes")
    if man in STEP_MANEUVERS:
        responses = {k: ch[k] for k in ("yaw_rate_radps", "lateral_accel_mps2") if k in ch}
        res.step = _try(res, "iso7401_step", lambda: iso7401.step_metrics(
            t, ch["front_wheel_angle_rad"], responses, ch.get("sideslip_rad"),
            steering_wheel_rad=ch.get("steering_wheel_angle_rad"),
            rear_wheel_rad=ch.get("rear_wheel_angle_rad")))
        if res.step is not None and res.steer_reference == "commanded":
            win = (t >= res.step.hold_end_s - iso7401.STEADY_WINDOW_S) \
                & (t <= res.step.hold_end_s)
            applied = run.channels["front_wheel_angle_rad"]
            cmd = ch["front_wheel_angle_rad"]
            den = float(np.mean(cmd[win]) - cmd[0])
            if den != 0.0:
                res.applied_to_commanded = float(np.mean(applied[win]) - applied[0]) / den
    outs = [ch[k] for k in ("yaw_rate_radps", "lateral_velocity_mps") if k in ch]
    res.modes = _try(res, "identified_modes", lambda: identify.identify_modes(
        t, ch["front_wheel_angle_rad"], outs, order=2))


def _steady_state(res: RunAnalysis, ch: Mapping[str, np.ndarray], vehicle: Any,
                  tick: Progress) -> None:
    """ISO 4138 steady-state gradients of a slow ramp or constant-radius run."""
    run, man, t = res.run, res.run.maneuver, res.run.time_s
    if man not in STEADY_MANEUVERS:
        res.unavailable["iso4138_steady_state"] = (
            f"needs a slow_ramp_steer or constant_radius run; this run is "
            f"{man or 'unrecognized'}")
        return
    if _past_limits(res, "iso4138_steady_state"):
        return
    tick(f"{run.name}: steady-state handling")

    def steady() -> iso4138.SteadyStateHandling:
        if vehicle is None:
            raise MetricUnavailableError("understeer gradient needs the wheelbase "
                                         "(vehicle mapping in run_config)")
        settle = t >= t[0] + 2.0  # skip the start transient
        return iso4138.steady_state_handling(
            ch["lateral_accel_mps2"][settle], ch["front_wheel_angle_rad"][settle],
            ch["yaw_rate_radps"][settle], ch["speed_mps"][settle],
            vehicle.chassis.wheelbase_m,
            ch["sideslip_rad"][settle] if "sideslip_rad" in ch else None,
            ch["roll_rad"][settle] if "roll_rad" in ch else None,
            steering_wheel_rad=ch["steering_wheel_angle_rad"][settle]
            if "steering_wheel_angle_rad" in ch else None)
    res.steady = _try(res, "iso4138_steady_state", steady)


def _iso3888(res: RunAnalysis, ch: Mapping[str, np.ndarray], tick: Progress) -> None:
    """ISO 3888-2 clearance and pass/fail of a double lane change."""
    run, man = res.run, res.run.maneuver
    if man != "double_lane_change":
        res.unavailable["iso3888_lane_change"] = (f"needs a double_lane_change run; this run "
                                                  f"is {man or 'unrecognized'}")
        return
    if _past_limits(res, "iso3888_lane_change"):
        return
    tick(f"{run.name}: lane change")
    res.lane_change = _try(res, "iso3888_lane_change",
                           lambda: lane_change.lane_change_of_run(
                               ch["x_m"], ch["y_m"], run.config["maneuver"]))


def _eigen_sweep(res: RunAnalysis, setting: _LawSetting) -> linearize.EigenSweep | None:
    """The lateral eigenvalues of the linearized 8-DOF closed with the run's law at
    :data:`SWEEP_SPEEDS_MPS`, shared by the runs of one vehicle, law, belief and options
    (:data:`_SWEEP_CACHE`); None if they cannot be computed (``res.unavailable`` says why)."""
    vehicle, belief, options = setting.vehicle, setting.belief, setting.options

    def sweep() -> linearize.EigenSweep:
        rows = [eightdof_linear_system(vehicle, v, res.law, belief, options).poles()
                for v in SWEEP_SPEEDS_MPS]
        width = max(len(_lateral_modes(r)) for r in rows)
        arr = np.full((len(rows), width), np.nan, dtype=complex)
        for k, r in enumerate(rows):
            lat = _lateral_modes(r)
            arr[k, :lat.size] = lat
        return linearize.EigenSweep("8dof", np.asarray(SWEEP_SPEEDS_MPS), arr)
    return _SWEEP_CACHE.get(_law_key(res, vehicle, belief, options),
                            lambda: _try(res, "eigenvalues_vs_speed", sweep))
