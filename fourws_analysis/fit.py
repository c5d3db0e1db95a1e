# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Fit vehicle parameters to measured logs: output-error identification (``fourws identify``).

The chosen model level (:data:`LEVELS`) is driven by the recorded inputs of each log -- the
steering-wheel angle through the steering ratio, :math:`\delta_f = \delta_H / N`, the rear
road-wheel angle of a rear-steer car, and for the 8-DOF the recorded speed, which the model's
speed-hold driver follows -- and the fitted fields :math:`\theta` minimise

.. math::

    J(\theta) = \sum_{\text{logs}} \sum_c \sum_k
        \left(\frac{e_{ck} - \bar e_c}{\sigma_c}\right)^2, \qquad
    e_{ck} = y_c(t_k) - \hat y_c(t_k; \theta),

over the channels :math:`c` the log and the model share (:data:`FIT_CHANNELS`), with
:func:`scipy.optimize.least_squares` inside the fields' plausibility bounds. Subtracting each
channel's mean residual :math:`\bar e_c` fits a constant sensor bias per channel and log in
closed form (the biases are reported); :math:`\sigma_c` is the channel's residual standard
deviation after a first pass, its variance inflated by :math:`(1+\rho_1)/(1-\rho_1)` where
the residual is correlated from sample to sample (lag-1 autocorrelation :math:`\rho_1`, an
AR(1) view of model error), and never below the channel's instrument floor
(:attr:`fourws_analysis.measured.Column.noise_floor`).

Uncertainty. With :math:`W` the weighted residual Jacobian at the optimum (central
differences), the covariance of the fitted values is :math:`(W^T W)^{-1}`; each value is
reported with its 95 % interval :math:`\pm 1.96\,\sigma_\theta`, and every pair whose
correlation exceeds :data:`INDISTINGUISHABLE` in magnitude is flagged: the record cannot tell
the two apart (only a combination of them is known).

Excitation. Before fitting, the same Jacobian at the base vehicle with the instrument floors as
noise predicts how well the record can pin each field. A field that does not move the model at
all is refused ("does not enter the model"), as is one the record would pin no better than
:data:`MAX_PREDICTED_CI` (relative 95 % half-width), e.g. a yaw inertia from a steady-state
record; roll fields need a roll signal. The refusal names the fields.

Fields are vehicle field paths (``axle_tires.cornering_stiffness_front_n_per_rad``; a
``vehicle.`` prefix is accepted, as in study files): one path fits that value; a file
shorthand (``tire.relaxation_length_m``) fits one value for the fields it stands for; paths
joined by commas move together by one factor (``roll.roll_stiffness_front_nm_per_rad,
roll.roll_stiffness_rear_nm_per_rad``: the total roll stiffness at the base's front/rear
split).
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.signal

from fourws_analysis import frequency as fq
from fourws_analysis.linear import RUN_CHANNELS, _standard_outputs
from fourws_analysis.measured import COLUMN_BY_NAME, MIN_SAMPLES, MeasuredLog, json_ready
from fourws_run.interface import WHEELS
from fourws_sim.drivers import SpeedHoldDriver, SpeedHoldSpec
from fourws_sim.errors import DivergedError, FourwsError, ParameterError
from fourws_sim.maneuvers.esc import phaseless_lowpass
from fourws_sim.models import eightdof, get_model
from fourws_sim.params import Vehicle, vehicle_from_mapping
from fourws_sim.simulator import Simulator

#: Channels compared with the model, where both the log and the model level have them.
FIT_CHANNELS = ("yaw_rate_radps", "lateral_accel_mps2", "sideslip_rad", "roll_rad",
                "roll_rate_radps")
#: |correlation| above which two fitted values cannot be told apart.
INDISTINGUISHABLE = 0.95
#: A field the record is predicted to pin no better than this (95 % half-width over the
#: value, instrument-floor noise) is refused: too little excitation.
MAX_PREDICTED_CI = 0.25
#: Two-sided 95 % quantile of the normal distribution.
Z95 = 1.959963984540054
#: A roll field needs a roll signal this many instrument floors strong (standard deviation).
MIN_ROLL_SIGNAL_FLOORS = 3.0
#: The linear levels hold one speed: the record's speed may vary by this fraction at most.
LINEAR_SPEED_SPREAD = 0.1
#: |a_y| bound of the linear range, m/s^2 (``auto`` picks a linear level inside it).
LINEAR_RANGE_MPS2 = 4.0
#: Cut-off of the low-pass on the recorded speed the 8-DOF's driver follows, Hz (sensor noise
#: on the speed would otherwise drive the wheel torques).
SPEED_FILTER_HZ = 2.0
#: Integration step of the 8-DOF level when a log does not say (a fourws bag does), s.
DEFAULT_STEP_S = 1e-3
#: Relative step of the central differences of the final Jacobian.
_JAC_STEP = 1e-4
#: Steering check: std(δH/N) over std(L r/U) in the linear range (1 for a neutral car, a few
#: for an understeering one at speed, towards 0 near an oversteer car's critical speed).
STEER_YAW_RATIO = (0.1, 10.0)

_UNIT_SUFFIXES = (("_n_per_rad", "N/rad"), ("_nm_per_rad", "N m/rad"),
                  ("_nms_per_rad", "N m s/rad"), ("_kgm2", "kg m²"), ("_kg", "kg"),
                  ("_m", "m"), ("_nm", "N m"), ("_n", "N"), ("_rad", "rad"))


def field_unit(path: str) -> str:
    """Unit of a vehicle field from its name (``rad/rad`` for the ratios)."""
    name = path.rsplit(".", 1)[-1]
    for suffix, unit in _UNIT_SUFFIXES:
        if name.endswith(suffix):
            return unit
    return "rad/rad" if name in ("ratio", "roll_steer_front", "roll_steer_rear") else "–"


# ------------------------------------------------------------------------------ fields

@dataclass(frozen=True)
class FieldGroup:
    """One fitted parameter: the vehicle fields it sets.

    Attributes
    ----------
    spec : str
        As given (``--fit``).
    paths : tuple of str
        ``subsystem.field`` of each field set.
    mode : {"value", "scale"}
        ``value``: every field takes one value ``v0 + theta * step``; ``scale``: each field
        is its base times ``1 + theta``.
    base : tuple of float
        Base values of the fields.
    step : float
        Size of one unit of theta, in the fields' unit (value mode; the base value, or a tenth
        of the plausible range for a field that is 0 in the base).
    bounds : tuple of float
        Range of theta (the fields' plausibility bounds and sign checks).
    """

    spec: str
    paths: tuple[str, ...]
    mode: str
    base: tuple[float, ...]
    step: float
    bounds: tuple[float, float]

    def values(self, theta: float) -> tuple[float, ...]:
        """The fields' values at ``theta``."""
        if self.mode == "scale":
            return tuple(b * (1.0 + theta) for b in self.base)
        return tuple(self.base[0] + theta * self.step for _ in self.paths)

    @property
    def roll(self) -> bool:
        """A roll field (needs a roll signal)."""
        return any(p.startswith("roll.") for p in self.paths)


def _field_meta(vehicle: Vehicle, path: str, where: str) -> tuple[Any, float]:
    """The dataclass field of ``subsystem.field`` and its base value."""
    sub_name, _, name = path.partition(".")
    sub = getattr(vehicle, sub_name, None) if sub_name in vehicle.to_dict() else None
    if sub is None or not dataclasses.is_dataclass(sub) or not name or "." in name:
        valid = [k for k, v in vehicle.to_dict().items() if isinstance(v, Mapping)]
        raise ParameterError(where, f"{path!r} is not a field of the base vehicle "
                             f"(subsystem.field; subsystems here: {', '.join(valid)})",
                             vehicle.source or vehicle.name)
    for f in dataclasses.fields(sub):
        if f.name == name and f.metadata.get("check") is not None:
            return f, float(getattr(sub, name))
    numeric = [f.name for f in dataclasses.fields(sub) if f.metadata.get("check") is not None]
    raise ParameterError(where, f"{path!r} is not a number field of {sub_name} (valid: "
                         f"{', '.join(numeric)})", vehicle.source or vehicle.name)


def _range(f: Any, path: str, vehicle: Vehicle) -> tuple[float, float]:
    """Values a field may take: its plausibility bounds within its sign check."""
    low, high = (-math.inf, math.inf)
    bounds = f.metadata.get("bounds")
    if bounds is not None and path not in vehicle.unchecked_fields:
        low, high = bounds
    check = f.metadata.get("check")
    if check == "positive":
        low = max(low, 0.0)
    elif check in ("nonnegative", "fraction"):
        low = max(low, 0.0)
    if check == "fraction":
        high = min(high, 1.0)
    return float(low), float(high)


def parse_field(spec: str, vehicle: Vehicle) -> FieldGroup:
    """A ``--fit`` entry as a :class:`FieldGroup` (module docstring).

    Raises
    ------
    ParameterError
        An unknown path, a linked field that is 0 in the base vehicle (it cannot move by a
        factor), a shorthand whose fields differ in the base.
    """
    where = f"--fit {spec}"
    parts = [p.strip() for p in spec.split(",")]
    parts = [p[len("vehicle."):] if p.startswith("vehicle.") else p for p in parts]
    if not all(parts):
        raise ParameterError(where, "empty field path", vehicle.source or vehicle.name)
    paths: list[str] = []
    metas = []
    for part in parts:
        sub_name, _, name = part.partition(".")
        cls = type(getattr(vehicle, sub_name, None))
        targets = getattr(cls, "SHORTHANDS", {}).get(name)
        if targets:
            expanded = [f"{sub_name}.{t}" for t in targets]
        else:
            expanded = [part]
        for path in expanded:
            if path in paths:
                raise ParameterError(where, f"{path} is named twice",
                                     vehicle.source or vehicle.name)
            paths.append(path)
            metas.append(_field_meta(vehicle, path, where))
    base = tuple(v for _, v in metas)
    ranges = [_range(f, p, vehicle) for (f, _), p in zip(metas, paths)]
    if len(parts) == 1:
        if len(set(base)) > 1:
            raise ParameterError(where, f"sets {', '.join(paths)}, which differ in the base "
                                 f"vehicle ({', '.join(f'{b:g}' for b in base)}): fit them "
                                 "linked (joined by commas) or one by one",
                                 vehicle.source or vehicle.name)
        v0 = base[0]
        low = max(r[0] for r in ranges)
        high = min(r[1] for r in ranges)
        if v0 != 0.0:
            step = abs(v0)
        else:  # a field that is 0 in the base: a tenth of its plausible range per unit
            reach = max(abs(low), abs(high))
            step = 0.1 * reach if math.isfinite(reach) and reach > 0.0 else 1.0
        return FieldGroup(spec, tuple(paths), "value", base, step,
                          ((low - v0) / step, (high - v0) / step))
    # linked paths (a shorthand among them is just its fields): one factor on every base
    zero = [p for p, b in zip(paths, base) if b == 0.0]
    if zero:
        raise ParameterError(where, f"linked fields move by one factor; {zero[0]} is 0 in the "
                             "base vehicle: fit it on its own", vehicle.source or vehicle.name)
    lows, highs = [], []
    for b, (low, high) in zip(base, ranges):
        lo, hi = sorted((low / b, high / b))
        lows.append(lo)
        highs.append(hi)
    return FieldGroup(spec, tuple(paths), "scale", base, 1.0,
                      (max(lows) - 1.0, min(highs) - 1.0))


def vehicle_with(base: Vehicle, groups: Sequence[FieldGroup], theta: np.ndarray,
                 name: str | None = None) -> Vehicle:
    """``base`` with every group set to its value at ``theta``."""
    mapping = base.to_dict()
    for g, th in zip(groups, theta):
        for path, value in zip(g.paths, g.values(float(th))):
            sub, _, key = path.partition(".")
            mapping[sub][key] = value
    if name is not None:
        mapping["name"] = name
    return vehicle_from_mapping(mapping, source=base.source or base.name)


# ------------------------------------------------------------------------------ levels

class Level:
    """A model level: simulates a log's channels for a vehicle from the log's inputs."""

    name = ""
    #: Channels the level predicts.
    outputs: tuple[str, ...] = ()

    def check(self, log: MeasuredLog, vehicle: Vehicle) -> None:
        """Refuse a log or vehicle the level cannot take (ParameterError)."""

    def simulate(self, log: MeasuredLog, vehicle: Vehicle) -> dict[str, np.ndarray]:
        """The level's channels on ``log.time_s`` driven by the log's inputs."""
        raise NotImplementedError

    def signature(self, log: MeasuredLog, vehicle: Vehicle) -> np.ndarray:
        """Every number of ``vehicle`` the level's model of ``log`` uses (a field that leaves
        it unchanged does not enter the model)."""
        raise NotImplementedError


def _ratio(vehicle: Vehicle) -> float:
    """Steering ratio N; 1 for a vehicle without a steering subsystem, as its maneuvers take
    it (:class:`fourws_sim.maneuvers.base.Maneuver`: the hand wheel is the road wheel)."""
    return vehicle.steering.ratio if vehicle.steering is not None else 1.0


def steer_inputs(log: MeasuredLog, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
    """Front road-wheel command δH/N (rad) and the rear road-wheel angle (rad, 0 without one)
    of a log, per sample, held over the sample's step."""
    front = log.channels["steering_wheel_angle_rad"] / _ratio(vehicle)
    rear = log.channels.get("rear_wheel_angle_rad")
    return front, (np.zeros_like(front) if rear is None else rear)


class LinearLevel(Level):
    """A linear model (``2dof``, ``2dof-lagged``, ``3dof``) at the log's median speed, its
    inputs held over each sample (zero-order hold: exact for fourws's own lockstep runs), the
    accelerations evaluated with the previous sample's input as the simulator does."""

    def __init__(self, model: str) -> None:
        self.name = model
        self._model = get_model(model)
        names = [m.name for m in self._model.STATE]
        outs = ["yaw_rate_radps", "lateral_accel_mps2", "sideslip_rad"]
        if "PHI" in names:
            outs.append("roll_rad")
        if "PHI_DOT" in names:
            outs.append("roll_rate_radps")
        self.outputs = tuple(outs)
        self._states = names

    @staticmethod
    def speed(log: MeasuredLog) -> float:
        """The one speed of the linear models, m/s: the record's median."""
        return float(np.median(log.channels["speed_mps"]))

    def check(self, log: MeasuredLog, vehicle: Vehicle) -> None:
        u = log.channels["speed_mps"]
        med = self.speed(log)
        if med <= 1.0:
            raise ParameterError("speed_mps", f"median {med:.3g} m/s: the {self.name} level "
                                 "needs a car in motion", log.source)
        spread = float(np.ptp(u)) / med
        if spread > LINEAR_SPEED_SPREAD:
            raise ParameterError("speed_mps", f"varies from {np.min(u):.3g} to {np.max(u):.3g} "
                                 f"m/s ({100 * spread:.0f} % of its median); the {self.name} "
                                 f"level holds one speed (at most {100 * LINEAR_SPEED_SPREAD:g} "
                                 "% spread): fit the 8dof level", log.source)
        self._model.params_for(vehicle, med)

    def signature(self, log: MeasuredLog, vehicle: Vehicle) -> np.ndarray:
        a, b = self._model.matrices(vehicle, self.speed(log))
        return np.concatenate((a.ravel(), b.ravel(), [_ratio(vehicle)]))

    def simulate(self, log: MeasuredLog, vehicle: Vehicle) -> dict[str, np.ndarray]:
        speed = self.speed(log)
        a, b = self._model.matrices(vehicle, speed)
        names, c, d = _standard_outputs(a, b, self._states, speed)
        rows = {RUN_CHANNELS[n]: (c[i], d[i]) for i, n in enumerate(names) if n in RUN_CHANNELS}
        if "PHI_DOT" in self._states:
            rows["roll_rate_radps"] = (np.eye(a.shape[0])[self._states.index("PHI_DOT")],
                                       np.zeros(b.shape[1]))
        front, rear = steer_inputs(log, vehicle)
        u = np.column_stack((front, rear))
        x = _zoh_states(a, b, u, log.dt_s)
        # a_y of the sample is evaluated with the input held over the previous step
        u_prev = np.vstack((u[:1], u[:-1]))
        return {ch: x @ rows[ch][0] + u_prev @ rows[ch][1] for ch in self.outputs}


def _zoh_states(a: np.ndarray, b: np.ndarray, u: np.ndarray, dt_s: float) -> np.ndarray:
    """States of ``dx/dt = A x + B u`` at the samples, ``u`` held over each step, starting at
    the steady state of the first input (straight running for a log that starts at rest):
    one recursive filter per mode of the discretized system (complex modes, scipy's lfilter:
    C speed) when A is diagonalizable, else the plain recursion."""
    n = a.shape[0]
    m = np.zeros((n + b.shape[1], n + b.shape[1]))
    m[:n, :n], m[:n, n:] = a * dt_s, b * dt_s
    e = scipy.linalg.expm(m)
    ad, bd = e[:n, :n], e[:n, n:]
    u0 = u[0]
    du = u - u0
    try:
        x0 = np.linalg.solve(np.eye(n) - ad, bd @ u0)
    except np.linalg.LinAlgError:
        x0 = np.zeros(n)
    lam, vec = np.linalg.eig(ad)
    if np.linalg.cond(vec) < 1e8:
        drive = np.linalg.solve(vec, bd @ du.T)  # modal inputs, (n, N)
        z = np.empty_like(drive)
        for i in range(n):
            z[i] = scipy.signal.lfilter([0.0, 1.0], [1.0, -lam[i]], drive[i])
        return (vec @ z).real.T + x0
    x = np.empty((u.shape[0], n))
    xi = np.zeros(n)
    for k in range(u.shape[0]):
        x[k] = xi
        xi = ad @ xi + bd @ du[k]
    return x + x0


class EightDofLevel(Level):
    """The 8-DOF (``fourws_sim.Simulator``, RK4) over the whole record: front command δH/N and
    the rear angle held over each sample, wheel torques from the speed-hold driver of the
    maneuvers following the recorded speed (low-passed at :data:`SPEED_FILTER_HZ`), from
    straight running at the first recorded speed. ``tire`` overrides the vehicle's tire
    model (``linear``: the axle cornering stiffnesses are the 8-DOF's too)."""

    name = "8dof"
    outputs = FIT_CHANNELS

    def __init__(self, tire: str | None = None) -> None:
        self.tire = tire

    def check(self, log: MeasuredLog, vehicle: Vehicle) -> None:
        Simulator(vehicle, model="8dof", dt_s=self._step(log)[0], tire=self.tire)

    @staticmethod
    def _step(log: MeasuredLog) -> tuple[float, int]:
        """Integration step and steps per sample."""
        step = log.config.get("integration_step_s", DEFAULT_STEP_S)
        if not isinstance(step, (int, float)) or not 0.0 < step <= log.dt_s:
            step = DEFAULT_STEP_S
        n = max(1, int(round(log.dt_s / step)))
        if abs(n * step - log.dt_s) > 1e-9 * log.dt_s:
            n = max(1, int(math.ceil(log.dt_s / DEFAULT_STEP_S)))
        return log.dt_s / n, n

    def signature(self, log: MeasuredLog, vehicle: Vehicle) -> np.ndarray:
        p = eightdof.params_for(vehicle, self.tire)
        return np.concatenate((p.arr, p.coeffs_front, p.coeffs_rear, [_ratio(vehicle)]))

    def simulate(self, log: MeasuredLog, vehicle: Vehicle) -> dict[str, np.ndarray]:
        dt, n_sub = self._step(log)
        sim = Simulator(vehicle, model="8dof", dt_s=dt, tire=self.tire)
        target = phaseless_lowpass(log.channels["speed_mps"], log.dt_s, SPEED_FILTER_HZ)
        sim.reset(speed_mps=float(target[0]))
        driver = SpeedHoldDriver(SpeedHoldSpec(), vehicle)
        front, rear = steer_inputs(log, vehicle)
        inp = sim.model.INPUT
        drive = [int(inp[f"DRIVE_{w}"]) for w in WHEELS]
        brake = [int(inp[f"BRAKE_{w}"]) for w in WHEELS]
        u = np.zeros(len(inp))
        out = {ch: np.empty(log.time_s.size) for ch in self.outputs}
        t = log.time_s - log.time_s[0]
        k = 0
        try:
            for k in range(t.size):
                y = sim.outputs()
                for ch in self.outputs:
                    out[ch][k] = y[ch]
                torque, brakes = driver.command(float(t[k]), y["speed_mps"], float(target[k]))
                u[inp.DELTA_F], u[inp.DELTA_R] = front[k], rear[k]
                u[drive], u[brake] = torque, brakes
                sim.step(u, n_sub)
        except DivergedError:
            # a trial vehicle the record drives past its limits: hold the last finite values
            # (a large, finite residual steers the fit back)
            for ch in self.outputs:
                out[ch][k + 1:] = out[ch][k]
        return out


#: Model levels by name (``fourws identify --level``).
LEVELS: dict[str, Callable[[str | None], Level]] = {
    "2dof": lambda tire: LinearLevel("2dof"),
    "2dof-lagged": lambda tire: LinearLevel("2dof-lagged"),
    "3dof": lambda tire: LinearLevel("3dof"),
    "8dof": lambda tire: EightDofLevel(tire),
}

#: Fields fitted when none are named, per level (those the vehicle has; a default the
#: record cannot pin is left out with a note instead of refused).
DEFAULT_FIELDS: dict[str, tuple[str, ...]] = {
    "2dof": ("axle_tires.cornering_stiffness_front_n_per_rad",
             "axle_tires.cornering_stiffness_rear_n_per_rad", "chassis.yaw_inertia_kgm2"),
    "2dof-lagged": ("axle_tires.cornering_stiffness_front_n_per_rad",
                    "axle_tires.cornering_stiffness_rear_n_per_rad", "chassis.yaw_inertia_kgm2",
                    "tire.relaxation_length_m"),
    "3dof": ("axle_tires.cornering_stiffness_front_n_per_rad",
             "axle_tires.cornering_stiffness_rear_n_per_rad", "chassis.yaw_inertia_kgm2",
             "roll.roll_stiffness_front_nm_per_rad,roll.roll_stiffness_rear_nm_per_rad",
             "roll.roll_damping_front_nms_per_rad,roll.roll_damping_rear_nms_per_rad"),
    "8dof": ("axle_tires.cornering_stiffness_front_n_per_rad",
             "axle_tires.cornering_stiffness_rear_n_per_rad", "chassis.yaw_inertia_kgm2",
             "roll.roll_stiffness_front_nm_per_rad,roll.roll_stiffness_rear_nm_per_rad",
             "roll.roll_damping_front_nms_per_rad,roll.roll_damping_rear_nms_per_rad",
             "tire.relaxation_length_m"),
}


def make_level(name: str, tire: str | None = None) -> Level:
    """The level called ``name``.

    Raises
    ------
    ParameterError
        An unknown level, or a tire choice for a linear level.
    """
    if name not in LEVELS:
        raise ParameterError("--level", f"unknown level {name!r} (valid: auto, "
                             f"{', '.join(LEVELS)})")
    if tire is not None and name != "8dof":
        raise ParameterError("--tire", f"only the 8dof level has a tire choice (level {name})")
    return LEVELS[name](tire)


def auto_level(logs: Sequence[MeasuredLog], vehicle: Vehicle) -> tuple[str, str]:
    """The level ``auto`` picks and why: a linear one when every log stays in the linear
    range at one speed (3dof with roll data and a roll signal, else 2dof), else the 8dof."""
    linear = all(float(np.max(np.abs(g.channels["lateral_accel_mps2"]))) <= LINEAR_RANGE_MPS2
                 and float(np.ptp(g.channels["speed_mps"]))
                 <= LINEAR_SPEED_SPREAD * float(np.median(g.channels["speed_mps"]))
                 for g in logs)
    if not linear and vehicle.body is not None and vehicle.roll is not None:
        return "8dof", (f"a log leaves the linear range (|a_y| > {LINEAR_RANGE_MPS2:g} m/s^2) "
                        "or changes speed: the 8-DOF over the whole record")
    roll = vehicle.roll is not None and all(g.has("roll_rad") for g in logs)
    why = ("every log stays in the linear range at one speed" if linear else
           "the vehicle has no 8-DOF data (body, roll): the linear level it has")
    return ("3dof" if roll else "2dof"), why


# ------------------------------------------------------------------------------ results

@dataclass
class FittedValue:
    """One fitted vehicle field.

    Attributes
    ----------
    path : str
        ``subsystem.field``.
    spec : str
        The ``--fit`` entry that set it.
    unit : str
    base, value : float
        Base and fitted value.
    ci95 : float
        Half-width of the 95 % interval, in ``unit``.
    """

    path: str
    spec: str
    unit: str
    base: float
    value: float
    ci95: float

    @property
    def relative_ci95(self) -> float:
        """ci95 over |value| (inf for a value of 0)."""
        return self.ci95 / abs(self.value) if self.value != 0.0 else math.inf

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"path": self.path, "fit": self.spec, "unit": self.unit, "base": self.base,
                "value": self.value, "ci95": self.ci95, "relative_ci95": self.relative_ci95,
                "change": (self.value / self.base - 1.0) if self.base else None}


@dataclass
class ChannelFit:
    """Residual of one channel of one log.

    Attributes
    ----------
    log, channel, unit : str
    rms_residual : float
        RMS of the residual after the bias, channel unit.
    rms_signal : float
        Standard deviation of the measured channel, channel unit.
    bias : float
        The fitted constant offset (measured minus model), channel unit.
    sigma : float
        Noise standard deviation used as the channel's weight (inflation included).
    autocorrelation : float
        Lag-1 autocorrelation of the residual.
    """

    log: str
    channel: str
    unit: str
    rms_residual: float
    rms_signal: float
    bias: float
    sigma: float
    autocorrelation: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return dict(self.__dict__)


@dataclass
class FrequencyFit:
    """Measured against model frequency response of one output of one log (broadband
    input only): both H1 estimates from the same input, so estimator bias cancels.

    Attributes
    ----------
    log, output : str
    measured, model : fq.FrequencyResponse
        Per steering-wheel angle (output unit per rad).
    band_hz : tuple of float
        Trusted band of the measured estimate (coherence, excitation).
    gain_error_db, phase_error_deg : float
        RMS of the model's gain (dB) and phase (deg) error over the band.
    """

    log: str
    output: str
    measured: fq.FrequencyResponse
    model: fq.FrequencyResponse
    band_hz: tuple[float, float]
    gain_error_db: float
    phase_error_deg: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (the points of the band)."""
        mask = self.measured.trusted()
        return {"log": self.log, "output": self.output, "input": self.measured.input,
                "band_hz": list(self.band_hz), "gain_error_db_rms": self.gain_error_db,
                "phase_error_deg_rms": self.phase_error_deg,
                "freq_hz": self.measured.freq_hz[mask].tolist(),
                "measured_gain": self.measured.gain[mask].tolist(),
                "model_gain": np.abs(self.model.response[mask]).tolist(),
                "measured_phase_deg": fq.display_phase_deg(self.measured)[mask].tolist(),
                "model_phase_deg": fq.display_phase_deg(self.model)[mask].tolist()}


@dataclass
class FitResult:
    """Everything ``fourws identify`` reports.

    Attributes
    ----------
    level : str
    level_reason : str
        Why this level (``auto``) or "chosen".
    base : Vehicle
    vehicle : Vehicle
        The fitted vehicle.
    groups : list of FieldGroup
    values : list of FittedValue
        One per field set.
    theta, covariance : ndarray
        Fitted group parameters and their covariance.
    correlation : ndarray
        Correlation matrix of the groups.
    indistinguishable : list of (str, str, float)
        Group pairs with |rho| > :data:`INDISTINGUISHABLE`.
    channels : list of ChannelFit
    frequency : list of FrequencyFit
    logs : list of MeasuredLog
    model : list of dict
        Per log, the fitted model's compared channels plus their fitted biases (the measured
        ones are in ``logs``).
    evaluations : int
        Model runs of the fit.
    elapsed_s : float
        Wall time of the identification, s.
    bias : bool
        A constant offset per channel and log was fitted.
    notes : list of str
    """

    level: str
    level_reason: str
    base: Vehicle
    vehicle: Vehicle
    groups: list[FieldGroup]
    values: list[FittedValue]
    theta: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    indistinguishable: list[tuple[str, str, float]]
    channels: list[ChannelFit]
    frequency: list[FrequencyFit]
    logs: list[MeasuredLog]
    model: list[dict[str, np.ndarray]]
    evaluations: int
    elapsed_s: float
    bias: bool = True
    notes: list[str] = field(default_factory=list)

    def value(self, path: str) -> FittedValue:
        """The fitted value of field ``path``."""
        for v in self.values:
            if v.path == path:
                return v
        raise KeyError(path)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (``identification.json``)."""
        specs = [g.spec for g in self.groups]
        return json_ready({
            "level": self.level, "level_reason": self.level_reason,
            "base_vehicle": self.base.name, "base_source": self.base.source,
            "data": [{"name": g.name, "source": g.source, "duration_s": g.duration_s,
                      "samples": int(g.time_s.size), "sample_period_s": g.dt_s,
                      "maneuver": g.maneuver or None} for g in self.logs],
            "values": [v.to_dict() for v in self.values],
            "fit": specs,
            "correlation": {"fields": specs, "matrix": self.correlation.tolist()},
            "cannot_be_told_apart": [{"fields": [a, b], "correlation": r}
                                     for a, b, r in self.indistinguishable],
            "channels": [c.to_dict() for c in self.channels],
            "frequency_response": [f.to_dict() for f in self.frequency],
            "biases_fitted": self.bias,
            "evaluations": self.evaluations, "elapsed_s": self.elapsed_s,
            "notes": list(self.notes)})


class ExcitationError(ParameterError):
    """The record cannot pin the requested fields (named in :attr:`fields`)."""

    def __init__(self, fields: Sequence[str], problem: str, source: str | None) -> None:
        self.fields = tuple(fields)
        super().__init__(", ".join(fields), problem, source)


# ------------------------------------------------------------------------------ the fit

@dataclass
class _Problem:
    """The residual function of one fit."""

    level: Level
    logs: list[MeasuredLog]
    base: Vehicle
    groups: list[FieldGroup]
    channels: list[list[str]]  # per log
    sigma: list[dict[str, float]]  # per log, per channel
    bias: bool = True
    evaluations: int = 0

    def predict(self, theta: np.ndarray) -> list[dict[str, np.ndarray]]:
        vehicle = vehicle_with(self.base, self.groups, theta)
        self.evaluations += 1
        return [self.level.simulate(g, vehicle) for g in self.logs]

    def errors(self, pred: list[dict[str, np.ndarray]]) -> list[dict[str, np.ndarray]]:
        """Residuals per log and channel, each less its mean (the bias) when biases are
        fitted."""
        out = []
        for g, p, chans in zip(self.logs, pred, self.channels):
            errs = {c: g.channels[c] - p[c] for c in chans}
            out.append({c: e - float(np.mean(e)) for c, e in errs.items()} if self.bias
                       else errs)
        return out

    def weighted(self, theta: np.ndarray) -> np.ndarray:
        errs = self.errors(self.predict(theta))
        return np.concatenate([e[c] / s[c] for e, s, chans in
                               zip(errs, self.sigma, self.channels) for c in chans])

    def jacobian(self, theta: np.ndarray, central: bool) -> tuple[np.ndarray, np.ndarray]:
        """Weighted residual and its Jacobian by finite differences."""
        r0 = self.weighted(theta)
        jac = np.empty((r0.size, theta.size))
        for j in range(theta.size):
            h = _JAC_STEP * max(1.0, abs(1.0 + theta[j])) if central else 1e-6
            tp = theta.copy()
            tp[j] += h
            if central:
                tm = theta.copy()
                tm[j] -= h
                jac[:, j] = (self.weighted(tp) - self.weighted(tm)) / (2.0 * h)
            else:
                jac[:, j] = (self.weighted(tp) - r0) / h
        return r0, jac


def _fit_channels(level: Level, log: MeasuredLog) -> list[str]:
    return [c for c in FIT_CHANNELS if c in level.outputs and log.has(c)]


def _floor(channel: str) -> float:
    return COLUMN_BY_NAME[channel].noise_floor


def _covariance(jac: np.ndarray) -> np.ndarray:
    """(J^T J)^-1 from the singular values of J; a direction the data cannot see (a singular
    value below 1e-12 of the largest) makes the entries of the parameters it moves infinite,
    the others keep their values."""
    _, s, vt = np.linalg.svd(jac, full_matrices=False)
    n = jac.shape[1]
    big = s[0] if s.size else 0.0
    seen = s > big * 1e-12 if big > 0.0 else np.zeros(s.size, dtype=bool)
    cov = (vt[seen].T / s[seen] ** 2) @ vt[seen]
    blind = [vt[k] for k in range(s.size) if not seen[k]] + (
        [] if s.size == n else list(np.linalg.svd(jac)[2][s.size:]))
    for v in blind:
        moved = np.abs(v) > 1e-8
        cov[np.ix_(moved, moved)] = np.inf
    return cov


def _check_steering_units(log: MeasuredLog, vehicle: Vehicle) -> None:
    """δH/N against the kinematic steer L r/U in the linear range (:data:`STEER_YAW_RATIO`):
    a factor of 57 means degrees given as radians (files only: a bag is SI)."""
    if log.kind == "bag":
        return
    u = log.channels["speed_mps"]
    sel = (np.abs(log.channels["lateral_accel_mps2"]) <= LINEAR_RANGE_MPS2) & (u > 2.0)
    if np.count_nonzero(sel) < MIN_SAMPLES:
        return
    front = log.channels["steering_wheel_angle_rad"][sel] / _ratio(vehicle)
    kin = vehicle.chassis.wheelbase_m * log.channels["yaw_rate_radps"][sel] / u[sel]
    s_k, s_f = float(np.std(kin)), float(np.std(front))
    # a turn of less than 5 hand-wheel resolutions is too little steering to judge
    if s_k < 5.0 * COLUMN_BY_NAME["steering_wheel_angle_rad"].noise_floor / _ratio(vehicle):
        return
    ratio = s_f / s_k
    low, high = STEER_YAW_RATIO
    if not low <= ratio <= high:
        raise ParameterError("steering_wheel_angle_rad", f"over the steering ratio varies "
                             f"{ratio:.3g} times as much as the kinematic steer L r/U "
                             f"(a car: {low:g}-{high:g}); is the angle in degrees, or the "
                             f"ratio ({_ratio(vehicle):g}) not the car's?", log.source)


def _predicted_ci(problem: _Problem, theta0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Jacobian at the base with floor noise: (predicted relative 95 % half-widths,
    correlation)."""
    _, jac = problem.jacobian(theta0, central=False)
    cov = _covariance(jac)
    sd = np.sqrt(np.abs(np.diag(cov)))
    rel = np.array([Z95 * sd[j] * _unit_value(g) for j, g in enumerate(problem.groups)])
    return rel, _correlation(cov, sd)


def _correlation(cov: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """Correlation matrix of ``cov`` (NaN where a variance is infinite or 0)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    corr[~np.isfinite(corr)] = np.nan
    return corr


def _unit_value(group: FieldGroup) -> float:
    """Relative size of one unit of theta at the base (1 for scale groups and for fields whose
    base is their step)."""
    if group.mode == "scale":
        return 1.0
    v0 = abs(group.base[0])
    return group.step / v0 if v0 > 0 else 1.0


def _enters(problem: _Problem, j: int) -> bool:
    """Group ``j`` moves a number the level's model reads, for some log."""
    probe = np.zeros(len(problem.groups))
    probe[j] = 0.01
    moved = vehicle_with(problem.base, problem.groups, probe)
    return not all(np.array_equal(problem.level.signature(log, moved),
                                  problem.level.signature(log, problem.base))
                   for log in problem.logs)


def _excitation(problem: _Problem, requested: bool, notes: list[str]) -> list[FieldGroup]:
    """The groups the record can pin; refuse (requested) or drop with a note (defaults) the
    others, naming them: first roll fields without a roll signal and fields the model does
    not read, then, among the others, those the record would not pin."""
    groups = problem.groups
    source = ", ".join(log.source for log in problem.logs)

    def roll_signal(log: MeasuredLog) -> float:
        roll = log.channels["roll_rad"]
        # with a fitted bias only the roll's changes tell; without, its level too
        return float(np.std(roll) if problem.bias else np.sqrt(np.mean(roll ** 2)))

    problems: dict[str, str] = {}
    for j, g in enumerate(groups):
        if g.roll and not all(log.has("roll_rad") and roll_signal(log)
                              >= MIN_ROLL_SIGNAL_FLOORS * _floor("roll_rad")
                              for log in problem.logs):
            problems[g.spec] = ("no roll signal in the log (roll_rad missing or flat); roll "
                                "fields need one")
        elif not _enters(problem, j):
            hint = (" (the axle cornering stiffness enters the 8-DOF only with the linear "
                    "tire: --tire linear, or a linear level)"
                    if problem.level.name == "8dof" and g.paths[0].startswith("axle_tires.")
                    else "")
            problems[g.spec] = f"does not enter the {problem.level.name} model{hint}"
    rest = [g for g in groups if g.spec not in problems]
    if rest:
        sub = dataclasses.replace(problem, groups=rest, evaluations=0)
        rel, corr = _predicted_ci(sub, np.zeros(len(rest)))
        problem.evaluations += sub.evaluations
        for j, g in enumerate(rest):
            if rel[j] <= MAX_PREDICTED_CI:
                continue
            partner = ""
            row = np.nan_to_num(np.abs(corr[j]), nan=0.0, posinf=0.0)
            row[j] = 0.0
            if row.size > 1 and row.max() > INDISTINGUISHABLE:
                partner = f", cannot be told apart from {rest[int(np.argmax(row))].spec}"
            elif not math.isfinite(rel[j]):
                others = [rest[k].spec for k in range(len(rest))
                          if k != j and not math.isfinite(rel[k])]
                if others:
                    partner = f", cannot be told apart from {', '.join(others)}"
            what = ("not pinned at all" if not rel[j] <= 10.0
                    else f"pinned only to +-{100 * rel[j]:.0f} %")
            problems[g.spec] = f"{what} (95 %, instrument-level noise){partner}"
    if not problems:
        return list(groups)
    if requested:
        raise ExcitationError(
            list(problems), "too little excitation in the record for these fields: "
            + "; ".join(f"{k}: {v}" for k, v in problems.items())
            + f" (a field must be pinned within +-{100 * MAX_PREDICTED_CI:g} %: add a "
            "transient or broadband steer, or fit fewer fields)", source)
    for spec, why in problems.items():
        notes.append(f"default field {spec} left out: {why}")
    return [g for g in groups if g.spec not in problems]


def identify(logs: Sequence[MeasuredLog], base: Vehicle, level: str = "auto",
             fields: Sequence[str] | None = None, tire: str | None = None,
             name: str | None = None, bias: bool = True,
             progress: Callable[[str], None] | None = None) -> FitResult:
    """Fit ``fields`` of ``base`` to ``logs`` on model ``level`` (module docstring).

    Parameters
    ----------
    logs : sequence of MeasuredLog
        Fitted together (one bias per channel and log).
    base : Vehicle
        The start and every field not fitted.
    level : str
        ``auto`` or a key of :data:`LEVELS`.
    fields : sequence of str, optional
        ``--fit`` entries; default :data:`DEFAULT_FIELDS` of the level (those the record can
        pin).
    tire : str, optional
        Tire model of the 8-DOF level.
    name : str, optional
        Name of the fitted vehicle (default ``<base>_fitted``).
    bias : bool
        Fit a constant offset per channel and log (default). False: the sensors are taken as
        zeroed, so a steady record's levels carry information (a steady-state circular run
        pins the cornering stiffnesses only this way).
    progress : callable, optional
        Called with a short description of each stage.

    Raises
    ------
    ParameterError
        A bad field, a log the level cannot take, units that cannot be right.
    ExcitationError
        Too little excitation for requested fields (named).
    """
    tick = progress or (lambda _m: None)
    start = time.perf_counter()
    logs = list(logs)
    if not logs:
        raise ParameterError("DATA", "no log given")
    for log in logs:
        _check_steering_units(log, base)
    if level == "auto":
        level, reason = auto_level(logs, base)
    else:
        reason = "chosen"
    lvl = make_level(level, tire)
    for log in logs:
        lvl.check(log, base)
    requested = fields is not None and len(fields) > 0
    specs = list(fields) if requested else [
        s for s in DEFAULT_FIELDS[level] if _has_fields(base, s)]
    groups = [parse_field(s, base) for s in specs]
    chans = [_fit_channels(lvl, g) for g in logs]
    for log, c in zip(logs, chans):
        if not c:
            raise ParameterError("DATA", f"no channel the {level} level predicts "
                                 f"({', '.join(lvl.outputs)})", log.source)
    notes: list[str] = []
    floors = [{c: _floor(c) for c in cs} for cs in chans]
    tick("excitation check")
    problem = _Problem(lvl, logs, base, groups, chans, floors, bias)
    groups = _excitation(problem, requested, notes)
    if not groups:
        raise ExcitationError(specs, "too little excitation in the record for every default "
                              "field; name the fields with --fit", logs[0].source)
    problem.groups = groups
    theta0 = np.zeros(len(groups))
    bounds = (np.array([g.bounds[0] for g in groups]), np.array([g.bounds[1] for g in groups]))
    # pass 1: channels weighted by a share of their spread (or the floor) ...
    problem.sigma = [{c: max(_floor(c), 0.05 * float(np.std(g.channels[c]))) for c in cs}
                     for g, cs in zip(logs, chans)]
    tick("fit, pass 1")
    sol = scipy.optimize.least_squares(problem.weighted, theta0, bounds=bounds,
                                       x_scale=1.0, xtol=1e-6, ftol=1e-8, gtol=1e-8,
                                       max_nfev=60)
    # ... pass 2: by the residual noise each channel shows (its floor at least), inflated for
    # correlated residuals; its Jacobian at the optimum gives the covariance
    errs = problem.errors(problem.predict(sol.x))
    problem.sigma = [{c: _sigma(e[c], _floor(c)) for c in cs} for e, cs in zip(errs, chans)]
    tick("fit, pass 2")
    sol = scipy.optimize.least_squares(problem.weighted, sol.x, bounds=bounds, x_scale=1.0,
                                       xtol=1e-10, ftol=1e-12, gtol=1e-12, max_nfev=60)
    tick("uncertainty")
    _, jac = problem.jacobian(sol.x, central=True)
    cov = _covariance(jac)
    sd = np.sqrt(np.abs(np.diag(cov)))
    corr = _correlation(cov, sd)
    vehicle = vehicle_with(base, groups, sol.x, name or f"{base.name}_fitted")
    values: list[FittedValue] = []
    for j, g in enumerate(groups):
        for path, b, v in zip(g.paths, g.base, g.values(float(sol.x[j]))):
            half = Z95 * sd[j] * (abs(b) if g.mode == "scale" else g.step)
            values.append(FittedValue(path, g.spec, field_unit(path), b, v, half))
    pairs = [(groups[i].spec, groups[j].spec, float(corr[i, j]))
             for i in range(len(groups)) for j in range(i + 1, len(groups))
             if abs(corr[i, j]) > INDISTINGUISHABLE]
    pred = problem.predict(sol.x)
    channels: list[ChannelFit] = []
    model: list[dict[str, np.ndarray]] = []
    for g, p, cs, sig in zip(logs, pred, chans, problem.sigma):
        shown = {}
        for c in cs:
            e = g.channels[c] - p[c]
            offset = float(np.mean(e)) if bias else 0.0
            shown[c] = p[c] + offset
            channels.append(ChannelFit(g.name, c, COLUMN_BY_NAME[c].unit,
                                       float(np.sqrt(np.mean((e - offset) ** 2))),
                                       float(np.std(g.channels[c])), offset, sig[c],
                                       _lag1(e - offset)))
        model.append(shown)
    tick("frequency response")
    frequency = [fr for g, p, cs in zip(logs, model, chans) for fr in _frequency_fit(g, p, cs)]
    if any(not math.isfinite(s) for s in sd):
        notes.append("the record cannot pin every fitted value: infinite intervals mark them")
    if sol.status == 0:
        notes.append(f"the fit stopped at its evaluation limit ({sol.nfev}) before converging")
    return FitResult(level=level, level_reason=reason, base=base, vehicle=vehicle,
                     groups=groups, values=values, theta=sol.x, covariance=cov,
                     correlation=corr, indistinguishable=pairs, channels=channels,
                     frequency=frequency, logs=logs, model=model,
                     evaluations=problem.evaluations,
                     elapsed_s=time.perf_counter() - start, bias=bias, notes=notes)


def _has_fields(vehicle: Vehicle, spec: str) -> bool:
    """Every subsystem a default field names exists in ``vehicle``, and a relaxation length
    is set (0 means no tire lag: nothing to fit)."""
    for part in spec.split(","):
        sub, _, name = part.partition(".")
        obj = getattr(vehicle, sub, None)
        if obj is None:
            return False
        if name == "relaxation_length_m" and obj.relaxation_length_front_m == 0.0:
            return False
    return True


def _lag1(e: np.ndarray) -> float:
    d = e - np.mean(e)
    den = float(np.dot(d, d))
    return float(np.dot(d[1:], d[:-1]) / den) if den > 0 else 0.0


def _sigma(e: np.ndarray, floor: float) -> float:
    """Weight of a channel: its residual's standard deviation, its variance inflated by
    (1 + rho1) / (1 - rho1) for a residual correlated from sample to sample (at most 100),
    and at least ``floor`` (white instrument noise)."""
    rho = min(max(_lag1(e), 0.0), 0.98)
    inflation = min((1.0 + rho) / (1.0 - rho), 100.0)
    return max(float(np.std(e)) * math.sqrt(inflation), floor)


def _frequency_fit(log: MeasuredLog, model: Mapping[str, np.ndarray],
                   channels: Sequence[str]) -> list[FrequencyFit]:
    """Measured and model H1 per steering-wheel angle for each output, when the input is
    broadband: trusted over at least two octaves (coherence, excitation)."""
    u = log.channels["steering_wheel_angle_rad"]
    method = "transient" if log.maneuver in fq.TRANSIENT_MANEUVERS else "welch"
    out = []
    for c in channels:
        try:
            meas = fq.estimate_response(u, log.channels[c], log.dt_s, method=method, output=c,
                                        input_name="steering_wheel_angle_rad")
            mod = fq.estimate_response(u, model[c], log.dt_s, method=method, output=c,
                                       input_name="steering_wheel_angle_rad")
        except FourwsError:
            continue
        mask = meas.trusted()
        if np.count_nonzero(mask) < 8:
            continue
        f = meas.freq_hz[mask]
        lo, hi = float(f[f > 0].min()) if np.any(f > 0) else 0.0, float(f.max())
        if lo <= 0.0 or hi / lo < 4.0:
            continue
        mod.label = "model"
        gain_err = 20.0 * np.log10(np.abs(mod.response[mask]) / np.abs(meas.response[mask]))
        phase_err = np.degrees(np.angle(mod.response[mask] / meas.response[mask]))
        out.append(FrequencyFit(log.name, c, meas, mod, (lo, hi),
                                float(np.sqrt(np.mean(gain_err ** 2))),
                                float(np.sqrt(np.mean(phase_err ** 2)))))
    return out


# ------------------------------------------------------------------------------ the file

def _yaml_scalar(value: Any) -> str:
    """A scalar of a vehicle mapping in YAML (floats exactly, strings JSON-quoted)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return _quoted(value)
    return str(value)


def _yaml_lines(value: Any, indent: int, comments: Mapping[str, str],
                prefix: str = "") -> list[str]:
    """Block YAML of a mapping or list at ``indent`` spaces; ``comments`` by dotted key."""
    pad = " " * indent
    lines: list[str] = []
    if isinstance(value, Mapping):
        for key, item in value.items():
            dotted = f"{prefix}{key}"
            if isinstance(item, (Mapping, list, tuple)) and item:
                lines.append(f"{pad}{key}:")
                lines.extend(_yaml_lines(item, indent + 2, comments, f"{dotted}."))
            else:
                text = ("{}" if isinstance(item, Mapping) else "[]"
                        if isinstance(item, (list, tuple)) else _yaml_scalar(item))
                note = comments.get(dotted)
                lines.append(f"{pad}{key}: {text}" + (f"   # {note}" if note else ""))
    else:
        for item in value:
            lines.append(f"{pad}- {_yaml_scalar(item)}")
    return lines


def vehicle_yaml(result: FitResult) -> str:
    """The fitted vehicle as a vehicle file (the layout of ``config/vehicles``), every fitted
    value commented with its interval and its data; :func:`fourws_sim.params.load_vehicle`
    reads it."""
    data = ", ".join(f"{g.name} ({g.duration_s:.1f} s{', ' + g.maneuver if g.maneuver else ''})"
                     for g in result.logs)
    lines = [
        f"# Fitted by `fourws identify` from the base vehicle {result.base.name}",
        f"# ({result.base.source or 'built in'}) on the {result.level} level to: {data}.",
        "# Each fitted value carries its 95 % interval (residual noise, Jacobian at the",
        "# optimum); every other value is the base's. Residual RMS per channel:",
    ]
    for c in result.channels:
        lines.append(f"#   {c.log}: {c.channel} {c.rms_residual:.4g} {c.unit} "
                     f"(signal {c.rms_signal:.4g}, bias {c.bias:+.3g})")
    for a, b, r in result.indistinguishable:
        lines.append(f"# Cannot be told apart (correlation {r:+.3f}): {a} and {b}.")
    comments = {}
    for fv in result.values:
        change = (f"{100 * (fv.value / fv.base - 1):+.1f} % from the base {fv.base:.6g}"
                  if fv.base else f"base {fv.base:g}")
        comments[fv.path] = (f"fitted: {fv.value:.6g} +- {fv.ci95:.3g} {fv.unit} (95 %), "
                             f"{change}; {result.level} on {data}")
    mapping = dict(result.vehicle.to_dict())
    mapping["description"] = f"{result.base.name} fitted on the {result.level} level to {data}"
    lines.extend(_yaml_lines(mapping, 0, comments))
    return "\n".join(lines) + "\n"


def _quoted(text: str) -> str:
    """A YAML double-quoted scalar (JSON's string syntax is a subset of it)."""
    return json.dumps(str(text), ensure_ascii=False)


__all__ = ["ChannelFit", "DEFAULT_FIELDS", "EightDofLevel", "ExcitationError", "FIT_CHANNELS",
           "FieldGroup", "FitResult", "FittedValue", "FrequencyFit", "INDISTINGUISHABLE",
           "LEVELS", "Level", "LinearLevel", "MAX_PREDICTED_CI", "auto_level", "field_unit",
           "identify", "make_level", "parse_field", "steer_inputs", "vehicle_with",
           "vehicle_yaml"]
