"""Vehicle parameters: frozen, validated dataclasses per subsystem, loaded from YAML.

A vehicle file (``config/vehicles/<name>.yaml``) is a mapping with one key per subsystem::

    name: table_4_1_set_1
    description: ...
    chassis: {mass_kg: ..., yaw_inertia_kgm2: ..., cg_to_front_axle_m: ..., ...}
    axle_tires: {cornering_stiffness_front_n_per_rad: ..., ...}
    roll: {...}          # optional: 3-DOF and 8-DOF models
    steering: {...}      # optional: free-control model, steering ratio of the 8-DOF
    tire: {...}          # optional: nonlinear tire choice and coefficients
    body: {...}          # optional: 8-DOF spread-tire geometry, wheels
    actuators: {...}     # optional: rear-steer limits (defaults apply when absent)

The same mapping may also sit under ``/**: ros__parameters: vehicle:`` (a ROS 2 parameter
file); :func:`load_vehicle` accepts both layouts. All values are SI (kg, m, s, rad, N);
the unit is part of every field name. A subsystem may declare file shorthands
(``SHORTHANDS``): ``tire.relaxation_length_m`` sets ``relaxation_length_front_m`` and
``relaxation_length_rear_m`` (one sigma for both axles, as the paper gives it).

Which subsystems a model needs is checked by the model (``Vehicle.require``), so a 2-DOF data
set with no roll data is a valid vehicle that a 3-DOF model refuses with a clear message.
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Mapping

import yaml

from fourws_sim.errors import ParameterError, UnknownNameError

def find_resource_dir(beside: Path, package: str, sub: str, marker: str) -> Path:
    """A folder shipped with fourws: ``beside`` in a checkout or an editable install, else
    ``share/<package>/<sub>`` of an installed package (``colcon build`` without
    ``--symlink-install``), searched along ``AMENT_PREFIX_PATH`` and this interpreter's prefix.
    ``marker`` is a name (glob) the folder must contain."""
    if any(beside.glob(marker)):
        return beside
    prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    for prefix in (*prefixes, sys.prefix):
        candidate = Path(prefix) / "share" / package / sub
        if any(candidate.glob(marker)):
            return candidate
    return beside


#: Folder holding the shipped configuration (vehicles, maneuvers, scenarios, node parameters).
CONFIG_DIR = find_resource_dir(Path(__file__).resolve().parent.parent / "config", "fourws",
                               "config", "vehicles")
VEHICLE_DIR = CONFIG_DIR / "vehicles"

GRAVITY_MPS2 = 9.80665
#: Number of wheels of the vehicles fourws models; every per-wheel array is ordered FL, FR, RL,
#: RR.
N_WHEELS = 4


def _spec(check: str = "positive", doc: str = "", default: Any = dataclasses.MISSING) -> Any:
    """Declare a float field with a range check ("positive", "nonnegative", "any", "fraction")."""
    meta = {"check": check, "doc": doc}
    if default is dataclasses.MISSING:
        return field(metadata=meta)
    return field(default=default, metadata=meta)


_CHECKS = {
    "positive": (lambda v: v > 0.0, "must be > 0"),
    "nonnegative": (lambda v: v >= 0.0, "must be >= 0"),
    "any": (lambda v: True, ""),
    "fraction": (lambda v: 0.0 <= v <= 1.0, "must be within [0, 1]"),
}


def _check_value(value: Any, f: dataclasses.Field[Any], name: str,
                 source: str | None) -> float:
    """``value`` as a float if it passes the range check of field ``f``, else ParameterError
    naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(name, f"must be a number, got {value!r}", source)
    value = float(value)
    if not math.isfinite(value):
        raise ParameterError(name, f"must be finite, got {value!r}", source)
    ok, msg = _CHECKS[f.metadata["check"]]
    if not ok(value):
        raise ParameterError(name, f"{msg}, got {value!r}", source)
    return value


def _validate_dataclass(obj: Any, source: str | None, prefix: str) -> None:
    for f in dataclasses.fields(obj):
        if f.metadata.get("check") is None:
            continue
        value = _check_value(getattr(obj, f.name), f, f"{prefix}{f.name}", source)
        object.__setattr__(obj, f.name, value)


def _expand_shorthands(cls: type, data: Mapping[str, Any], source: str | None,
                       prefix: str) -> Mapping[str, Any]:
    """Replace a file's shorthand keys (``cls.SHORTHANDS``: key -> the fields it sets) by the
    fields they stand for; a shorthand given together with one of its fields is an error (the
    file would state one fact twice)."""
    shorthands: Mapping[str, tuple[str, ...]] = getattr(cls, "SHORTHANDS", {})
    if not any(key in data for key in shorthands):
        return data
    out = dict(data)
    for key, targets in shorthands.items():
        if key not in out:
            continue
        both = [t for t in targets if t in out]
        if both:
            raise ParameterError(f"{prefix}{key}",
                                 f"sets {' and '.join(targets)}; give either it or "
                                 f"{both[0]}, not both", source)
        value = out.pop(key)
        _check_value(value, next(f for f in dataclasses.fields(cls) if f.name == targets[0]),
                     f"{prefix}{key}", source)  # an error names the key the file has
        for target in targets:
            out[target] = value
    return out


def _from_mapping(cls: type, data: Any, source: str | None, prefix: str) -> Any:
    """Build dataclass ``cls`` from a mapping, rejecting unknown and missing fields."""
    if not isinstance(data, Mapping):
        raise ParameterError(prefix.rstrip(".") or "<root>", "must be a mapping", source)
    names = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - set(names) - set(getattr(cls, "SHORTHANDS", {})))
    if unknown:
        raise ParameterError(
            f"{prefix}{unknown[0]}",
            f"unknown field (valid: "
            f"{', '.join(sorted([*names, *getattr(cls, 'SHORTHANDS', {})]))})",
            source,
        )
    data = _expand_shorthands(cls, data, source, prefix)
    kwargs: dict[str, Any] = {}
    for name, f in names.items():
        if name in data:
            kwargs[name] = data[name]
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ParameterError(f"{prefix}{name}", "missing required field", source)
    try:
        obj = cls(**kwargs)
    except ParameterError:
        raise
    _validate_dataclass(obj, source, prefix)
    post = getattr(obj, "_check", None)
    if post is not None:
        post(source, prefix)
    return obj


@dataclass(frozen=True)
class Chassis:
    """Whole-vehicle mass properties and axle positions (every model needs these)."""

    mass_kg: float = _spec(doc="total vehicle mass m")
    yaw_inertia_kgm2: float = _spec(doc="yaw moment of inertia Iz about the CG")
    cg_to_front_axle_m: float = _spec(doc="a = Lf, CG to front axle")
    cg_to_rear_axle_m: float = _spec(doc="b = Lr, CG to rear axle")

    @property
    def wheelbase_m(self) -> float:
        """Wheelbase L = a + b in m."""
        return self.cg_to_front_axle_m + self.cg_to_rear_axle_m


@dataclass(frozen=True)
class AxleTires:
    """Linear (small-slip) tire data per axle, used by the linear models and the laws.

    Cornering stiffness is per axle (both tires together): the lateral force of the axle is
    ``F = -C * alpha`` for slip angle ``alpha`` in rad.
    """

    cornering_stiffness_front_n_per_rad: float = _spec(doc="Cf, front axle")
    cornering_stiffness_rear_n_per_rad: float = _spec(doc="Cr, rear axle")


@dataclass(frozen=True)
class Roll:
    """Sprung-mass roll data (3-DOF linear model and 8-DOF model)."""

    sprung_mass_kg: float = _spec(doc="ms")
    roll_inertia_kgm2: float = _spec(doc="Ix of the sprung mass about the roll axis")
    roll_yaw_product_kgm2: float = _spec("any", doc="Ixz product of inertia of the sprung mass")
    roll_arm_m: float = _spec(doc="h, sprung-mass CG above the roll axis")
    roll_stiffness_front_nm_per_rad: float = _spec("nonnegative", doc="K_phi,f")
    roll_stiffness_rear_nm_per_rad: float = _spec("nonnegative", doc="K_phi,r")
    roll_damping_front_nms_per_rad: float = _spec("nonnegative", doc="C_phi,f")
    roll_damping_rear_nms_per_rad: float = _spec("nonnegative", doc="C_phi,r")
    roll_steer_front: float = _spec("any", doc="eps_f, front road-wheel steer per roll, rad/rad")
    roll_steer_rear: float = _spec("any", doc="eps_r, rear road-wheel steer per roll, rad/rad")

    @property
    def roll_stiffness_nm_per_rad(self) -> float:
        """Total roll stiffness K_phi in N m/rad."""
        return self.roll_stiffness_front_nm_per_rad + self.roll_stiffness_rear_nm_per_rad

    @property
    def roll_damping_nms_per_rad(self) -> float:
        """Total roll damping C_phi in N m s/rad."""
        return self.roll_damping_front_nms_per_rad + self.roll_damping_rear_nms_per_rad


@dataclass(frozen=True)
class Steering:
    """Steering system: ratio, and the free-control first-order dynamics (ch. 3.4/4.4)."""

    ratio: float = _spec(doc="steering-wheel angle per front road-wheel angle")
    damping_nms_per_rad: float = _spec("nonnegative", default=0.0,
                                       doc="nu, viscous damping about the kingpin")
    trail_m: float = _spec("nonnegative", default=0.0, doc="eta, caster/pneumatic trail")


@dataclass(frozen=True)
class Tire:
    """Nonlinear tire choice and its coefficients (8-DOF and nonlinear 2-DOF models).

    Relaxation length (stretched-string lag of the side force, ch. 5) per axle: a car whose
    axles carry different loads has different tire lag. In a file, ``relaxation_length_m``
    is the shorthand for one value on both axles (the paper's single sigma, Table 5.1); it
    may not be given together with a per-axle field.
    """

    #: File keys that stand for several fields (expanded by the loader, see the docstring).
    SHORTHANDS: ClassVar[Mapping[str, tuple[str, ...]]] = {
        "relaxation_length_m": ("relaxation_length_front_m", "relaxation_length_rear_m"),
    }

    model: str = "linear"
    friction_coefficient: float = _spec(default=1.0, doc="mu, peak friction (linear model)")
    relaxation_length_front_m: float = _spec(
        "nonnegative", default=0.0, doc="sigma_f, relaxation length of a front tire, 0 = no lag")
    relaxation_length_rear_m: float = _spec(
        "nonnegative", default=0.0, doc="sigma_r, relaxation length of a rear tire, 0 = no lag")
    cubic_coefficient_front_per_rad2: float = _spec(
        "nonnegative", default=0.0, doc="K of F = -C(1 - K alpha^2) alpha, front (ch. 7)")
    cubic_coefficient_rear_per_rad2: float = _spec(
        "nonnegative", default=0.0, doc="K of F = -C(1 - K alpha^2) alpha, rear (ch. 7)")
    longitudinal_stiffness_n: float = _spec(
        "nonnegative", default=0.0,
        doc="C_s per tire, N per unit slip ratio (linear model; 0 = derive 1.5 x per-tire Calpha)")
    rolling_resistance: float = _spec("nonnegative", default=0.0,
                                      doc="f_r, rolling-resistance force per normal load")
    sti: Mapping[str, float] = field(default_factory=dict)
    magic_formula: Mapping[str, float] = field(default_factory=dict)

    def _check(self, source: str | None, prefix: str) -> None:
        valid = ("linear", "sti", "magic_formula")
        if self.model not in valid:
            raise ParameterError(f"{prefix}model",
                                 f"unknown tire model {self.model!r} (valid: {', '.join(valid)})",
                                 source)
        for group in ("sti", "magic_formula"):
            values = getattr(self, group)
            if not isinstance(values, Mapping):
                raise ParameterError(f"{prefix}{group}", "must be a mapping", source)
            for key, v in values.items():
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise ParameterError(f"{prefix}{group}.{key}",
                                         f"must be a finite number, got {v!r}", source)


@dataclass(frozen=True)
class Body:
    """Spread-tire geometry and wheels of the 8-DOF model (ch. 8)."""

    track_front_m: float = _spec(doc="Tf")
    track_rear_m: float = _spec(doc="Tr")
    cg_height_m: float = _spec(doc="total-mass CG height above ground (longitudinal transfer)")
    roll_centre_height_front_m: float = _spec("nonnegative", doc="front roll-centre height")
    roll_centre_height_rear_m: float = _spec("nonnegative", doc="rear roll-centre height")
    unsprung_cg_height_m: float = _spec("nonnegative", doc="unsprung-mass CG height")
    wheel_radius_m: float = _spec(doc="loaded rolling radius")
    wheel_spin_inertia_kgm2: float = _spec(doc="Iw, one wheel about its spin axis")


@dataclass(frozen=True)
class Actuators:
    """Rear-steer actuator limits (defaults: 5 deg, 30 deg/s; production 4WS systems stay
    within a few degrees of rear steer)."""

    rear_angle_limit_rad: float = _spec(default=math.radians(5.0), doc="|delta_r| max")
    rear_rate_limit_rad_per_s: float = _spec(default=math.radians(30.0), doc="|d delta_r/dt|")


_SUBSYSTEMS: dict[str, type] = {
    "chassis": Chassis,
    "axle_tires": AxleTires,
    "roll": Roll,
    "steering": Steering,
    "tire": Tire,
    "body": Body,
    "actuators": Actuators,
}
_REQUIRED = ("chassis", "axle_tires")


@dataclass(frozen=True)
class Vehicle:
    """A complete vehicle: the subsystems a file gives (optional ones may be ``None``)."""

    name: str
    chassis: Chassis
    axle_tires: AxleTires
    roll: Roll | None = None
    steering: Steering | None = None
    tire: Tire | None = None
    body: Body | None = None
    actuators: Actuators = field(default_factory=Actuators)
    description: str = ""
    source: str = field(default="", compare=False)

    def require(self, *subsystems: str, user: str = "this model") -> None:
        """Raise :class:`ParameterError` unless every named subsystem is present."""
        for name in subsystems:
            if getattr(self, name) is None:
                raise ParameterError(name, f"missing; {user} needs it", self.source or self.name)

    @property
    def understeer_gradient_rad_per_mps2(self) -> float:
        """K_us = m/L (b/Cf - a/Cr) in rad/(m/s^2); > 0 understeer (axle cornering stiffness)."""
        c, t = self.chassis, self.axle_tires
        return c.mass_kg / c.wheelbase_m * (
            c.cg_to_rear_axle_m / t.cornering_stiffness_front_n_per_rad
            - c.cg_to_front_axle_m / t.cornering_stiffness_rear_n_per_rad)

    def with_axle_tires(self, scale_front: float, scale_rear: float | None = None) -> "Vehicle":
        """Copy with cornering stiffnesses scaled (e.g. a controller's ±40 % belief)."""
        s_r = scale_front if scale_rear is None else scale_rear
        t = self.axle_tires
        new = AxleTires(t.cornering_stiffness_front_n_per_rad * scale_front,
                        t.cornering_stiffness_rear_n_per_rad * s_r)
        _validate_dataclass(new, self.source, "axle_tires.")
        return dataclasses.replace(self, axle_tires=new)

    def to_dict(self) -> dict[str, Any]:
        """Plain mapping in the file layout (for recording a run's configuration)."""
        out: dict[str, Any] = {"name": self.name, "description": self.description}
        for key in _SUBSYSTEMS:
            sub = getattr(self, key)
            if sub is not None:
                out[key] = {k: (dict(v) if isinstance(v, Mapping) else v)
                            for k, v in dataclasses.asdict(sub).items()}
        return out


def vehicle_from_mapping(data: Any, source: str = "<mapping>") -> Vehicle:
    """Validate a vehicle mapping (file layout) and build a :class:`Vehicle`.

    Raises
    ------
    ParameterError
        On a missing or unknown field, a non-number, a non-finite or out-of-range value.
    """
    if isinstance(data, Mapping) and "/**" in data:
        try:
            data = data["/**"]["ros__parameters"]["vehicle"]
        except (KeyError, TypeError):
            raise ParameterError("/**.ros__parameters.vehicle", "missing", source) from None
    if not isinstance(data, Mapping):
        raise ParameterError("<root>", "vehicle file must be a mapping", source)
    allowed = set(_SUBSYSTEMS) | {"name", "description"}
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise ParameterError(unknown[0], f"unknown field (valid: {', '.join(sorted(allowed))})",
                             source)
    for key in ("name", *_REQUIRED):
        if key not in data:
            raise ParameterError(key, "missing required field", source)
    name = data["name"]
    if not isinstance(name, str) or not name:
        raise ParameterError("name", "must be a non-empty string", source)
    subs = {key: _from_mapping(cls, data[key], source, f"{key}.")
            for key, cls in _SUBSYSTEMS.items() if key in data and data[key] is not None}
    return Vehicle(name=name, description=str(data.get("description", "")), source=source,
                   **subs)


def available_configs(folder: Path) -> list[str]:
    """Names (file stems) of the YAML files in a config folder."""
    return sorted(p.stem for p in folder.glob("*.yaml"))


def resolve_config_path(kind: str, name_or_path: str | Path, folder: Path) -> Path:
    """Turn a config name (file stem under ``folder``) or a path into the path of its file.

    Raises
    ------
    ParameterError
        A path (``.yaml``/``.yml`` or existing) that is not a file.
    UnknownNameError
        A name with no file under ``folder`` (the message lists the valid names).
    """
    text = str(name_or_path)
    path = Path(text)
    if path.suffix in (".yaml", ".yml") or path.exists():
        if not path.is_file():
            raise ParameterError(kind, f"no such file {text!r}")
        return path
    candidate = folder / f"{text}.yaml"
    if not candidate.is_file():
        raise UnknownNameError(kind, text, available_configs(folder))
    return candidate


def read_yaml(path: Path) -> Any:
    """Parse a YAML file; invalid YAML is a :class:`ParameterError` naming the file."""
    try:
        return yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ParameterError("<file>", f"not valid YAML ({exc})", str(path)) from None


def available_vehicles() -> list[str]:
    """Names (file stems) of the shipped vehicle files."""
    return available_configs(VEHICLE_DIR)


def resolve_vehicle_path(name_or_path: str | Path) -> Path:
    """Turn a vehicle name (file stem under ``config/vehicles``) or a path into a path."""
    return resolve_config_path("vehicle", name_or_path, VEHICLE_DIR)


def load_vehicle(name_or_path: str | Path) -> Vehicle:
    """Load and validate a vehicle by name (``table_8_1``) or by YAML path."""
    path = resolve_vehicle_path(name_or_path)
    return vehicle_from_mapping(read_yaml(path), str(path))
