# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Common interface of the rear-wheel steering laws, and the rear-steer actuator.

Every law in fourws is linear in the measured signals with gains scheduled on the forward
speed ``U`` (chapter 4 shows that constant gains can destabilize the vehicle):

.. math::

    \\delta_r = k_{\\delta}(U)\\,\\delta_f + k_r(U)\\,r + k_\\phi(U)\\,\\phi
               + k_{\\dot\\phi}(U)\\,\\dot\\phi + k_V(U)\\,V

A law computes the gain vector :meth:`Law.gains` from its *belief* vehicle (which may differ
from the simulated one, e.g. ``vehicle.with_axle_tires(0.6)``) and applies it to a
:class:`LawInput`. Because every law has this form, :meth:`Law.linear_gains` can express it
in the state/input order of any linear model (or of the 8-DOF's linearization), which lets
the analysis close the loop exactly.

Signs follow ``docs/architecture.md``: positive steer angles turn left, ``r`` positive to the
left, ``V`` positive to the left, roll positive right side down (the roll gains are expressed
in that convention whatever the model's internal convention is).

Low speed
---------
Closed-form gains contain ``1/U`` terms (e.g. ``Kr U`` of Solution 1 grows like ``1/U``) and
the LQR design becomes ill-conditioned near standstill. Below ``min_speed_mps`` (default
:data:`DEFAULT_MIN_SPEED_MPS`) every law therefore uses the gains of ``min_speed_mps`` scaled
by ``U / min_speed_mps``: the rear steer fades linearly to zero at standstill (and stays zero
when reversing), continuous in ``U`` and never NaN.

Sampling
--------
A law runs in a sampled loop: its command is computed once per control period ``Tc`` and held
(zero-order hold) by the actuator until the next (``docs/architecture.md``, tick sequence of
:mod:`fourws_run.closed_loop`). Every law is built with the period it will run at
(``control_period_s``, default :data:`DEFAULT_CONTROL_PERIOD_S`; the offline runner and the
controller node pass the loop's period through :func:`fourws_control.registry.make_loop_law`).
Laws designed in continuous time (closed forms of chapters 4 and 6) do not use it; a law
designed for the sampled loop (``lqr``'s default design) does.

Plain functions
---------------
The arithmetic of a law step is written once as plain functions of floats and arrays, in the
subset of Python that numba compiles: each law's gain schedule (:class:`GainFunction`,
:meth:`Law.gain_function`), the low-speed fade (:func:`gain_speed`), the sum of the gained
signals (:func:`rear_angle_of`) and the actuator's limits (:func:`actuator_step`). The
classes here call them; the study's compiled loop compiles the same functions
(:mod:`fourws_control.compiled` collects them from the registry: each law class names its
own in :attr:`Law.gain_functions` and :attr:`Law.gain_helpers`), so a compiled closed loop
performs the same float operations in the same order as the interpreted one.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Mapping

import numpy as np

from fourws_control.bicycle import bicycle
from fourws_control.signals import Signal, signal_map
from fourws_sim.errors import IncompatibleError, NonFiniteError, ParameterError
from fourws_sim.params import Actuators, Vehicle

#: Speed below which the gains fade linearly to zero at standstill, m/s. Parking-lot speeds
#: (~7 km/h) keep full gains; walking pace and below fades out.
DEFAULT_MIN_SPEED_MPS = 2.0
#: Control period a law is designed for when none is given, s: fourws' default 100 Hz loop
#: (``control_period_s`` of ``config/scenarios/*.yaml`` and of the controller node).
DEFAULT_CONTROL_PERIOD_S = 0.01


@dataclass(frozen=True, slots=True)
class LawInput:
    """What a law may measure at one instant (SI, ``docs/architecture.md`` signs)."""

    delta_f_rad: float
    speed_mps: float
    yaw_rate_radps: float = 0.0
    roll_rad: float = 0.0
    roll_rate_radps: float = 0.0
    lateral_velocity_mps: float = 0.0
    time_s: float = 0.0


@dataclass(frozen=True)
class LinearGains:
    """A law written for a linear model: ``delta_r = K_x @ x + K_u @ u``.

    Attributes
    ----------
    model : str
        Model name (``2dof``, ``2dof-free``, ``2dof-lagged``, ``3dof``, or ``8dof`` for its
        linearization, :data:`fourws_control.signals.LINEARIZED_MODELS`).
    speed_mps : float
        Forward speed the gains belong to, m/s.
    K_x : numpy.ndarray
        Gains on the model states, shape ``(n_states,)``, in the model's ``STATE`` order.
    K_u : numpy.ndarray
        Gains on the model inputs, shape ``(n_inputs,)``, in the model's ``INPUT`` order; the
        entry of the rear-steer input itself is zero.
    state_names, input_names : tuple of str
        Names of the model's ``STATE`` and ``INPUT`` members.
    """

    model: str
    speed_mps: float
    K_x: np.ndarray
    K_u: np.ndarray
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"model": self.model, "speed_mps": self.speed_mps,
                "K_x": dict(zip(self.state_names, map(float, self.K_x))),
                "K_u": dict(zip(self.input_names, map(float, self.K_u)))}


@dataclass(frozen=True)
class GainFunction:
    """A law's gain schedule as a plain function of the speed and a parameter vector.

    ``function(speed_mps, params, out)`` writes the gains at ``speed_mps >= min_speed_mps``
    (m/s) in :class:`Signal` order into ``out`` (length ``len(Signal)``, zeros on entry), from
    the law's parameter vector ``params`` (float64). It uses only float arithmetic, indexing
    and the functions of its own module, so numba compiles it to the same operations.

    Attributes
    ----------
    function : callable
        ``f(speed_mps, params, out) -> None``.
    params : numpy.ndarray
        The law's parameters (read only), in the order ``function`` reads them.
    """

    function: Callable[[float, np.ndarray, np.ndarray], None]
    params: np.ndarray

    def __post_init__(self) -> None:
        params = np.array(self.params, dtype=np.float64).reshape(-1)
        params.flags.writeable = False
        object.__setattr__(self, "params", params)

    def evaluate(self, speed_mps: float) -> np.ndarray:
        """The gains at ``speed_mps`` (m/s), :class:`Signal` order."""
        out = np.zeros(len(Signal))
        self.function(speed_mps, self.params, out)
        return out


def gain_speed(speed_mps: float, min_speed_mps: float) -> tuple[float, float]:
    """``(design speed, scale)``: a law's gains at ``speed_mps`` are its design gains at the
    design speed times ``scale`` -- the speed itself and 1 at or above ``min_speed_mps``,
    else ``min_speed_mps`` and ``max(U, 0) / min_speed_mps`` (the low-speed fade of the
    module docstring). Speeds in m/s."""
    if speed_mps >= min_speed_mps:
        return speed_mps, 1.0
    return min_speed_mps, max(speed_mps, 0.0) / min_speed_mps


def rear_angle_of(k: Any, delta_f_rad: float, yaw_rate_radps: float, roll_rad: float,
                  roll_rate_radps: float, lateral_velocity_mps: float) -> float:
    """The rear road-wheel angle (rad) of gains ``k`` (:class:`Signal` order, units of
    :data:`GAIN_UNITS`) and the signals they multiply (SI)."""
    return (k[0] * delta_f_rad + k[1] * yaw_rate_radps + k[2] * roll_rad
            + k[3] * roll_rate_radps + k[4] * lateral_velocity_mps)


def actuator_step(angle_rad: float, command_rad: float, angle_limit_rad: float,
                  max_step_rad: float) -> float:
    """The rear actuator's angle after one period: from ``angle_rad`` toward ``command_rad``
    clipped to ``+-angle_limit_rad``, by at most ``max_step_rad`` (the rate limit times the
    period). Angles in rad."""
    target = min(max(command_rad, -angle_limit_rad), angle_limit_rad)
    step = min(max(target - angle_rad, -max_step_rad), max_step_rad)
    return angle_rad + step


def check_speed(speed_mps: float, field: str = "speed_mps") -> float:
    """Return ``speed_mps`` as float; raise :class:`ParameterError` unless finite and > 0."""
    try:
        value = float(speed_mps)
    except (TypeError, ValueError):
        raise ParameterError(field, f"must be a number, got {speed_mps!r}") from None
    if not math.isfinite(value) or value <= 0.0:
        raise ParameterError(field, f"must be finite and > 0 m/s, got {speed_mps!r}")
    return value


def check_option(name: str, value: Any, check: str = "positive") -> float:
    """Validate one numeric law option ("positive" or "nonnegative"); return it as float."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ParameterError(name, f"must be a number, got {value!r}")
    v = float(value)
    ok = v > 0.0 if check == "positive" else v >= 0.0
    if not math.isfinite(v) or not ok:
        rel = "> 0" if check == "positive" else ">= 0"
        raise ParameterError(name, f"must be finite and {rel}, got {value!r}")
    return v


class Law(ABC):
    """A speed-scheduled linear rear-steer law.

    Parameters
    ----------
    belief_vehicle : Vehicle
        The vehicle the controller believes it drives; gains are computed from it.
    min_speed_mps : float, optional
        Below this speed the gains fade linearly to zero at standstill (see module docstring).
    control_period_s : float, optional
        Period of the sampled loop the law runs in, s (> 0; see module docstring).

    Subclasses set :attr:`name`, :attr:`signals` (the signals with possibly non-zero gain)
    and implement :meth:`_design_gains` for ``U >= min_speed_mps``.
    """

    #: Registry name of the law.
    name: ClassVar[str] = ""
    #: One-line description with the paper reference.
    summary: ClassVar[str] = ""
    #: Signals the law uses; a linear model lacking one of them cannot be closed with it.
    signals: ClassVar[tuple[Signal, ...]] = ()
    #: The plain gain functions of the law's module that :meth:`gain_function` may hold
    #: (the study's compiled loop compiles them, :mod:`fourws_control.compiled`); none: the
    #: law runs interpreted only.
    gain_functions: ClassVar[tuple[Callable[[float, np.ndarray, np.ndarray], None], ...]] = ()
    #: The plain functions of its module that the gain functions call (compiled with them).
    gain_helpers: ClassVar[tuple[Callable[..., Any], ...]] = ()

    def __init__(self, belief_vehicle: Vehicle, *,
                 min_speed_mps: float = DEFAULT_MIN_SPEED_MPS,
                 control_period_s: float = DEFAULT_CONTROL_PERIOD_S) -> None:
        if not isinstance(belief_vehicle, Vehicle):
            raise ParameterError("belief_vehicle",
                                 f"must be a fourws Vehicle, got {type(belief_vehicle).__name__}")
        self.vehicle = belief_vehicle
        #: 2-DOF parameters of the belief vehicle, extracted once (laws run at 100 Hz)
        self.bicycle = bicycle(belief_vehicle)
        self.min_speed_mps = check_option("min_speed_mps", min_speed_mps)
        self.control_period_s = check_option("control_period_s", control_period_s)

    @abstractmethod
    def _design_gains(self, speed_mps: float) -> np.ndarray:
        """Gains in :class:`Signal` order at ``speed_mps >= min_speed_mps``."""

    def gain_function(self) -> GainFunction | None:
        """The law's gain schedule as a plain function (:class:`GainFunction`; its
        ``evaluate`` is :meth:`_design_gains`), or None for a law that has none (it then only
        runs interpreted)."""
        return None

    def gains(self, speed_mps: float) -> np.ndarray:
        """Gain vector in :class:`Signal` order at forward speed ``speed_mps`` (m/s).

        Units per :data:`fourws_control.signals.GAIN_UNITS`. Below ``min_speed_mps`` the gains
        of ``min_speed_mps`` scaled by ``max(U, 0) / min_speed_mps``.

        Raises
        ------
        NonFiniteError
            If the speed is not finite or the gains come out non-finite.
        """
        u = float(speed_mps)
        if not math.isfinite(u):
            raise NonFiniteError(f"{self.name}: speed_mps must be finite, got {speed_mps!r}")
        design_speed, scale = gain_speed(u, self.min_speed_mps)
        k = self._design_gains(design_speed)
        if scale != 1.0:
            k = k * scale
        if not np.all(np.isfinite(k)):
            raise NonFiniteError(f"{self.name}: non-finite gains {k} at speed {u} m/s")
        return k

    def gains_dict(self, speed_mps: float) -> dict[str, float]:
        """:meth:`gains` as ``{signal name (lower case): gain}`` for reports/JSON."""
        k = self.gains(speed_mps)
        return {s.name.lower(): float(k[s]) for s in self.signals}

    def rear_angle(self, inp: LawInput) -> float:
        """Rear road-wheel angle command in rad (before actuator limits)."""
        k = self.gains(inp.speed_mps)
        out = float(rear_angle_of(k, inp.delta_f_rad, inp.yaw_rate_radps, inp.roll_rad,
                                  inp.roll_rate_radps, inp.lateral_velocity_mps))
        if not math.isfinite(out):
            raise NonFiniteError(f"{self.name}: non-finite rear angle for input {inp}")
        return out

    __call__ = rear_angle

    def linear_gains(self, model_name: str, vehicle: Vehicle | None = None,
                     speed_mps: float = 0.0) -> LinearGains:
        """The law in a model's state/input order: ``delta_r = K_x x + K_u u``.

        Parameters
        ----------
        model_name : str
            ``2dof``, ``2dof-free``, ``2dof-lagged``, ``3dof`` (linear models), or ``8dof``
            (the state and input order of its linearization; the law is linear, so its gains
            are the same about any trim).
        vehicle : Vehicle, optional
            The model's (true) vehicle; only used to check that the model can be built.
        speed_mps : float
            Forward speed, m/s (> 0).

        Raises
        ------
        ParameterError
            Speed not > 0.
        IncompatibleError
            The law uses a signal the model does not have (e.g. roll feedback on a 2-DOF).
        """
        speed = check_speed(speed_mps)
        smap = signal_map(model_name)
        missing = [s for s in self.signals if s not in smap.available]
        if missing:
            raise IncompatibleError(
                f"law {self.name!r} needs {', '.join(s.name.lower() for s in missing)}, "
                f"which model {model_name!r} does not have")
        k = self.gains(speed)
        K_x = np.zeros(len(smap.state_names))
        K_u = np.zeros(len(smap.input_names))
        for sig, (where, index, scale) in smap.positions.items():
            if sig not in self.signals:
                continue
            if where == "state":
                K_x[index] += k[sig] * scale
            else:
                K_u[index] += k[sig] * scale
        return LinearGains(model_name, speed, K_x, K_u, smap.state_names, smap.input_names)

    def describe(self) -> Mapping[str, Any]:
        """Name, summary and belief-vehicle name (for run configurations)."""
        return {"law": self.name, "summary": self.summary, "belief_vehicle": self.vehicle.name,
                "min_speed_mps": self.min_speed_mps, "control_period_s": self.control_period_s}


class RearSteerActuator:
    """Rear-steer actuator: angle and rate limits on the commanded rear road-wheel angle.

    Parameters
    ----------
    vehicle : Vehicle, optional
        Source of the default limits (``vehicle.actuators``); the fourws defaults otherwise.
    angle_limit_rad : float, optional
        Override of ``|delta_r|`` max, rad (> 0).
    rate_limit_rad_per_s : float, optional
        Override of ``|d delta_r / dt|`` max, rad/s (> 0; ``math.inf`` disables it).
    initial_angle_rad : float
        Angle at start, rad.
    """

    def __init__(self, vehicle: Vehicle | None = None, *, angle_limit_rad: float | None = None,
                 rate_limit_rad_per_s: float | None = None,
                 initial_angle_rad: float = 0.0) -> None:
        act = vehicle.actuators if vehicle is not None else Actuators()
        self.angle_limit_rad = check_option(
            "angle_limit_rad",
            act.rear_angle_limit_rad if angle_limit_rad is None else angle_limit_rad)
        rate = act.rear_rate_limit_rad_per_s if rate_limit_rad_per_s is None \
            else rate_limit_rad_per_s
        if isinstance(rate, (int, float)) and not isinstance(rate, bool) and rate == math.inf:
            self.rate_limit_rad_per_s = math.inf
        else:
            self.rate_limit_rad_per_s = check_option("rate_limit_rad_per_s", rate)
        self.angle_rad = 0.0
        self.reset(initial_angle_rad)

    def reset(self, angle_rad: float = 0.0) -> None:
        """Set the current angle (clipped to the angle limit), rad."""
        a = float(angle_rad)
        if not math.isfinite(a):
            raise NonFiniteError(f"rear actuator: initial angle must be finite, got {angle_rad!r}")
        self.angle_rad = min(max(a, -self.angle_limit_rad), self.angle_limit_rad)

    def apply(self, command_rad: float, dt_s: float) -> float:
        """Move toward ``command_rad`` within the limits over ``dt_s`` seconds; return the angle.

        Raises
        ------
        NonFiniteError
            Non-finite command.
        ParameterError
            ``dt_s`` not > 0.
        """
        cmd = float(command_rad)
        if not math.isfinite(cmd):
            raise NonFiniteError(f"rear actuator: command must be finite, got {command_rad!r}")
        dt = check_option("dt_s", dt_s)
        self.angle_rad = actuator_step(self.angle_rad, cmd, self.angle_limit_rad,
                                       self.rate_limit_rad_per_s * dt)
        return self.angle_rad
