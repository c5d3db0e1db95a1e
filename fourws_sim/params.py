# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
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
    aero: {...}          # optional: 8-DOF aerodynamic drag and lift (absent: none)
    driveline: {...}     # optional: driven axles, torque split, differentials
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
import functools
import json
import math
import os
import sys
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Mapping

from fourws_sim.config_yaml import plain_copy, read_yaml
from fourws_sim.errors import ParameterError, UnknownNameError, describe
from fourws_sim.tires import TIRES, get_tire


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

# Plausibility bounds (see docs/architecture.md, "Parameters"). Vehicle fields carry theirs in
# their declaration (``_spec(bounds=...)``); these are the ones shared across modules.
#: Fastest forward speed of any vehicle, maneuver or analysis, m/s (540 km/h).
MAX_SPEED_MPS = 150.0
#: Largest rear road-wheel angle limit an actuator may have, rad (45 deg).
MAX_REAR_ANGLE_RAD = math.pi / 4
#: Largest rear-steer rate limit, rad/s.
MAX_REAR_RATE_RADPS = 10.0
#: Magnitude bound of fitted tire coefficients (``tire.sti``, ``tire.magic_formula``).
TIRE_COEFFICIENT_BOUNDS = (-1e6, 1e6)


def _spec(check: str = "positive", doc: str = "", default: Any = dataclasses.MISSING,
          bounds: tuple[float, float] | None = None) -> Any:
    """Declare a float field with a range check and its plausibility bounds.

    Parameters
    ----------
    check : str
        What the value must be for the model to make sense at all: "positive",
        "nonnegative", "any" or "fraction" (never overridable).
    doc : str
        Meaning, symbol and unit.
    default : float, optional
        Default value (the field is required without one).
    bounds : (float, float), optional
        Plausibility range ``[low, high]`` in the field's unit: what a real vehicle (1:28 scale
        car to heavy truck) or maneuver can have. A value outside is refused unless the file
        lists the field under ``unchecked_fields`` (see :func:`check_plausible`).
    """
    meta = {"check": check, "doc": doc, "bounds": bounds}
    if default is dataclasses.MISSING:
        return field(metadata=meta)
    return field(default=default, metadata=meta)


_CHECKS = {
    "positive": (lambda v: v > 0.0, "must be > 0"),
    "nonnegative": (lambda v: v >= 0.0, "must be >= 0"),
    "any": (lambda v: True, ""),
    "fraction": (lambda v: 0.0 <= v <= 1.0, "must be within [0, 1]"),
}

#: Top-level key of vehicle, maneuver and scenario files listing the dotted names of fields
#: whose plausibility bounds are not applied (for exotic vehicles; sign checks still apply).
UNCHECKED_KEY = "unchecked_fields"


def _check_value(value: Any, f: dataclasses.Field[Any], name: str,
                 source: str | None) -> float:
    """``value`` as a float if it passes the range check of field ``f``, else ParameterError
    naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(name, f"must be a number, got {describe(value)}", source)
    value = float(value)
    if not math.isfinite(value):
        raise ParameterError(name, f"must be finite, got {value!r}", source)
    ok, msg = _CHECKS[f.metadata["check"]]
    if not ok(value):
        raise ParameterError(name, f"{msg}, got {value!r}", source)
    return value


def check_plausible(name: str, value: float, bounds: tuple[float, float] | None,
                    source: str | None, unchecked: frozenset[str] = frozenset()) -> None:
    """Refuse ``value`` of field ``name`` outside ``bounds`` unless ``name`` is unchecked.

    Raises
    ------
    ParameterError
        Naming the field, the value, the range and the way to accept it anyway.
    """
    if bounds is None or name in unchecked:
        return
    low, high = bounds
    if not low <= value <= high:
        raise ParameterError(name, f"{value:.6g} is outside the plausible range "
                                   f"[{low:g}, {high:g}] (list it under {UNCHECKED_KEY} to "
                                   "accept it)", source)


def bounded_fields(cls: type, prefix: str = "") -> list[str]:
    """Dotted names of the fields of dataclass ``cls`` that have plausibility bounds (in their
    ``_spec`` or in ``cls.OPTIONAL_BOUNDS``), and of the file shorthands (``cls.SHORTHANDS``)
    that stand for them."""
    names = [f"{prefix}{f.name}" for f in dataclasses.fields(cls)
             if f.metadata.get("bounds") is not None]
    # optional fields that are not _spec fields declare theirs in OPTIONAL_BOUNDS
    return names + [f"{prefix}{key}" for key in (*getattr(cls, "SHORTHANDS", {}),
                                                 *getattr(cls, "OPTIONAL_BOUNDS", {}))]


def name_and_description(data: Mapping[str, Any], source: str | None,
                         default_name: str | None = None) -> tuple[str, str]:
    """The ``name`` (a non-empty string, ``default_name`` when absent) and ``description`` (a
    string, empty when absent) of a configuration file's mapping; ``ParameterError`` else."""
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name:
        raise ParameterError("name", f"must be a non-empty string, got {describe(name)}", source)
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ParameterError("description", f"must be a string, got {describe(description)}",
                             source)
    return name, description


def unchecked_fields_from(data: Mapping[str, Any], valid: list[str] | set[str],
                          source: str | None) -> frozenset[str]:
    """The ``unchecked_fields`` list of a file (empty if absent), each name checked.

    Raises
    ------
    ParameterError
        Not a list of strings, or a name that is not a bounded field of this file.
    """
    names = data.get(UNCHECKED_KEY)
    if names is None:
        return frozenset()
    if not isinstance(names, (list, tuple)) or not all(isinstance(n, str) for n in names):
        raise ParameterError(UNCHECKED_KEY, f"must be a list of field names, got "
                                            f"{describe(names)}", source)
    for n in names:
        if n not in valid:
            raise ParameterError(UNCHECKED_KEY, f"{n!r} is not a field with plausibility "
                                                "bounds here", source)
    return frozenset(names)


def _validate_dataclass(obj: Any, source: str | None, prefix: str,
                        unchecked: frozenset[str] = frozenset()) -> None:
    for f in dataclasses.fields(obj):
        if f.metadata.get("check") is None:
            continue
        name = f"{prefix}{f.name}"
        value = _check_value(getattr(obj, f.name), f, name, source)
        check_plausible(name, value, f.metadata.get("bounds"), source, unchecked)
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


def _from_mapping(cls: type, data: Any, source: str | None, prefix: str,
                  unchecked: frozenset[str] = frozenset()) -> Any:
    """Build dataclass ``cls`` from a mapping, rejecting unknown and missing fields and values
    outside their checks and plausibility bounds (except the ``unchecked`` dotted names; a
    listed shorthand lifts the bounds of the fields it sets)."""
    if not isinstance(data, Mapping):
        raise ParameterError(prefix.rstrip(".") or "<root>",
                             f"must be a mapping, got {describe(data)}", source)
    names = {f.name: f for f in dataclasses.fields(cls)}
    shorthands: Mapping[str, tuple[str, ...]] = getattr(cls, "SHORTHANDS", {})
    unknown = sorted(str(k) for k in data if k not in names and k not in shorthands)
    if unknown:
        raise ParameterError(
            f"{prefix}{unknown[0]}",
            f"unknown field (valid: "
            f"{', '.join(sorted([*names, *shorthands]))})",
            source,
        )
    data = _expand_shorthands(cls, data, source, prefix)
    unchecked = unchecked | {f"{prefix}{target}" for key, targets in shorthands.items()
                             if f"{prefix}{key}" in unchecked for target in targets}
    kwargs: dict[str, Any] = {}
    for name, f in names.items():
        if name in data:
            kwargs[name] = data[name]
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ParameterError(f"{prefix}{name}", "missing required field", source)
    obj = cls(**kwargs)
    _validate_dataclass(obj, source, prefix, unchecked)
    post = getattr(obj, "_check", None)
    if post is not None:
        post(source, prefix, unchecked)
    return obj


@dataclass(frozen=True)
class Chassis:
    """Whole-vehicle mass properties and axle positions (every model needs these)."""

    mass_kg: float = _spec(doc="total vehicle mass m", bounds=(0.1, 1e5))
    yaw_inertia_kgm2: float = _spec(doc="yaw moment of inertia Iz about the CG",
                                    bounds=(1e-5, 2e6))
    cg_to_front_axle_m: float = _spec(doc="a = Lf, CG to front axle", bounds=(0.01, 15.0))
    cg_to_rear_axle_m: float = _spec(doc="b = Lr, CG to rear axle", bounds=(0.01, 15.0))

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

    cornering_stiffness_front_n_per_rad: float = _spec(doc="Cf, front axle", bounds=(1.0, 1e7))
    cornering_stiffness_rear_n_per_rad: float = _spec(doc="Cr, rear axle", bounds=(1.0, 1e7))


@dataclass(frozen=True)
class Roll:
    """Sprung-mass roll data (3-DOF linear model and 8-DOF model)."""

    sprung_mass_kg: float = _spec(doc="ms (at most chassis.mass_kg)", bounds=(0.05, 1e5))
    roll_inertia_kgm2: float = _spec(doc="Ix of the sprung mass about the roll axis",
                                     bounds=(1e-6, 1e6))
    roll_yaw_product_kgm2: float = _spec("any", doc="Ixz product of inertia of the sprung mass",
                                         bounds=(-1e6, 1e6))
    roll_arm_m: float = _spec(doc="h, sprung-mass CG above the roll axis", bounds=(1e-3, 3.0))
    roll_stiffness_front_nm_per_rad: float = _spec("nonnegative", doc="K_phi,f",
                                                   bounds=(0.0, 5e7))
    roll_stiffness_rear_nm_per_rad: float = _spec("nonnegative", doc="K_phi,r",
                                                  bounds=(0.0, 5e7))
    roll_damping_front_nms_per_rad: float = _spec("nonnegative", doc="C_phi,f",
                                                  bounds=(0.0, 1e7))
    roll_damping_rear_nms_per_rad: float = _spec("nonnegative", doc="C_phi,r",
                                                 bounds=(0.0, 1e7))
    roll_steer_front: float = _spec("any", doc="eps_f, front road-wheel steer per roll, rad/rad",
                                    bounds=(-1.0, 1.0))
    roll_steer_rear: float = _spec("any", doc="eps_r, rear road-wheel steer per roll, rad/rad",
                                   bounds=(-1.0, 1.0))

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
    """Steering system: ratio, and the free-control dynamics (ch. 3.4/4.4).

    The 2-DOF free-control model (``2dof-free``) is the paper's first-order system: damping
    and trail only, the trail standing for caster plus pneumatic trail (its tire has no
    aligning moment). The 8-DOF's free steering system (``8dof-free``) adds the inertia and
    the Coulomb friction; there ``trail_m`` is the caster (mechanical) trail alone, since the
    tire model gives the aligning moment of the pneumatic trail (a linear tire gives none, so
    there it is the whole trail again). Torques and the inertia are about the kingpins (the
    road-wheel level); the driver's steering-wheel torque acts through ``ratio``.
    """

    ratio: float = _spec(doc="steering-wheel angle per front road-wheel angle",
                         bounds=(1.0, 50.0))
    damping_nms_per_rad: float = _spec("nonnegative", default=0.0,
                                       doc="nu, viscous damping about the kingpin",
                                       bounds=(0.0, 1e5))
    trail_m: float = _spec("nonnegative", default=0.0, doc="eta, caster/pneumatic trail",
                           bounds=(0.0, 0.5))
    # a heavy truck's steering system: ratio 25, 0.1 kg m^2 of wheel and column -> 60 kg m^2
    # about the kingpins plus its wheels; 5 N m of friction at its wheel -> 125 N m
    inertia_kgm2: float = _spec("nonnegative", default=0.0,
                                doc="J, inertia about the kingpins incl. ratio^2 x steering "
                                    "wheel (0 = no 8-DOF steering system)",
                                bounds=(0.0, 1e3))
    coulomb_friction_nm: float = _spec("nonnegative", default=0.0,
                                       doc="T_c, Coulomb friction about the kingpins",
                                       bounds=(0.0, 1e4))


#: Bounds of the TMeasy force-characteristic values (N): a 1:28 scale car's tire to a heavy
#: truck's at twice its nominal load.
_TMEASY_FORCE_BOUNDS = (0.01, 1e6)
#: Bounds of the TMeasy slip values (dimensionless slip at the peak, where sliding begins,
#: where the trail changes sign or ends).
_TMEASY_SLIP_BOUNDS = (1e-4, 10.0)


def _tm_force(doc: str, default: float) -> Any:
    return _spec(doc=doc, default=default, bounds=_TMEASY_FORCE_BOUNDS)


def _tm_slope(doc: str, default: float) -> Any:
    return _spec(doc=doc, default=default, bounds=(1.0, 1e8))


def _tm_slip(doc: str, default: float) -> Any:
    return _spec(doc=doc, default=default, bounds=_TMEASY_SLIP_BOUNDS)


@dataclass(frozen=True)
class TMeasy:
    """Parameters of the TMeasy tire (``tire.tmeasy``; :mod:`fourws_sim.tires.tmeasy`).

    TMeasy (Hirschberg, Rill, Weinfurter, Vehicle System Dynamics 45, 2007; Rill, *Road
    Vehicle Dynamics*, CRC Press, 2012) describes each pure-slip force characteristic by its
    initial slope ``dF0``, maximum ``F_M`` at slip ``s_M``, and sliding value ``F_S`` from slip
    ``s_S`` on, given at the nominal load ``F_z^N`` (``_pn``) and at twice it (``_p2n``): the
    forces and slopes are interpolated quadratically in the load, the slips linearly, as
    TMeasy does. Forces in N, slopes in N per unit slip; TMeasy slips are slip velocity over
    rolling speed (``s_x = kappa``, ``s_y = -tan(alpha)`` at free rolling). The aligning
    torque is ``-n F_y`` with the pneumatic trail ``n = L (n/L)(s_y)``, ``L = 2 sqrt(r0 dz)``
    the contact length from the unloaded radius and the static deflection ``dz`` under the
    progressive vertical stiffness given at the two loads.

    Defaults: the HMMWV tire of Chrono::Vehicle (``data/vehicle/hmmwv/tire/
    HMMWV_TMeasy_converted.json``, BSD-3-Clause). In a file ``tire.tmeasy.json`` names a
    Chrono::Vehicle or LFDM TMeasy JSON file (relative to the vehicle file) whose values fill
    the fields the block does not give (:func:`fourws_sim.tires.tmeasy.read_json` lists the
    keys read).
    """

    nominal_load_n: float = _spec(doc="F_z^N, nominal load (pn)", default=7600.0,
                                  bounds=(1.0, 2e5))
    maximum_load_n: float = _spec(doc="load above which the characteristics are held "
                                      "(pn_max; Chrono and LFDM: 3.5 pn)", default=26600.0,
                                  bounds=(1.0, 1e6))
    unloaded_radius_m: float = _spec(doc="r0, unloaded radius (contact length)",
                                     default=0.464, bounds=(0.01, 2.0))
    vertical_stiffness_pn_n_per_m: float = _spec(doc="c_z at the nominal load",
                                                 default=326332.4234, bounds=(10.0, 1e8))
    vertical_stiffness_p2n_n_per_m: float = _spec(doc="c_z at twice the nominal load",
                                                  default=326332.4234, bounds=(10.0, 1e8))
    dfx0_pn_n: float = _tm_slope("dF_x^0, initial longitudinal slope at pn", 157030.738840308)
    dfx0_p2n_n: float = _tm_slope("dF_x^0 at 2 pn", 274685.069847482)
    fxm_pn_n: float = _tm_force("F_x^M, longitudinal maximum at pn", 6894.765328626913)
    fxm_p2n_n: float = _tm_force("F_x^M at 2 pn", 11973.78061414796)
    sxm_pn: float = _tm_slip("s_x^M, slip of the longitudinal maximum at pn", 0.1337681868200464)
    sxm_p2n: float = _tm_slip("s_x^M at 2 pn", 0.1634000724558567)
    fxs_pn_n: float = _tm_force("F_x^S, longitudinal sliding force at pn", 5692.145971941859)
    fxs_p2n_n: float = _tm_force("F_x^S at 2 pn", 10765.232472159529)
    sxs_pn: float = _tm_slip("s_x^S, slip where longitudinal sliding begins at pn",
                             0.959999390695378)
    sxs_p2n: float = _tm_slip("s_x^S at 2 pn", 0.9599349397154496)
    dfy0_pn_n: float = _tm_slope("dF_y^0, initial lateral slope (cornering stiffness) at pn",
                                 55087.49318774042)
    dfy0_p2n_n: float = _tm_slope("dF_y^0 at 2 pn", 102058.29431565656)
    fym_pn_n: float = _tm_force("F_y^M, lateral maximum at pn", 5948.424247065884)
    fym_p2n_n: float = _tm_force("F_y^M at 2 pn", 11335.717829523435)
    sym_pn: float = _tm_slip("s_y^M, slip of the lateral maximum at pn", 0.3794817785000966)
    sym_p2n: float = _tm_slip("s_y^M at 2 pn", 0.3775168408962764)
    fys_pn_n: float = _tm_force("F_y^S, lateral sliding force at pn", 5648.517057661229)
    fys_p2n_n: float = _tm_force("F_y^S at 2 pn", 10693.243250366206)
    sys_pn: float = _tm_slip("s_y^S, slip where lateral sliding begins at pn", 0.925640996144482)
    sys_p2n: float = _tm_slip("s_y^S at 2 pn", 0.959833720945494)
    nto0_pn: float = _spec("nonnegative", doc="(n/L)_0, trail per contact length at zero slip, "
                                              "pn (0 = no aligning torque)", default=0.13,
                           bounds=(0.0, 1.0))
    nto0_p2n: float = _spec("nonnegative", doc="(n/L)_0 at 2 pn", default=0.167,
                            bounds=(0.0, 1.0))
    synto0_pn: float = _tm_slip("s_y^0, lateral slip where the trail changes sign, pn",
                                0.3984558674251015)
    synto0_p2n: float = _tm_slip("s_y^0 at 2 pn", 0.3963926829410902)
    syntoe_pn: float = _tm_slip("s_y^E, lateral slip where the trail ends, pn",
                                0.6792276290602397)
    syntoe_p2n: float = _tm_slip("s_y^E at 2 pn", 0.6781638113282699)

    #: (force, slip) field stems of the two pure-slip characteristics.
    CURVES: ClassVar[tuple[str, str]] = ("x", "y")
    #: Fields interpolated quadratically in the load (forces, slopes); the others linearly.
    QUADRATIC: ClassVar[tuple[str, ...]] = ("dfx0", "fxm", "fxs", "dfy0", "fym", "fys")
    LINEAR: ClassVar[tuple[str, ...]] = ("sxm", "sxs", "sym", "sys", "nto0", "synto0",
                                         "syntoe")

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        """The relations TMeasy needs: loads ordered, a progressive vertical stiffness, the
        sliding slip beyond the peak slip and the sliding force at most the maximum at both
        loads, and every interpolated value positive from zero to the maximum load."""
        def refuse(name: str, problem: str) -> None:
            raise ParameterError(f"{prefix}{name}", problem, source)

        if not self.maximum_load_n >= self.nominal_load_n:
            refuse("maximum_load_n", f"must be >= nominal_load_n ({self.nominal_load_n:g} N), "
                                     f"got {self.maximum_load_n:g}")
        c1, c2 = self.vertical_stiffness_pn_n_per_m, self.vertical_stiffness_p2n_n_per_m
        if not c1 <= c2 < math.sqrt(2.0) * c1:
            refuse("vertical_stiffness_p2n_n_per_m",
                   f"must lie within [c_z(pn), sqrt(2) c_z(pn)) = [{c1:g}, "
                   f"{math.sqrt(2.0) * c1:g}) (a progressive F_z(dz) = a1 dz + a2 dz^2 with "
                   f"a1, a2 >= 0), got {c2:g}")
        for axis in self.CURVES:
            for load in ("pn", "p2n"):
                sm, ss = getattr(self, f"s{axis}m_{load}"), getattr(self, f"s{axis}s_{load}")
                if not ss > sm:
                    refuse(f"s{axis}s_{load}", f"must exceed s{axis}m_{load} ({sm:g}), got {ss:g}")
                fm, fs = (getattr(self, f"f{axis}m_{load}_n"), getattr(self, f"f{axis}s_{load}_n"))
                if not fs <= fm:
                    refuse(f"f{axis}s_{load}_n", f"must be at most f{axis}m_{load}_n ({fm:g} N), "
                                                 f"got {fs:g}")
            if not self.syntoe_pn > self.synto0_pn or not self.syntoe_p2n > self.synto0_p2n:
                refuse("syntoe_pn", "the slip where the trail ends must exceed the slip where "
                                    "it changes sign (synto0) at both loads")
        x_max = self.maximum_load_n / self.nominal_load_n
        for stem in self.QUADRATIC:
            w1, w2 = getattr(self, f"{stem}_pn_n"), getattr(self, f"{stem}_p2n_n")
            # Y(x) = x (2 w1 - w2/2 - (w1 - w2/2) x) > 0 on (0, x_max]: the bracket is linear
            # in x, so positive at both ends
            if not (2.0 * w1 - 0.5 * w2 > 0.0 and 2.0 * w1 - 0.5 * w2 - (w1 - 0.5 * w2) * x_max
                    > 0.0):
                refuse(f"{stem}_p2n_n", f"with {stem}_pn_n = {w1:g} N its quadratic "
                                        f"interpolation is not positive at every load up to "
                                        f"maximum_load_n ({self.maximum_load_n:g} N)")
        for stem in self.LINEAR:
            w1, w2 = getattr(self, f"{stem}_pn"), getattr(self, f"{stem}_p2n")
            low = min(2.0 * w1 - w2, w1 + (w2 - w1) * (x_max - 1.0))
            if not (low > 0.0 or (stem == "nto0" and low >= 0.0)):
                refuse(f"{stem}_p2n", f"with {stem}_pn = {w1:g} its linear interpolation is "
                                      f"not positive at every load up to maximum_load_n "
                                      f"({self.maximum_load_n:g} N)")


#: Key of ``tire.tmeasy`` naming a Chrono::Vehicle or LFDM TMeasy JSON file.
TMEASY_JSON_KEY = "json"


def tmeasy_from_mapping(values: Mapping[str, Any], source: str | None,
                        prefix: str = "tire.tmeasy.",
                        unchecked: frozenset[str] = frozenset()) -> TMeasy:
    """Validate a ``tire.tmeasy`` mapping (without its ``json`` key) into :class:`TMeasy`;
    missing fields take the defaults.

    Raises
    ------
    ParameterError
        An unknown field, a bad value or a broken relation (see ``TMeasy._check``).
    """
    return _from_mapping(TMeasy, values, source, prefix, unchecked)


def _tmeasy_resolved(values: Any, source: str | None, prefix: str,
                     unchecked: frozenset[str]) -> Mapping[str, Any]:
    """``tire.tmeasy`` as validated: with a ``json`` file, every field (the block's own values
    over the file's) and the file's resolved path, so that the vehicle's ``to_dict`` reloads
    without the file; without one, the block as given."""
    if not isinstance(values, Mapping):
        raise ParameterError(prefix.rstrip("."), f"must be a mapping, got {describe(values)}",
                             source)
    own = {k: v for k, v in values.items() if k != TMEASY_JSON_KEY}
    path = values.get(TMEASY_JSON_KEY)
    names = [f.name for f in dataclasses.fields(TMeasy)]
    if path is None:
        tmeasy_from_mapping(own, source, prefix, unchecked)
        return values
    if not isinstance(path, str) or not path:
        raise ParameterError(f"{prefix}{TMEASY_JSON_KEY}",
                             f"must be a file path, got {describe(path)}", source)
    where = Path(path).expanduser()
    if not where.is_absolute() and source and Path(source).is_file():
        where = Path(source).resolve().parent / where
    merged = dict(own)
    if any(name not in own for name in names):  # a complete block needs no file
        from fourws_sim.tires import tmeasy  # numba: the tires load it (about 0.5 s)

        loaded = tmeasy.read_json(where, f"{prefix}{TMEASY_JSON_KEY}", source)
        merged = {**loaded, **own}
    built = tmeasy_from_mapping(merged, source, prefix, unchecked)
    return {**dataclasses.asdict(built), TMEASY_JSON_KEY: str(where)}


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
    friction_coefficient: float = _spec(default=1.0, doc="mu, peak friction (linear model)",
                                        bounds=(0.01, 3.0))
    relaxation_length_front_m: float = _spec(
        "nonnegative", default=0.0, doc="sigma_f, relaxation length of a front tire, 0 = no lag",
        bounds=(0.0, 10.0))
    relaxation_length_rear_m: float = _spec(
        "nonnegative", default=0.0, doc="sigma_r, relaxation length of a rear tire, 0 = no lag",
        bounds=(0.0, 10.0))
    cubic_coefficient_front_per_rad2: float = _spec(
        "nonnegative", default=0.0, doc="K of F = -C(1 - K alpha^2) alpha, front (ch. 7)",
        bounds=(0.0, 1e3))
    cubic_coefficient_rear_per_rad2: float = _spec(
        "nonnegative", default=0.0, doc="K of F = -C(1 - K alpha^2) alpha, rear (ch. 7)",
        bounds=(0.0, 1e3))
    longitudinal_stiffness_n: float = _spec(
        "nonnegative", default=0.0,
        doc="C_s per tire, N per unit slip ratio (linear model; 0 = derive 1.5 x per-tire Calpha)",
        bounds=(0.0, 1e7))
    rolling_resistance: float = _spec("nonnegative", default=0.0,
                                      doc="f_r, rolling-resistance force per normal load",
                                      bounds=(0.0, 0.5))
    #: Coefficients of a tire model, the field named after the model (``fourws_sim.tires``).
    sti: Mapping[str, float] = field(default_factory=dict)
    magic_formula: Mapping[str, float] = field(default_factory=dict)
    tmeasy: Mapping[str, Any] = field(default_factory=dict)

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if self.model not in TIRES:
            raise ParameterError(f"{prefix}model", f"unknown tire model {describe(self.model)} "
                                                   f"(valid: {', '.join(TIRES)})", source)
        for group in TIRE_COEFFICIENT_GROUPS:
            values = getattr(self, group)
            if not isinstance(values, Mapping):
                raise ParameterError(f"{prefix}{group}",
                                     f"must be a mapping, got {describe(values)}", source)
            if values:
                # get_tire imports the tire module (numba): only a file with coefficients pays
                # for it; their names and signs are the tire module's, checked at load for
                # every tool, not only by the tools that integrate the tire
                get_tire(group).pack_mapping(values, source, prefix=f"{prefix}{group}.")
            for key, v in values.items():
                name = f"{prefix}{group}.{key}"
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise ParameterError(name, f"must be a finite number, got {describe(v)}",
                                         source)
                # fitted coefficients: the tire module checks each one's sign; any magnitude
                # beyond this is a slip of the pen (the largest shipped one is 4420)
                check_plausible(name, float(v), TIRE_COEFFICIENT_BOUNDS, source, unchecked)
        object.__setattr__(self, "tmeasy", _tmeasy_resolved(self.tmeasy, source,
                                                            f"{prefix}tmeasy.", unchecked))


#: Tire models whose fitted coefficients a vehicle file gives as a ``tire.<model>`` mapping of
#: numbers: the fields of :class:`Tire` of that type named after a model of
#: ``fourws_sim.tires.TIRES`` (``tire.tmeasy`` is a validated :class:`TMeasy` block instead).
TIRE_COEFFICIENT_GROUPS: tuple[str, ...] = tuple(
    name for name, hint in typing.get_type_hints(Tire).items()
    if name in TIRES and hint == Mapping[str, float])


@dataclass(frozen=True)
class Body:
    """Spread-tire geometry and wheels of the 8-DOF model (ch. 8)."""

    track_front_m: float = _spec(doc="Tf", bounds=(0.02, 5.0))
    track_rear_m: float = _spec(doc="Tr", bounds=(0.02, 5.0))
    cg_height_m: float = _spec(doc="total-mass CG height above ground (longitudinal transfer)",
                               bounds=(0.005, 5.0))
    roll_centre_height_front_m: float = _spec("nonnegative", doc="front roll-centre height",
                                              bounds=(0.0, 3.0))
    roll_centre_height_rear_m: float = _spec("nonnegative", doc="rear roll-centre height",
                                             bounds=(0.0, 3.0))
    unsprung_cg_height_m: float = _spec("nonnegative", doc="unsprung-mass CG height",
                                        bounds=(0.0, 3.0))
    wheel_radius_m: float = _spec(doc="loaded rolling radius", bounds=(0.01, 2.0))
    wheel_spin_inertia_kgm2: float = _spec(doc="Iw, one wheel about its spin axis",
                                           bounds=(1e-7, 1e4))


#: Sea-level air density of the ISO standard atmosphere (ISO 2533: 15 degC, 101.325 kPa),
#: kg/m^3: ``aero.air_density_kgpm3`` when a file does not give one.
AIR_DENSITY_KGPM3 = 1.225


@dataclass(frozen=True)
class Aero:
    """Aerodynamic drag and lift of the 8-DOF model (``aero:``; absent = none, the paper's
    model).

    Still air, so the air speed is the body's longitudinal velocity U. Drag
    ``D = 0.5 rho C_d A U |U|`` acts along the body's -x at the height of the CG (no pitch
    moment about the CG: it decelerates the car without the forward load transfer of a
    braking force at the ground). Lift ``0.5 rho C_l,i A U^2`` on axle i (front, rear)
    takes that much load off the axle, half from each of its wheels (negative C_l A is
    downforce). Side force and the aerodynamic yaw and roll moments are left out.
    """

    drag_area_m2: float = _spec("nonnegative", default=0.0,
                                doc="C_d A, drag coefficient times frontal area",
                                bounds=(0.0, 20.0))
    lift_area_front_m2: float = _spec("any", default=0.0,
                                      doc="C_l,f A, front-axle lift coefficient times area "
                                          "(negative: downforce)", bounds=(-10.0, 10.0))
    lift_area_rear_m2: float = _spec("any", default=0.0,
                                     doc="C_l,r A, rear-axle lift coefficient times area "
                                         "(negative: downforce)", bounds=(-10.0, 10.0))
    air_density_kgpm3: float = _spec(default=AIR_DENSITY_KGPM3,
                                     doc="rho, air density (ISO 2533 sea level by default)",
                                     bounds=(0.3, 1.6))

    @property
    def drag_coefficient_kg_per_m(self) -> float:
        """``0.5 rho C_d A`` in kg/m (N per (m/s)^2): the drag is this times U |U|."""
        return 0.5 * self.air_density_kgpm3 * self.drag_area_m2

    def lift_coefficients_kg_per_m(self) -> tuple[float, float]:
        """``0.5 rho C_l,i A`` of the front and rear axle in kg/m: the axle's lift is this
        times U^2 (N)."""
        half_rho = 0.5 * self.air_density_kgpm3
        return half_rho * self.lift_area_front_m2, half_rho * self.lift_area_rear_m2


#: Driven axles a driveline may have (``driveline.drive``; the speed-hold driver's
#: ``driven_axle`` takes the same names).
DRIVES = ("front", "rear", "all")
#: Differentials of an axle: ``open`` (equal torque to both wheels), ``locked`` (both wheels
#: at one speed), ``limited_slip`` (a viscous coupling and/or a torque bias ratio).
DIFFERENTIALS = ("open", "locked", "limited_slip")


@dataclass(frozen=True)
class Driveline:
    """Drive torque split and differentials of the 8-DOF model (``driveline:``; absent = the
    speed-hold driver's ``driven_axle`` with open differentials, equal torque per driven
    wheel).

    ``drive`` names the driven axles (it replaces the maneuvers' ``speed_hold.driven_axle``);
    with ``all`` the front axle gets ``front_torque_fraction`` of the drive torque. On each
    axle the differential takes the axle's torque and gives its wheels equal shares less a
    locking torque ``T_lock`` moved from the faster wheel to the slower one:
    ``T_lock = c_v (omega_fast - omega_slow) + k_b |T_axle| s / 2`` with the viscous coupling
    ``c_v`` (N m s/rad), ``k_b = (TBR - 1)/(TBR + 1)`` of the torque bias ratio TBR (the
    slower wheel gets up to TBR times the faster one's torque) and ``s`` the speed
    difference over ``eightdof.BIAS_BAND_RADPS``, at most 1 (a smooth onset, no chatter at
    equal speeds). ``locked`` is a coupling stiff enough to hold the wheels together within
    ``eightdof.LOCK_TIME_S``.
    """

    drive: str = "rear"
    front_torque_fraction: float = _spec("fraction", default=0.5,
                                         doc="front axle's share of the drive torque "
                                             "(drive: all)", bounds=(0.0, 1.0))
    differential_front: str = "open"
    differential_rear: str = "open"
    viscous_coupling_front_nms_per_rad: float = _spec(
        "nonnegative", default=0.0, doc="c_v of a limited-slip front differential",
        bounds=(0.0, 1e4))
    viscous_coupling_rear_nms_per_rad: float = _spec(
        "nonnegative", default=0.0, doc="c_v of a limited-slip rear differential",
        bounds=(0.0, 1e4))
    torque_bias_ratio_front: float = _spec(
        default=1.0, doc="TBR of a limited-slip front differential (1 = none)",
        bounds=(1.0, 10.0))
    torque_bias_ratio_rear: float = _spec(
        default=1.0, doc="TBR of a limited-slip rear differential (1 = none)",
        bounds=(1.0, 10.0))

    def front_fraction(self) -> float:
        """Front axle's share of the drive torque (0 rear drive, 1 front drive)."""
        return {"front": 1.0, "rear": 0.0, "all": self.front_torque_fraction}[self.drive]

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if self.drive not in DRIVES:
            raise ParameterError(f"{prefix}drive", f"must be one of {', '.join(DRIVES)}, got "
                                                   f"{describe(self.drive)}", source)
        for axle in ("front", "rear"):
            kind = getattr(self, f"differential_{axle}")
            if kind not in DIFFERENTIALS:
                raise ParameterError(f"{prefix}differential_{axle}",
                                     f"must be one of {', '.join(DIFFERENTIALS)}, got "
                                     f"{describe(kind)}", source)
            coupled = (getattr(self, f"viscous_coupling_{axle}_nms_per_rad") > 0.0
                       or getattr(self, f"torque_bias_ratio_{axle}") > 1.0)
            if coupled and kind != "limited_slip":
                raise ParameterError(f"{prefix}differential_{axle}",
                                     f"is {kind}: a viscous coupling or torque bias ratio "
                                     "needs limited_slip", source)


@dataclass(frozen=True)
class Actuators:
    """Rear-steer actuator limits (defaults: 5 deg, 30 deg/s; production 4WS systems stay
    within a few degrees of rear steer)."""

    rear_angle_limit_rad: float = _spec(default=math.radians(5.0), doc="|delta_r| max",
                                        bounds=(1e-4, MAX_REAR_ANGLE_RAD))
    rear_rate_limit_rad_per_s: float = _spec(default=math.radians(30.0), doc="|d delta_r/dt|",
                                             bounds=(1e-3, MAX_REAR_RATE_RADPS))


_SUBSYSTEMS: dict[str, type] = {
    "chassis": Chassis,
    "axle_tires": AxleTires,
    "roll": Roll,
    "steering": Steering,
    "tire": Tire,
    "body": Body,
    "aero": Aero,
    "driveline": Driveline,
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
    aero: Aero | None = None
    driveline: Driveline | None = None
    actuators: Actuators = field(default_factory=Actuators)
    description: str = ""
    source: str = field(default="", compare=False)
    unchecked_fields: frozenset[str] = frozenset()

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
        """Copy with cornering stiffnesses scaled (e.g. a controller's ±40 % belief); the
        same copy for the same scales (kept per instance: the vehicle is frozen)."""
        s_r = scale_front if scale_rear is None else scale_rear
        scaled = self._scaled
        key = (float(scale_front), float(s_r))
        if key in scaled:
            return scaled[key]
        t = self.axle_tires
        new = AxleTires(t.cornering_stiffness_front_n_per_rad * scale_front,
                        t.cornering_stiffness_rear_n_per_rad * s_r)
        _validate_dataclass(new, self.source, "axle_tires.", self.unchecked_fields)
        if len(scaled) >= 64:
            scaled.pop(next(iter(scaled)))
        scaled[key] = dataclasses.replace(self, axle_tires=new)
        return scaled[key]

    def cache_key(self) -> str:
        """The vehicle as canonical JSON (its :meth:`to_dict`, keys sorted): equal for equal
        vehicles, a key for caches of what is computed from a vehicle (a Jacobian, a law)."""
        return self._json_key

    def to_dict(self) -> dict[str, Any]:
        """Plain mapping in the file layout (for recording a run's configuration); a new
        mapping each call."""
        return plain_copy(self._mapping)

    # computed once per instance (the vehicle is frozen; cached_property writes the
    # instance's __dict__ directly)
    @functools.cached_property
    def _scaled(self) -> dict[tuple[float, float], "Vehicle"]:
        return {}  # with_axle_tires' copies by scales

    @functools.cached_property
    def _json_key(self) -> str:
        return json.dumps(self._mapping, sort_keys=True, default=repr)

    @functools.cached_property
    def _mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"name": self.name, "description": self.description}
        for key in _SUBSYSTEMS:
            sub = getattr(self, key)
            if sub is not None:
                out[key] = {k: (dict(v) if isinstance(v, Mapping) else v)
                            for k, v in dataclasses.asdict(sub).items()}
        if self.unchecked_fields:
            out[UNCHECKED_KEY] = sorted(self.unchecked_fields)
        return out


#: Vehicles built by :func:`vehicle_from_mapping`, by their mapping's key (:func:`_mapping_key`)
#: and source (a study builds the same vehicle for many points; the analysis of a run builds its
#: vehicle and belief from the run configuration).
_BUILT: dict[tuple[str, str], Vehicle] = {}
_BUILT_SIZE = 256


def _mapping_key(value: Any) -> str | None:
    """A key for a parsed YAML/JSON mapping: its JSON text with sorted keys (``1``, ``1.0``
    and ``true`` stay apart; floats are written exactly); None if it has anything JSON does
    not write (then nothing is cached). Two mappings can share a key only through dict keys
    that are not strings (JSON writes ``1`` and ``"1"`` alike), and a vehicle mapping with
    such a key is refused (unknown field), so it is never cached."""
    try:
        return json.dumps(value, sort_keys=True, allow_nan=True)
    except (TypeError, ValueError):
        return None


def vehicle_from_mapping(data: Any, source: str = "<mapping>") -> Vehicle:
    """Validate a vehicle mapping (file layout) and build a :class:`Vehicle`.

    The vehicle of a mapping validated before (equal content and source) is returned again
    (vehicles are frozen); a refused mapping is validated again each time.

    Raises
    ------
    ParameterError
        On a missing or unknown field, a non-number, a non-finite or out-of-range value.
    """
    text = _mapping_key(data)
    key = None if text is None else (text, source)
    if key is not None:
        built = _BUILT.get(key)
        if built is not None:
            return built
    vehicle = _vehicle_from_mapping(data, source)
    if key is not None:
        if len(_BUILT) >= _BUILT_SIZE:
            _BUILT.pop(next(iter(_BUILT)))
        _BUILT[key] = vehicle
    return vehicle


def _vehicle_from_mapping(data: Any, source: str) -> Vehicle:
    """:func:`vehicle_from_mapping` without the cache."""
    if isinstance(data, Mapping) and "/**" in data:
        try:
            data = data["/**"]["ros__parameters"]["vehicle"]
        except (KeyError, TypeError):
            raise ParameterError("/**.ros__parameters.vehicle", "missing", source) from None
    if not isinstance(data, Mapping):
        raise ParameterError("<root>", f"vehicle file must be a mapping, got {describe(data)}",
                             source)
    allowed = set(_SUBSYSTEMS) | {"name", "description", UNCHECKED_KEY}
    unknown = sorted(str(k) for k in data if k not in allowed)
    if unknown:
        raise ParameterError(unknown[0], f"unknown field (valid: {', '.join(sorted(allowed))})",
                             source)
    for key in ("name", *_REQUIRED):
        if key not in data:
            raise ParameterError(key, "missing required field", source)
        if data[key] is None:
            raise ParameterError(key, "is null; it is required", source)
    name, description = name_and_description(data, source)
    unchecked = unchecked_fields_from(data, _vehicle_bounded_fields(data), source)
    # an optional subsystem given as null is absent (as if the key were not there)
    subs = {key: _from_mapping(cls, data[key], source, f"{key}.", unchecked)
            for key, cls in _SUBSYSTEMS.items() if key in data and data[key] is not None}
    roll, chassis = subs.get("roll"), subs["chassis"]
    if roll is not None and roll.sprung_mass_kg > chassis.mass_kg:
        raise ParameterError("roll.sprung_mass_kg", f"{roll.sprung_mass_kg:g} kg exceeds "
                             f"chassis.mass_kg ({chassis.mass_kg:g} kg)", source)
    return Vehicle(name=name, description=description, source=source,
                   unchecked_fields=unchecked, **subs)


def _vehicle_bounded_fields(data: Mapping[str, Any]) -> set[str]:
    """Names ``unchecked_fields`` of a vehicle may list: every bounded subsystem field and
    the tire coefficients the file gives."""
    names = {n for key, cls in _SUBSYSTEMS.items() for n in bounded_fields(cls, f"{key}.")}
    names.update(bounded_fields(TMeasy, "tire.tmeasy."))
    tire = data.get("tire")
    if isinstance(tire, Mapping):
        for group in TIRE_COEFFICIENT_GROUPS:
            if isinstance(tire.get(group), Mapping):
                names.update(f"tire.{group}.{k}" for k in tire[group])
    return names


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


#: Public names of the field declaration (:func:`_spec`) and the validating loader
#: (:func:`_from_mapping`), for the validated dataclasses of the packages above this one.
declare_field = _spec
dataclass_from_mapping = _from_mapping
