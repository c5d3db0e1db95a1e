# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Study files: a base run and the axes it is swept over, validated before anything runs.

A study file (``config/studies/<name>.yaml``)::

    name: robustness_cornering_stiffness
    description: ...
    scenario: default             # scenario name, YAML path, or an inline scenario mapping
    law: fws                      # the law when ``law`` is not an axis (default: the
                                  # scenario's first)
    grid:                         # the cross product of these axes, first slowest
      speed_kmh: {from: 40, to: 160, step: 10}
      belief.cornering_stiffness_scale_front: [0.6, 0.8, 1.0, 1.2, 1.4]
      vehicle.chassis.mass_kg: {scale: [0.9, 1.0, 1.1]}
      law: [fws, sol1, rwc2_3dof]
    monte_carlo:                  # optional: samples drawn per point of the grid
      samples: 1000
      seed: 1996
      fields:
        vehicle.chassis.yaw_inertia_kgm2:
          apply: scale            # value (default) | scale | shift
          distribution: lognormal # normal {mean, std} | uniform {low, high} |
          median: 1.0             # lognormal {median, sigma (of the log)}
          sigma: 0.1
          truncate: [0.7, 1.4]    # optional bounds of the draw (inverse-CDF truncation)
    report:                       # optional (fourws_study.report)
      map_axes: [speed_kmh, belief.cornering_stiffness_scale_front]
      metrics: [max_abs_sideslip_rad, ...]   # numeric result columns (checked)
      worst: {metric: max_abs_sideslip_rad, count: 20}
    block_size: 8                 # optional: points per task

A point is ``spun`` or ``diverged`` by its maneuver's ``vehicle_limits`` (the scenario's or
the maneuver file's, :class:`fourws_sim.outcome.VehicleLimits`: the rule every run follows;
an axis ``maneuver.vehicle_limits.max_sideslip_rad`` sweeps it where the base maneuver
gives ``vehicle_limits``). The former study key ``spin_sideslip_rad`` is refused with that
advice.

Axis keys (the result table's column names) are field paths of the run:

* ``law``; ``speed_mps`` or ``speed_kmh`` (the maneuver's initial speed);
* ``maneuver.<field>`` (any field of the maneuver file, nested with dots);
* ``vehicle.<subsystem>.<field>`` (any vehicle field, :mod:`fourws_sim.params`);
  ``road_friction`` is ``vehicle.tire.friction_coefficient``;
* ``belief.cornering_stiffness_scale_front`` / ``_rear`` (the controller's belief scales,
  ``belief.cornering_stiffness_scale`` sets both) and ``belief.<subsystem>.<field>`` (a
  field of the belief vehicle only).

Several paths joined by commas move together (``vehicle.chassis.mass_kg,
vehicle.roll.sprung_mass_kg`` with ``scale``: a load on the sprung mass); with ``shift`` a
path written ``-path`` moves the other way (``vehicle.chassis.cg_to_front_axle_m,
-vehicle.chassis.cg_to_rear_axle_m``: the CG moves, the wheelbase stays). A grid axis is a
list (values), or ``{values|scale|shift: list or {from, to, step}}``.

Points are numbered 0..N-1: the Monte Carlo sample is the slowest index, then the grid axes
in file order. Every point has a seed: the seed of its sample
(``numpy.random.SeedSequence(seed, spawn_key=(sample,))``); its draws are the inverse CDFs
of uniform numbers from ``numpy.random.default_rng(point seed)``, so a point re-runs exactly
on its own, and the points of one sample (different laws, speeds) share their draws.

:func:`load_study` checks everything before a point runs: unknown keys and paths, empty
axes, malformed values, distributions with bad parameters or that can draw values the field
refuses (give ``truncate``), laws that do not fit the vehicle, and every point's vehicle,
belief and maneuver (all points up to :data:`VALIDATE_ALL_MAX`, else every axis value on its
own). Errors are :class:`~fourws_sim.errors.ParameterError` naming the field and the file.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import numpy as np
import yaml

from fourws_control import make_loop_law
from fourws_control.registry import LAWS
from fourws_run.config import RunConfig, software_versions
from fourws_run.scenario import Scenario, load_scenario, scenario_from_mapping
from fourws_sim.config_yaml import parse_yaml, plain_copy, read_config_text
from fourws_sim.errors import FourwsError, ParameterError, UnknownNameError
from fourws_sim.maneuvers import ManeuverSpec, maneuver_spec_from_mapping
from fourws_sim.models import eightdof
from fourws_sim.params import (CONFIG_DIR, Vehicle, load_vehicle, resolve_config_path,
                               vehicle_from_mapping)

STUDY_DIR = CONFIG_DIR / "studies"
#: Studies larger than this need ``force`` (``fourws study --force``).
MAX_POINTS = 10 ** 6
#: Up to this many points every point's run is built and checked before the study runs.
VALIDATE_ALL_MAX = 20000
#: km/h per m/s.
KMH_PER_MPS = 3.6
#: Ways an axis value acts on its field.
OPS = ("value", "scale", "shift")
DISTRIBUTIONS = {"normal": ("mean", "std"), "uniform": ("low", "high"),
                 "lognormal": ("median", "sigma")}
_FIELDS = ("name", "description", "scenario", "law", "grid", "monte_carlo", "report",
           "block_size")
#: Study keys that are gone, and what says it now.
_REPLACED = {"spin_sideslip_rad": "a run spins by its maneuver's vehicle_limits: give "
                                  "vehicle_limits: {max_sideslip_rad: ...} in the scenario "
                                  "(or its maneuver)"}
#: Default points per task: a few seconds of work at the compiled path's speed.
DEFAULT_BLOCK_SIZE = 16


@dataclass(frozen=True)
class Target:
    """One field an axis sets.

    Attributes
    ----------
    kind : str
        ``law``, ``maneuver``, ``vehicle`` or ``belief``.
    path : tuple of str
        Keys inside its mapping (``("chassis", "mass_kg")``); ``("front",)``/``("rear",)``
        for the belief scales.
    sign : float
        +1, or -1 for a ``-path`` of a linked ``shift``.
    factor : float
        Unit factor from the axis value to the field (1/3.6 for ``speed_kmh``).
    """

    kind: str
    path: tuple[str, ...]
    sign: float = 1.0
    factor: float = 1.0

    @property
    def name(self) -> str:
        """Dotted field name."""
        return ".".join((self.kind, *self.path)) if self.kind != "law" else "law"


@dataclass(frozen=True)
class Distribution:
    """A Monte Carlo distribution, sampled by its inverse CDF.

    Attributes
    ----------
    kind : str
        ``normal`` (``a`` mean, ``b`` std), ``uniform`` (``a`` low, ``b`` high) or
        ``lognormal`` (``a`` median, ``b`` sigma of the log).
    a, b : float
    truncate : tuple of float or None
        Bounds of the draw.
    """

    kind: str
    a: float
    b: float
    truncate: tuple[float, float] | None = None

    def _bounds(self) -> tuple[float, float]:
        """Support of the draw (after truncation)."""
        lo, hi = {"normal": (-math.inf, math.inf), "uniform": (self.a, self.b),
                  "lognormal": (0.0, math.inf)}[self.kind]
        if self.truncate is not None:
            lo, hi = max(lo, self.truncate[0]), min(hi, self.truncate[1])
        return lo, hi

    @property
    def support(self) -> tuple[float, float]:
        """Smallest and largest value it can draw."""
        return self._bounds()

    def _cdf_range(self) -> tuple[float, float]:
        # scipy.special: about 0.2 s to load; only a truncated normal axis needs it
        from scipy.special import ndtr

        lo, hi = self._bounds()
        if self.kind == "uniform":
            return (lo - self.a) / (self.b - self.a), (hi - self.a) / (self.b - self.a)
        if self.kind == "normal":
            return (float(ndtr((lo - self.a) / self.b)), float(ndtr((hi - self.a) / self.b)))
        log_lo = math.log(lo) if lo > 0.0 else -math.inf
        log_hi = math.log(hi) if hi < math.inf else math.inf
        mu = math.log(self.a)
        return float(ndtr((log_lo - mu) / self.b)), float(ndtr((log_hi - mu) / self.b))

    def draw(self, u: float) -> float:
        """The value at uniform number ``u`` in [0, 1) (inverse CDF of the truncated
        distribution)."""
        # scipy.special: about 0.2 s to load; only a truncated normal axis needs it
        from scipy.special import ndtri

        p_lo, p_hi = self._cdf_range()
        p = p_lo + u * (p_hi - p_lo)
        lo, hi = self._bounds()
        if self.kind == "uniform":
            x = self.a + p * (self.b - self.a)
        elif self.kind == "normal":
            x = self.a + self.b * float(ndtri(p))
        else:
            x = math.exp(math.log(self.a) + self.b * float(ndtri(p)))
        return min(max(x, lo), hi)  # the inverse CDF's rounding stays inside the bounds


@dataclass(frozen=True)
class Axis:
    """One grid axis or Monte Carlo field.

    Attributes
    ----------
    key : str
        As written in the file: the result table's column.
    targets : tuple of Target
    op : str
        ``value``, ``scale`` or ``shift``.
    values : tuple
        Grid values (numbers, or law names); empty for a Monte Carlo field.
    distribution : Distribution or None
        Monte Carlo fields only.
    """

    key: str
    targets: tuple[Target, ...]
    op: str = "value"
    values: tuple[Any, ...] = ()
    distribution: Distribution | None = None

    @property
    def numeric(self) -> bool:
        """The axis takes numbers (every axis but ``law``)."""
        return self.targets[0].kind != "law"


@dataclass(frozen=True)
class ReportSpec:
    """What the report draws (``report:`` of the study file; :mod:`fourws_study.report`).

    Attributes
    ----------
    map_axes : tuple of str
        The grid axes of the stability maps and heat maps (x, then y).
    metrics : tuple of str
        Result columns drawn as heat maps (default: by maneuver).
    worst_metric : str
        Column the worst points are ranked by (largest first).
    worst_count : int
        Rows of the worst-points table.
    """

    map_axes: tuple[str, ...] = ()
    metrics: tuple[str, ...] = ()
    worst_metric: str = "max_abs_sideslip_rad"
    worst_count: int = 20


@dataclass(frozen=True)
class MonteCarlo:
    """The ``monte_carlo:`` block: ``samples`` draws of ``fields`` from ``seed``."""

    samples: int
    seed: int
    fields: tuple[Axis, ...]


@dataclass(frozen=True)
class BaseRun:
    """The base run of a study, resolved to plain data (no file is read again).

    Attributes
    ----------
    scenario : Scenario
        The validated scenario (lockstep).
    law : str
        Law of the points when ``law`` is not an axis.
    vehicle_map : dict
        The simulated vehicle as a vehicle-file mapping (tire override applied).
    belief_map : dict or None
        The belief's own vehicle (None: the simulated one).
    belief_scales : tuple of float
        Cornering-stiffness scales of the belief (front, rear).
    maneuver_map : dict
        The maneuver as a maneuver-file mapping.
    """

    scenario: Scenario
    law: str
    vehicle_map: dict[str, Any]
    belief_map: dict[str, Any] | None
    belief_scales: tuple[float, float]
    maneuver_map: dict[str, Any]


@dataclass(frozen=True)
class Point:
    """One point of a study: its number, Monte Carlo sample, seed and axis values."""

    index: int
    sample: int
    seed: int
    values: tuple[tuple[str, Any], ...]

    def value(self, key: str) -> Any:
        """The value of axis ``key``."""
        return dict(self.values)[key]


@dataclass(frozen=True)
class Study:
    """A validated study (see the module docstring)."""

    name: str
    description: str
    source: str
    text: str
    base: BaseRun
    grid: tuple[Axis, ...]
    monte_carlo: MonteCarlo | None
    report: ReportSpec = field(default_factory=ReportSpec)
    block_size: int = DEFAULT_BLOCK_SIZE

    # ---------------------------------------------------------------- points
    @property
    def grid_shape(self) -> tuple[int, ...]:
        """Number of values of each grid axis."""
        return tuple(len(a.values) for a in self.grid)

    @property
    def n_grid(self) -> int:
        """Points of the grid (1 without grid axes)."""
        return int(np.prod(self.grid_shape, dtype=np.int64)) if self.grid else 1

    @property
    def n_samples(self) -> int:
        """Monte Carlo samples (1 without Monte Carlo)."""
        return self.monte_carlo.samples if self.monte_carlo is not None else 1

    @property
    def n_points(self) -> int:
        """Points of the study."""
        return self.n_grid * self.n_samples

    @property
    def axes(self) -> tuple[Axis, ...]:
        """Grid axes, then Monte Carlo fields."""
        return self.grid + (self.monte_carlo.fields if self.monte_carlo is not None else ())

    def sample_seed(self, sample: int) -> int:
        """The seed of Monte Carlo sample ``sample`` (0 <= seed < 2^63)."""
        entropy = self.monte_carlo.seed if self.monte_carlo is not None else 0
        state = np.random.SeedSequence(entropy, spawn_key=(int(sample),)).generate_state(
            1, np.uint64)[0]
        return int(state >> np.uint64(1))

    def draws(self, seed: int) -> tuple[float, ...]:
        """The Monte Carlo field values of a point with seed ``seed`` (file order)."""
        if self.monte_carlo is None:
            return ()
        uniforms = np.random.default_rng(seed).random(len(self.monte_carlo.fields))
        return tuple(ax.distribution.draw(float(u))  # type: ignore[union-attr]
                     for ax, u in zip(self.monte_carlo.fields, uniforms))

    def point(self, index: int) -> Point:
        """Point number ``index`` (0 <= index < n_points)."""
        if not 0 <= index < self.n_points:
            raise ParameterError("point", f"{index} is not a point of study {self.name!r} "
                                 f"(0..{self.n_points - 1})", self.source)
        sample, rest = divmod(int(index), self.n_grid)
        values: list[tuple[str, Any]] = []
        if self.grid:
            for axis, k in zip(self.grid, np.unravel_index(rest, self.grid_shape)):
                values.append((axis.key, axis.values[int(k)]))
        seed = self.sample_seed(sample)
        if self.monte_carlo is not None:
            values += [(ax.key, v) for ax, v in zip(self.monte_carlo.fields, self.draws(seed))]
        return Point(int(index), sample, seed, tuple(values))

    def points(self, indices: Sequence[int] | None = None) -> Iterator[Point]:
        """The points ``indices`` (default all), in order."""
        for i in (range(self.n_points) if indices is None else indices):
            yield self.point(int(i))

    # ---------------------------------------------------------------- runs
    def base_config(self) -> RunConfig:
        """The run with no axis applied (the resolved base run config)."""
        return self._config(())

    def config(self, point: Point) -> RunConfig:
        """The run of ``point``.

        Raises
        ------
        ParameterError
            The point's values make an invalid vehicle, belief or maneuver (the message
            names the point, its values, the field and the study file).
        """
        try:
            return self._config(tuple(zip(self.axes, (v for _, v in point.values))))
        except FourwsError as exc:
            values = ", ".join(f"{k}={_fmt(v)}" for k, v in point.values)
            raise ParameterError(f"point {point.index} ({values})", _problem(exc),
                                 self.source) from None

    @functools.cached_property
    def _base_vehicle(self) -> Vehicle:
        """The base run's vehicle, validated once (points that change no vehicle field)."""
        return vehicle_from_mapping(self.base.vehicle_map, self.source)

    def _config(self, settings: tuple[tuple[Axis, Any], ...]) -> RunConfig:
        base = self.base
        sc = base.scenario
        vehicle_map = None  # copied from the base at the first change
        maneuver_map = plain_copy(base.maneuver_map)
        scales = list(base.belief_scales)
        law = base.law
        belief_changes: list[tuple[Target, str, Any]] = []
        for axis, value in settings:
            for target in axis.targets:
                if target.kind == "law":
                    law = str(value)
                elif target.kind == "maneuver":
                    _apply(maneuver_map, target, axis.op, value)
                elif target.kind == "vehicle":
                    if vehicle_map is None:
                        vehicle_map = plain_copy(base.vehicle_map)
                    _apply(vehicle_map, target, axis.op, value)
                elif target.path in (("front",), ("rear",)):
                    i = 0 if target.path == ("front",) else 1
                    scales[i] = _combine(scales[i], target, axis.op, value)
                else:
                    belief_changes.append((target, axis.op, value))
        source = self.source
        vehicle = (self._base_vehicle if vehicle_map is None
                   else vehicle_from_mapping(vehicle_map, source))
        if base.belief_map is None and not belief_changes:
            belief_vehicle = vehicle
        else:
            belief_map = plain_copy(base.belief_map if base.belief_map is not None
                                    else (base.vehicle_map if vehicle_map is None
                                          else vehicle_map))
            for target, op, value in belief_changes:
                _apply(belief_map, target, op, value)
            belief_vehicle = vehicle_from_mapping(belief_map, source)
        for name, scale in zip(("front", "rear"), scales):
            if not (math.isfinite(scale) and scale > 0.0):
                raise ParameterError(f"belief.cornering_stiffness_scale_{name}",
                                     f"must be > 0, got {scale!r}", source)
        if scales != [1.0, 1.0]:
            belief_vehicle = belief_vehicle.with_axle_tires(scales[0], scales[1])
        maneuver = maneuver_spec_from_mapping(maneuver_map, source,
                                              default_name=sc.maneuver.name)
        _check_runnable_maneuver(maneuver, source)
        return RunConfig(
            vehicle=vehicle, belief=belief_vehicle, maneuver=maneuver, law=law,
            law_options=dict(sc.law_options.get(law, {})), model=sc.model, tire=sc.tire,
            integrator=sc.integrator, integration_step_s=sc.integration_step_s,
            control_period_s=sc.control_period_s, state_period_s=sc.state_period_s,
            clock_mode="lockstep", scenario=sc.name, versions=_versions())

    def to_summary(self) -> dict[str, Any]:
        """Name, size and axes (JSON-ready)."""
        return {"name": self.name, "source": self.source, "points": self.n_points,
                "grid": {a.key: [_jsonable(v) for v in a.values] for a in self.grid},
                "monte_carlo": None if self.monte_carlo is None else {
                    "samples": self.monte_carlo.samples, "seed": self.monte_carlo.seed,
                    "fields": [a.key for a in self.monte_carlo.fields]},
                "block_size": self.block_size}


def _problem(exc: FourwsError) -> str:
    """An error's message without the file it names (the study file is named instead)."""
    if isinstance(exc, ParameterError):
        return f"{exc.field}: {exc.problem}"
    return str(exc)


def _versions() -> dict[str, str]:
    """:func:`fourws_run.config.software_versions`, looked up once per process."""
    global _VERSIONS
    if _VERSIONS is None:
        _VERSIONS = software_versions()
    return dict(_VERSIONS)


_VERSIONS: dict[str, str] | None = None


def _jsonable(value: Any) -> Any:
    return float(value) if isinstance(value, (float, np.floating)) else value


def _fmt(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def _combine(base: float, target: Target, op: str, value: float) -> float:
    if op == "value":
        return float(value) * target.factor
    if op == "scale":
        return base * float(value)
    return base + target.sign * float(value) * target.factor


def _apply(mapping: dict[str, Any], target: Target, op: str, value: Any) -> None:
    """Set ``target``'s field in ``mapping`` (a vehicle or maneuver file mapping)."""
    node = mapping
    for key in target.path[:-1]:
        node = node[key]
    last = target.path[-1]
    node[last] = _combine(node.get(last, 0.0), target, op, value) \
        if op != "value" else float(value) * target.factor


def _check_runnable_maneuver(spec: ManeuverSpec, source: str) -> None:
    """A study point runs once: a step with an unresolved lateral-acceleration target (its
    amplitude depends on the law's runs) is refused."""
    if not getattr(spec.params, "resolved", True):
        raise ParameterError("maneuver.target_lateral_accel_mps2",
                             "a study point runs once; give maneuver.amplitude_rad (or sweep "
                             "it) instead of a target lateral acceleration", source)


# ================================================================================ loading

def available_studies() -> list[str]:
    """Names of the shipped studies (``config/studies``)."""
    return sorted(p.stem for p in STUDY_DIR.glob("*.yaml"))


def load_study(path_or_name: str | Path) -> Study:
    """Load and validate a study by name (``config/studies``) or YAML path.

    Raises
    ------
    ParameterError
        Anything wrong (field and file named), see the module docstring.
    UnknownNameError
        An unknown law, vehicle, maneuver or scenario name.
    """
    path = resolve_config_path("study", path_or_name, STUDY_DIR)
    text = read_config_text(path)
    data = parse_yaml(text, str(path))
    return study_from_mapping(data, str(path), text, default_name=path.stem)


def study_from_mapping(data: Any, source: str = "<study>", text: str = "",
                       default_name: str = "study") -> Study:
    """Validate a study mapping (see :func:`load_study`)."""
    if not isinstance(data, Mapping):
        raise ParameterError("<root>", "a study file must be a mapping", source)
    for key, advice in _REPLACED.items():
        if key in data:
            raise ParameterError(key, f"no longer a study key: {advice}", source)
    unknown = sorted(set(data) - set(_FIELDS))
    if unknown:
        raise ParameterError(unknown[0], f"unknown field (valid: {', '.join(_FIELDS)})",
                             source)
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name:
        raise ParameterError("name", f"must be a non-empty string, got {name!r}", source)
    if "scenario" not in data:
        raise ParameterError("scenario", "missing: a scenario name, path or mapping", source)
    base = _base_run(data, source)
    if not text:
        text = yaml.safe_dump(dict(data), sort_keys=False)
    grid = _grid(data.get("grid"), base, source)
    mc = _monte_carlo(data.get("monte_carlo"), base, source)
    keys = [a.key for a in grid] + ([a.key for a in mc.fields] if mc else [])
    dup = sorted({k for k in keys if keys.count(k) > 1})
    if dup:
        raise ParameterError(f"grid.{dup[0]}", "given twice (grid and monte_carlo)", source)
    block = data.get("block_size", DEFAULT_BLOCK_SIZE)
    if isinstance(block, bool) or not isinstance(block, int) or block < 1:
        raise ParameterError("block_size", f"must be an integer >= 1, got {block!r}", source)
    study = Study(name=name, description=str(data.get("description", "")), source=source,
                  text=text, base=base, grid=grid, monte_carlo=mc,
                  report=_report(data.get("report"), grid, source),
                  block_size=block)
    _validate_points(study)
    return study


def _base_run(data: Mapping[str, Any], source: str) -> BaseRun:
    scen = data["scenario"]
    if isinstance(scen, Mapping):
        scenario = scenario_from_mapping(scen, f"{source} (inline scenario)")
    elif isinstance(scen, str) and scen:
        scenario = load_scenario(scen)
    else:
        raise ParameterError("scenario", f"must be a scenario name, path or mapping, got "
                             f"{scen!r}", source)
    if not scenario.controller.builtin:
        raise ParameterError("scenario.controller", "a study runs fourws's own laws (the "
                             "offline twin); leave the user controller out", source)
    scenario = dataclasses.replace(scenario, clock_mode="lockstep")
    law = data.get("law", scenario.laws[0])
    if not isinstance(law, str) or law not in LAWS:
        raise UnknownNameError("law", str(law), list(LAWS))
    vehicle = scenario.build_vehicle()
    belief_map = None
    if scenario.belief.vehicle is not None:
        belief_map = load_vehicle(scenario.belief.vehicle).to_dict()
    return BaseRun(scenario, law, vehicle.to_dict(), belief_map,
                   (scenario.belief.cornering_stiffness_scale_front,
                    scenario.belief.cornering_stiffness_scale_rear),
                   scenario.maneuver.to_dict())


# ---------------------------------------------------------------- axis keys

def _targets(key: Any, base: BaseRun, op: str, where: str, source: str) -> tuple[Target, ...]:
    """The fields an axis key names (validated against the base run's mappings)."""
    if not isinstance(key, str) or not key.strip():
        raise ParameterError(where, f"an axis key must be a field path, got {key!r}", source)
    parts = [p.strip() for p in key.split(",")]
    targets: list[Target] = []
    for part in parts:
        sign = 1.0
        if part.startswith("-"):
            if op != "shift":
                raise ParameterError(where, f"{part!r}: a '-' path only moves the other way "
                                     "with shift", source)
            sign, part = -1.0, part[1:].strip()
        for t in _path_targets(part, base, f"{where} ({part})", source):
            targets.append(dataclasses.replace(t, sign=sign))
    kinds = {t.kind for t in targets}
    if "law" in kinds and len(targets) > 1:
        raise ParameterError(where, "law cannot be linked with other fields", source)
    if "law" in kinds and op != "value":
        raise ParameterError(where, "law takes values (law names), not scale or shift",
                             source)
    return tuple(targets)


def _path_targets(path: str, base: BaseRun, where: str, source: str) -> list[Target]:
    if path == "law":
        return [Target("law", ())]
    if path in ("speed_mps", "speed_kmh"):
        return [Target("maneuver", ("initial_speed_mps",),
                       factor=1.0 if path == "speed_mps" else 1.0 / KMH_PER_MPS)]
    if path == "road_friction":
        path = "vehicle.tire.friction_coefficient"
    if path == "belief.cornering_stiffness_scale":
        return [Target("belief", ("front",)), Target("belief", ("rear",))]
    if path in ("belief.cornering_stiffness_scale_front", "belief.cornering_stiffness_scale_rear"):
        return [Target("belief", (path.rsplit("_", 1)[1],))]
    kind, _, rest = path.partition(".")
    keys = tuple(rest.split(".")) if rest else ()
    if kind not in ("vehicle", "maneuver", "belief") or not keys or not all(keys):
        raise ParameterError(where, "unknown field path (valid: law, speed_mps, speed_kmh, "
                             "road_friction, maneuver.<field>, vehicle.<subsystem>.<field>, "
                             "belief.cornering_stiffness_scale[_front|_rear], "
                             "belief.<subsystem>.<field>)", source)
    mapping = base.maneuver_map if kind == "maneuver" else (
        base.belief_map if kind == "belief" and base.belief_map is not None
        else base.vehicle_map)
    node: Any = mapping
    for i, k in enumerate(keys):
        if not isinstance(node, Mapping) or k not in node:
            have = sorted(node) if isinstance(node, Mapping) else []
            raise ParameterError(where, f"{'.'.join((kind, *keys[:i + 1]))} is not a field of "
                                 f"the base run's {kind if kind != 'belief' else 'belief vehicle'}"
                                 f" (valid here: {', '.join(map(str, have))})", source)
        node = node[k]
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        raise ParameterError(where, f"{path} is not a number in the base run (it is "
                             f"{node!r}); only numeric fields can be swept", source)
    return [Target(kind, keys)]


def _field_check(base: BaseRun, target: Target) -> str:
    """Range check of a vehicle field (``positive``, ``nonnegative``, ``fraction``, ``any``),
    '' when unknown (maneuver fields: their own validation decides)."""
    if target.kind not in ("vehicle", "belief") or len(target.path) != 2:
        return ""
    mapping = base.vehicle_map if target.kind == "vehicle" or base.belief_map is None \
        else base.belief_map
    vehicle = vehicle_from_mapping(mapping, "<base>")
    sub = getattr(vehicle, target.path[0], None)
    if sub is None or not dataclasses.is_dataclass(sub):
        return ""
    for f in dataclasses.fields(sub):
        if f.name == target.path[1]:
            return str(f.metadata.get("check", ""))
    return ""


# ---------------------------------------------------------------- grid

def _number(value: Any, where: str, source: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value):
        raise ParameterError(where, f"must be a finite number, got {value!r}", source)
    return float(value)


def _values(spec: Any, where: str, source: str, numeric: bool) -> tuple[Any, ...]:
    if isinstance(spec, Mapping) and set(spec) <= {"from", "to", "step"} and spec:
        missing = [k for k in ("from", "to", "step") if k not in spec]
        if missing:
            raise ParameterError(f"{where}.{missing[0]}", "missing (a range needs from, to, "
                                 "step)", source)
        lo, hi, step = (_number(spec[k], f"{where}.{k}", source) for k in ("from", "to", "step"))
        if step <= 0.0 or hi < lo:
            raise ParameterError(where, f"from {lo:g} to {hi:g} by {step:g}: needs step > 0 "
                                 "and to >= from", source)
        n = int(math.floor((hi - lo) / step + 1e-9)) + 1
        return tuple(lo + k * step for k in range(n))
    if not isinstance(spec, (list, tuple)):
        raise ParameterError(where, f"must be a list of values or {{from, to, step}}, got "
                             f"{spec!r}", source)
    if not spec:
        raise ParameterError(where, "is empty: an axis needs at least one value", source)
    if numeric:
        return tuple(_number(v, f"{where}[{i}]", source) for i, v in enumerate(spec))
    return tuple(spec)


def _grid(data: Any, base: BaseRun, source: str) -> tuple[Axis, ...]:
    if data is None:
        return ()
    if not isinstance(data, Mapping):
        raise ParameterError("grid", "must map field paths to values", source)
    axes = []
    for key, spec in data.items():
        where = f"grid.{key}"
        op = "value"
        if isinstance(spec, Mapping) and not set(spec) <= {"from", "to", "step"}:
            ops = [o for o in OPS if o in spec]
            extra = sorted(set(spec) - set(OPS) - {"values"})
            if extra or len(ops) + ("values" in spec) != 1:
                raise ParameterError(where, "must be a list, {from, to, step}, or one of "
                                     "{values: ...}, {scale: ...}, {shift: ...}", source)
            op = ops[0] if ops else "value"
            spec = spec[op if ops else "values"]
        targets = _targets(key, base, op, where, source)
        numeric = targets[0].kind != "law"
        values = _values(spec, where, source, numeric)
        if not numeric:
            for v in values:
                if not isinstance(v, str) or v not in LAWS:
                    raise ParameterError(where, f"{v!r} is not a law (valid: "
                                         f"{', '.join(sorted(LAWS))})", source)
        if len(set(values)) != len(values):
            raise ParameterError(where, "lists a value twice", source)
        axes.append(Axis(str(key), targets, op, values))
    return tuple(axes)


# ---------------------------------------------------------------- Monte Carlo

def _distribution(spec: Mapping[str, Any], where: str, source: str) -> Distribution:
    kind = spec.get("distribution")
    if kind not in DISTRIBUTIONS:
        raise ParameterError(f"{where}.distribution", f"must be one of "
                             f"{', '.join(DISTRIBUTIONS)}, got {kind!r}", source)
    names = DISTRIBUTIONS[kind]
    extra = sorted(set(spec) - {"distribution", "apply", "truncate", *names})
    if extra:
        raise ParameterError(f"{where}.{extra[0]}", f"unknown for a {kind} distribution "
                             f"(valid: {', '.join(names)}, truncate, apply)", source)
    for n in names:
        if n not in spec:
            raise ParameterError(f"{where}.{n}", f"missing (a {kind} distribution needs "
                                 f"{' and '.join(names)})", source)
    a, b = (_number(spec[n], f"{where}.{n}", source) for n in names)
    if kind == "normal" and b <= 0.0:
        raise ParameterError(f"{where}.std", f"must be > 0, got {b!r}", source)
    if kind == "uniform" and not b > a:
        raise ParameterError(f"{where}.high", f"must exceed low ({a:g}), got {b!r}", source)
    if kind == "lognormal" and not (a > 0.0 and b > 0.0):
        raise ParameterError(where, f"a lognormal needs median > 0 and sigma > 0, got "
                             f"{a!r}, {b!r}", source)
    trunc = spec.get("truncate")
    bounds = None
    if trunc is not None:
        if not isinstance(trunc, (list, tuple)) or len(trunc) != 2:
            raise ParameterError(f"{where}.truncate", f"must be [low, high], got {trunc!r}",
                                 source)
        lo, hi = (_number(v, f"{where}.truncate", source) for v in trunc)
        if not hi > lo:
            raise ParameterError(f"{where}.truncate", f"needs high > low, got {trunc!r}",
                                 source)
        bounds = (lo, hi)
    dist = Distribution(kind, a, b, bounds)
    lo, hi = dist.support
    p_lo, p_hi = dist._cdf_range()
    if not hi > lo or not p_hi - p_lo > 1e-12:
        raise ParameterError(f"{where}.truncate", f"leaves nothing to draw from the {kind} "
                             "distribution", source)
    return dist


_CHECKS = {"positive": (lambda v: v > 0.0, "> 0"), "nonnegative": (lambda v: v >= 0.0, ">= 0"),
           "fraction": (lambda v: 0.0 <= v <= 1.0, "within [0, 1]")}


def _monte_carlo(data: Any, base: BaseRun, source: str) -> MonteCarlo | None:
    if data is None:
        return None
    if not isinstance(data, Mapping):
        raise ParameterError("monte_carlo", "must be a mapping with samples, seed, fields",
                             source)
    extra = sorted(set(data) - {"samples", "seed", "fields"})
    if extra:
        raise ParameterError(f"monte_carlo.{extra[0]}", "unknown field (valid: samples, "
                             "seed, fields)", source)
    samples = data.get("samples")
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ParameterError("monte_carlo.samples", f"must be an integer >= 1, got "
                             f"{samples!r}", source)
    seed = data.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ParameterError("monte_carlo.seed", f"must be an integer >= 0, got {seed!r}",
                             source)
    fields = data.get("fields")
    if not isinstance(fields, Mapping) or not fields:
        raise ParameterError("monte_carlo.fields", "must map field paths to distributions "
                             "(at least one)", source)
    axes = []
    for key, spec in fields.items():
        where = f"monte_carlo.fields.{key}"
        if not isinstance(spec, Mapping):
            raise ParameterError(where, "must be a distribution mapping", source)
        op = spec.get("apply", "value")
        if op not in OPS:
            raise ParameterError(f"{where}.apply", f"must be one of {', '.join(OPS)}, got "
                                 f"{op!r}", source)
        targets = _targets(key, base, op, where, source)
        if targets[0].kind == "law":
            raise ParameterError(where, "law is a grid axis, not a distribution", source)
        dist = _distribution(spec, where, source)
        lo, hi = dist.support
        for t in targets:
            check = _field_check(base, t)
            if check not in _CHECKS:
                continue
            base_value = _base_value(base, t)
            # the log-normal's 0 is an open bound: it draws values > 0 only
            ends = [_combine(base_value, t, op, v) for v in (lo, hi)
                    if not (dist.kind == "lognormal" and v == 0.0)]
            ok, rel = _CHECKS[check]
            for e in ends:
                if not ok(e):
                    raise ParameterError(where, f"can draw {t.name} = {e:g}, which must be "
                                         f"{rel}; give truncate: [low, high]", source)
        axes.append(Axis(str(key), targets, op, (), dist))
    return MonteCarlo(samples, seed, tuple(axes))


def _base_value(base: BaseRun, target: Target) -> float:
    if target.kind == "belief" and target.path in (("front",), ("rear",)):
        return base.belief_scales[0 if target.path == ("front",) else 1]
    mapping = base.maneuver_map if target.kind == "maneuver" else (
        base.belief_map if target.kind == "belief" and base.belief_map is not None
        else base.vehicle_map)
    node: Any = mapping
    for k in target.path:
        node = node[k]
    return float(node)


# ---------------------------------------------------------------- report

def _report(data: Any, grid: tuple[Axis, ...], source: str) -> ReportSpec:
    numeric = [a.key for a in grid if a.numeric and len(a.values) > 1]
    if data is None:
        return ReportSpec(map_axes=tuple(numeric[:2]))
    if not isinstance(data, Mapping):
        raise ParameterError("report", "must be a mapping", source)
    extra = sorted(set(data) - {"map_axes", "metrics", "worst"})
    if extra:
        raise ParameterError(f"report.{extra[0]}", "unknown field (valid: map_axes, metrics, "
                             "worst)", source)
    axes = data.get("map_axes", numeric[:2])
    if not isinstance(axes, (list, tuple)) or len(axes) > 2:
        raise ParameterError("report.map_axes", f"must list up to two grid axes, got "
                             f"{axes!r}", source)
    for a in axes:
        if a not in numeric:
            raise ParameterError("report.map_axes", f"{a!r} is not a numeric grid axis with "
                                 f"several values (valid: {', '.join(numeric)})", source)
    metrics = data.get("metrics", [])
    if not isinstance(metrics, (list, tuple)) or not all(isinstance(m, str) for m in metrics):
        raise ParameterError("report.metrics", "must be a list of result columns", source)
    worst = data.get("worst", {})
    if not isinstance(worst, Mapping) or set(worst) - {"metric", "count"}:
        raise ParameterError("report.worst", "must be {metric: column, count: n}", source)
    count = worst.get("count", 20)
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise ParameterError("report.worst.count", f"must be an integer >= 1, got {count!r}",
                             source)
    metric = worst.get("metric", "max_abs_sideslip_rad")
    if not isinstance(metric, str):
        raise ParameterError("report.worst.metric", "must be a result column name", source)
    return ReportSpec(tuple(axes), tuple(metrics), metric, count)


# ---------------------------------------------------------------- points

def _validate_points(study: Study) -> None:
    """Build and check the runs of the study before any of it runs (module docstring)."""
    base = study.base
    sc = base.scenario

    def check(config: RunConfig) -> None:
        if config.model == "8dof":
            p = eightdof.params_for(config.vehicle, config.tire)
            eightdof.check_step(p, config.integration_step_s, config.integrator,
                                study.source)

    base_config = study.base_config()
    laws = {base.law}
    for axis in study.grid:
        if not axis.numeric:
            laws |= set(axis.values)
    for law in sorted(laws):
        try:
            make_loop_law(law, base_config.belief, sc.controller_period_s,
                          sc.law_options.get(law))
        except FourwsError as exc:
            raise ParameterError("law", f"{law}: {_problem(exc)}", study.source) from None
    check(base_config)
    if study.n_points <= VALIDATE_ALL_MAX:
        # the law changes no vehicle, belief scale or maneuver: one point per other values
        seen = set()
        for point in study.points():
            key = tuple(v for k, v in point.values if k != "law")
            if key not in seen:
                seen.add(key)
                check(study.config(point))
        return
    # too many to build each: every grid value on its own, and the ends of each draw
    for axis in study.grid:
        for value in axis.values:
            _check_single(study, axis, value, check)
    if study.monte_carlo is not None:
        for axis in study.monte_carlo.fields:
            assert axis.distribution is not None
            for value in axis.distribution.support:
                if math.isfinite(value):
                    _check_single(study, axis, value, check)


def _check_single(study: Study, axis: Axis, value: Any, check: Any) -> None:
    try:
        check(study._config(((axis, value),)))
    except FourwsError as exc:
        raise ParameterError(f"{axis.key} = {_fmt(value)}", _problem(exc),
                             study.source) from None


__all__ = ["Axis", "BaseRun", "DISTRIBUTIONS", "Distribution", "MAX_POINTS", "MonteCarlo",
           "OPS", "Point", "ReportSpec", "STUDY_DIR", "Study", "Target", "VALIDATE_ALL_MAX",
           "available_studies", "load_study", "study_from_mapping"]
