# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Driver models: the speed-hold driver and a single-point preview path follower.

A maneuver (:mod:`fourws_sim.maneuvers`) combines an open-loop steering waveform or a path
follower with the speed-hold driver into one :class:`DriverCommand` per control tick.

Call sequence and determinism
-----------------------------
Drivers with internal state (the PI integrator of :class:`SpeedHoldDriver`, the lateral-error
integrator of :class:`PreviewPathDriver`) advance *only* inside their ``command``/``steer``
calls, by ``dt = t - t_previous`` of the times they are given (0 on the first call). Online
(the maneuver node, called once per received state at the control rate) and offline
(:func:`fourws_run.closed_loop.run_closed_loop`) they are called with the same sequence of
``(t_k, outputs_k)``, so they produce the same commands bit for bit.

Speed-hold driver
-----------------
A PI controller from the speed error ``e = U_target - U`` (m/s) to a longitudinal acceleration
request ``a = kp e + ki \int e dt`` (m/s^2), turned into a total wheel torque
``T = m R (a + f_r g + D/m)`` (N m; ``m`` vehicle mass, ``R`` wheel radius, ``f_r``
rolling-resistance coefficient of the tire data, ``D = 0.5 rho C_d A U |U|`` the aerodynamic
drag of the ``aero`` data at the measured speed U, 0 without it: :func:`speed_hold_torque`).
``T > 0`` goes to the driven axles (the vehicle's ``driveline``: its ``drive`` and front
torque fraction; without one ``driven_axle``), each axle's share equally to its two wheels
(the open split its differential starts from: :func:`drive_fractions`); ``T < 0`` is applied
as brake torque split front/rear by ``brake_front_fraction`` (each axle's share equally on
its two wheels). The integrator stops while the torque saturates (anti-windup by
conditional integration). Vehicles with no ``body`` data (single-track models, which hold
speed by construction) get zero torques.

Preview path follower
---------------------
A single-point preview ("pure pursuit") driver: the driver looks at the point of the reference
path a preview distance ``L_p = max(L_min, U T_p)`` ahead of the vehicle and steers the
curvature of the circular arc through that point tangent to the current heading,
``kappa = 2 y_p / L_p^2`` (``y_p`` the lateral offset of the preview point in the vehicle
frame; Coulter 1992, "Implementation of the pure pursuit path tracking algorithm",
CMU-RI-TR-92-01). The preview-time concept and the 0.5–1.5 s range of human preview times
follow MacAdam (1981), "Application of an optimal preview control for simulation of closed-loop
automobile driving", IEEE Trans. SMC 11(6). The curvature is turned into a front road-wheel
angle with the driver's internal model of the car, the steady-state inverse of the linear
bicycle model, ``delta_f = (L + K_us U^2) kappa`` (``K_us`` the understeer gradient of the
vehicle's axle cornering stiffnesses), plus an optional feedback of the yaw-rate shortfall
``k_r (U kappa - r)`` (the driver feels that the car turns less than asked, e.g. when a
rear-steer law lowers its yaw gain, and steers more), plus a slow integral of the lateral path
error — the trim a human driver applies in steady cornering — which removes the remaining
offset that tire nonlinearity and a rear-steer law (which changes the car's steady-state gain)
leave:

    delta_f = (L + K_us U^2) kappa + k_r (U kappa - r) - k_i \int e_y dt.

Path-tracking driver (lane changes)
-----------------------------------
:class:`PathTrackingDriver` follows a smooth reference line (:class:`SplinePath`, e.g. the
widest-margin line of :mod:`fourws_sim.corridor`) closely enough to thread the ISO 3888-2 cones,
whatever rear-steer law the car carries. It follows the feedback-feedforward design of Kapania
& Gerdes (2015), "Design of a feedback-feedforward steering controller for accurate path tracking
and stability at the limits of handling", Vehicle System Dynamics 53(12): a feedforward of the
path curvature through the steady-state car model plus feedback of the path errors, and their
finding that the path deviation is smallest when the velocity vector (heading plus sideslip), not
the heading, is held tangent to the path, so the angle error fed back is the *course* error
(Rajamani (2012), Vehicle Dynamics and Control, 2nd ed., ch. 3, derives the path-error
dynamics). Two additions make it
independent of the law, which changes both the car's yaw gain (a factor of two between ``fws`` and
``sol1`` on table_8_1) and the mix of yaw and sideslip in its response: an inner loop on the
turning rate the driver feels, and a countersteer on sideslip. With the path ``y_ref(x)``, its
heading ``theta_ref = atan y_ref'`` and curvature ``kappa_ref``, and the vehicle's CG position
(x, y), heading ``psi``, sideslip ``beta``, speed U, yaw rate r and lateral acceleration a_y:

    e_y = (y - y_ref(x)) cos(theta_ref),   e_chi = psi + beta - theta_ref       (path errors)
    a_c = U^2 kappa_ref(x + U T_p) - w_n^2 e_y - 2 zeta w_n U sin(e_chi)        (m/s^2)
    omega = w r + (1 - w) abar_y / U,   e_w = a_c / U - omega                   (rad/s)
    delta_c = (L + K_us U^2) a_c / U^2 + k_p e_w + k_i \int e_w dt + k_b beta
    T_n d(delta)/dt + delta = delta_c,   |delta| <= delta_max.

The lateral-acceleration command ``a_c`` makes the path error a damped second-order system
(natural frequency ``w_n``, damping ``zeta``) around the previewed curvature (``T_p`` looks
ahead over the car's response lag). The felt turning rate ``omega`` mixes the yaw rate (weight
``w``) with the course rate ``a_y / U`` (``abar_y``: a_y through a first-order lag ``T_a``, the
seat's lateral-acceleration cue); the difference of the two is the sideslip rate, so a small ``w``
tracks the CG path and a large one keeps the yaw in hand on laws whose lateral acceleration
answers the front steer late (``sol1``, ``rwc4_3dof`` steer the rear out of phase). The PI on
``e_w`` supplies what the nominal internal model (L, K_us of the vehicle file's axle cornering
stiffnesses) gets wrong; ``k_b beta`` countersteers a sliding rear (beta < 0 in a left turn when
the tail steps out). ``T_n`` is the driver's neuromuscular lag (a first-order lag of the
order of 0.1 s in McRuer & Jex (1967), "A review of quasi-linear pilot models", IEEE Trans.
HFE 8(3)); it also keeps the steering free of the fast content of the measured signals (the
``lqr`` law's rear steer switches at the control rate). The integrator and the two lags are
advanced by forward Euler with ``dt = t - t_previous``.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Any, Mapping, Protocol

import numpy as np

from fourws_sim.errors import ParameterError
from fourws_sim.params import (GRAVITY_MPS2, MAX_SPEED_MPS, Vehicle, _from_mapping,
                               _spec)

#: Front axle's share of the drive torque for each ``driven_axle`` (``all``: equal torque per
#: wheel; a vehicle's ``driveline`` gives its own split).
_FRONT_SHARE = {"front": 1.0, "rear": 0.0, "all": 0.5}


@dataclass(frozen=True)
class DriverCommand:
    """One driver input (the fields of ``DriverInput.msg``).

    Attributes
    ----------
    steering_wheel_angle_rad : float
        Hand-wheel angle in rad (= ``front_wheel_angle_rad * steering ratio``).
    front_wheel_angle_rad : float
        Front road-wheel angle in rad, positive turns left.
    steering_torque_nm : float
        Driver torque on the steering wheel in N m (free-control model only; 0 here).
    drive_torque_nm : tuple of 4 float
        Drive torque per wheel (FL, FR, RL, RR) in N m, positive drives forward.
    brake_torque_nm : tuple of 4 float
        Brake torque per wheel in N m, >= 0, always opposes wheel spin.
    """

    steering_wheel_angle_rad: float
    front_wheel_angle_rad: float
    steering_torque_nm: float = 0.0
    drive_torque_nm: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    brake_torque_nm: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)

    def to_dict(self) -> dict[str, Any]:
        """Plain mapping with the field names of ``DriverInput.msg``."""
        return {
            "steering_wheel_angle_rad": self.steering_wheel_angle_rad,
            "front_wheel_angle_rad": self.front_wheel_angle_rad,
            "steering_torque_nm": self.steering_torque_nm,
            "drive_torque_nm": list(self.drive_torque_nm),
            "brake_torque_nm": list(self.brake_torque_nm),
        }


@dataclass(frozen=True)
class SpeedHoldSpec:
    """Gains and torque routing of the speed-hold driver (YAML key ``speed_hold``).

    Defaults: ``kp = 4 /s``, ``ki = 2 /s^2``: the speed loop ``s^2 + kp s + ki`` has real
    poles at -0.59 and -3.41 rad/s (no overshoot), fast against the seconds-long maneuvers yet
    slow against the tire/wheel-spin dynamics; on table_8_1 they hold 85 km/h within 0.5 %
    through the 0.63 g step steer (kp = 2 /s, ki = 1 /s^2 gave 0.86 %).
    ``driven_axle = rear`` keeps the steered front tires free of drive force, closest to the
    paper's constant-speed simulations (ch. 8 holds U constant). ``brake_front_fraction`` 0.65
    is a typical passenger-car brake balance.
    """

    enabled: bool = True
    kp_per_s: float = _spec("nonnegative", default=4.0, doc="accel per speed error, 1/s",
                            bounds=(0.0, 100.0))
    ki_per_s2: float = _spec("nonnegative", default=2.0, doc="accel per integrated error, 1/s^2",
                             bounds=(0.0, 1e3))
    driven_axle: str = "rear"
    brake_front_fraction: float = _spec("fraction", default=0.65, doc="front share of braking",
                                        bounds=(0.0, 1.0))
    max_accel_mps2: float = _spec(default=3.0, doc="drive request limit, m/s^2",
                                  bounds=(0.01, 20.0))
    max_decel_mps2: float = _spec(default=8.0, doc="brake request limit, m/s^2",
                                  bounds=(0.01, 20.0))

    def _check(self, source: str | None, prefix: str,
               unchecked: frozenset[str] = frozenset()) -> None:
        if not isinstance(self.enabled, bool):
            raise ParameterError(f"{prefix}enabled", "must be true or false", source)
        if self.driven_axle not in _FRONT_SHARE:
            raise ParameterError(f"{prefix}driven_axle",
                                 f"must be one of {', '.join(_FRONT_SHARE)}, got "
                                 f"{self.driven_axle!r}", source)


def speed_hold_request(error_mps: float, integral_m: float, dt_s: float, kp_per_s: float,
                       ki_per_s2: float, max_decel_mps2: float,
                       max_accel_mps2: float) -> tuple[float, float]:
    """One step of the speed-hold PI with conditional integration (module docstring).

    Parameters
    ----------
    error_mps : float
        Speed error ``U_target - U``, m/s.
    integral_m : float
        The integrated error so far, m.
    dt_s : float
        Time since the previous step, s.
    kp_per_s, ki_per_s2, max_decel_mps2, max_accel_mps2 : float
        :class:`SpeedHoldSpec` gains and limits.

    Returns
    -------
    tuple of float
        The acceleration request (m/s^2, within the limits) and the new integral (m): the
        integral advances only while the request is within the limits.
    """
    integral = integral_m + error_mps * dt_s
    request = kp_per_s * error_mps + ki_per_s2 * integral
    if -max_decel_mps2 <= request <= max_accel_mps2:
        return request, integral
    # saturated: hold the integrator (conditional integration)
    request = kp_per_s * error_mps + ki_per_s2 * integral_m
    return min(max(request, -max_decel_mps2), max_accel_mps2), integral_m


def drive_fractions(driven_axle: str, vehicle: Vehicle) -> tuple[float, float, float, float]:
    """Each wheel's share (FL, FR, RL, RR) of the speed-hold driver's drive torque: the
    vehicle's ``driveline`` (driven axles and front torque fraction) if it has one, else
    ``driven_axle``; an axle's share in equal halves (its differential's open split).
    Without a driveline every share is 0 or 1/n of the n driven wheels, so ``T * share`` is
    the former ``T / n`` bit for bit."""
    dl = vehicle.driveline
    front = dl.front_fraction() if dl is not None else _FRONT_SHARE[driven_axle]
    return (0.5 * front, 0.5 * front, 0.5 * (1.0 - front), 0.5 * (1.0 - front))


def speed_hold_torque(request_mps2: float, speed_mps: float, mass_kg: float, radius_m: float,
                      rolling: float, drag_kg_per_m: float) -> float:
    """Total wheel torque (N m; < 0 brakes) of the speed-hold driver for the acceleration
    request ``request_mps2``: the request plus the resistances the driver knows, the rolling
    resistance ``rolling`` (f_r) and the aerodynamic drag ``drag_kg_per_m`` U|U|
    (0.5 rho C_d A, kg/m) at the measured speed ``speed_mps`` (m/s), times mass (kg) and wheel
    radius (m). Without drag it is ``m R (a + f_r g)`` bit for bit."""
    resist = rolling * GRAVITY_MPS2 + drag_kg_per_m / mass_kg * (speed_mps * abs(speed_mps))
    return mass_kg * radius_m * (request_mps2 + resist)


def split_brake_torque(total_nm: float, front_fraction: float
                       ) -> tuple[float, float, float, float]:
    """Split a total brake torque (N m, >= 0) over FL, FR, RL, RR by the front fraction."""
    front = 0.5 * total_nm * front_fraction
    rear = 0.5 * total_nm * (1.0 - front_fraction)
    return (front, front, rear, rear)


class SpeedHoldDriver:
    """PI speed-hold driver acting through wheel drive and brake torques (see module doc).

    Parameters
    ----------
    spec : SpeedHoldSpec
        Gains and routing.
    vehicle : Vehicle
        Mass (kg), wheel radius (m, ``body``) and rolling resistance (``tire``) are used.
    """

    def __init__(self, spec: SpeedHoldSpec, vehicle: Vehicle) -> None:
        self.spec = spec
        self._mass_kg = vehicle.chassis.mass_kg
        self._radius_m = vehicle.body.wheel_radius_m if vehicle.body is not None else 0.0
        self._rolling = vehicle.tire.rolling_resistance if vehicle.tire is not None else 0.0
        self._drag = (vehicle.aero.drag_coefficient_kg_per_m if vehicle.aero is not None
                      else 0.0)
        self._fractions = drive_fractions(spec.driven_axle, vehicle)
        self._integral_m = 0.0
        self._t_prev: float | None = None

    def reset(self) -> None:
        """Clear the integrator (a new run)."""
        self._integral_m = 0.0
        self._t_prev = None

    def command(self, t_s: float, speed_mps: float, target_mps: float
                ) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """Drive and brake torques (N m, FL FR RL RR) holding ``target_mps``.

        Advances the integrator by ``t_s - t_previous``.
        """
        dt = 0.0 if self._t_prev is None else max(t_s - self._t_prev, 0.0)
        self._t_prev = t_s
        zeros = (0.0, 0.0, 0.0, 0.0)
        if not self.spec.enabled or self._radius_m <= 0.0:
            return zeros, zeros
        spec = self.spec
        request, self._integral_m = speed_hold_request(
            target_mps - speed_mps, self._integral_m, dt, spec.kp_per_s, spec.ki_per_s2,
            spec.max_decel_mps2, spec.max_accel_mps2)
        total_nm = speed_hold_torque(request, speed_mps, self._mass_kg, self._radius_m,
                                     self._rolling, self._drag)
        if total_nm >= 0.0:
            drive = tuple(total_nm * w if w > 0.0 else 0.0 for w in self._fractions)
            return drive, zeros
        return zeros, split_brake_torque(-total_nm, self.spec.brake_front_fraction)


# ---------------------------------------------------------------------------- paths

class Path(Protocol):
    """A reference path in the earth frame (``odom``: x, y in m)."""

    def preview_point(self, x_m: float, y_m: float, heading_rad: float,
                      distance_m: float) -> tuple[float, float]:
        """Earth-frame point of the path about ``distance_m`` ahead of the vehicle."""

    def lateral_error(self, x_m: float, y_m: float) -> float:
        """Signed distance of (x, y) from the path in m, positive to the left of it."""


@dataclass(frozen=True)
class CirclePath:
    """A circle of radius ``radius_m`` driven counter-clockwise (left, ``direction=+1``) or
    clockwise (right, ``-1``), tangent to the x axis at the origin (the start pose)."""

    radius_m: float
    direction: int = 1

    @property
    def centre(self) -> tuple[float, float]:
        """Centre (x, y) in m."""
        return (0.0, self.direction * self.radius_m)

    def _angle(self, x_m: float, y_m: float) -> float:
        cx, cy = self.centre
        return math.atan2(y_m - cy, x_m - cx)

    def preview_point(self, x_m: float, y_m: float, heading_rad: float,
                      distance_m: float) -> tuple[float, float]:
        """Point on the circle at chord distance ``distance_m`` ahead of the projection."""
        cx, cy = self.centre
        r = self.radius_m
        half = min(distance_m / (2.0 * r), 1.0)
        ang = self._angle(x_m, y_m) + self.direction * 2.0 * math.asin(half)
        return (cx + r * math.cos(ang), cy + r * math.sin(ang))

    def lateral_error(self, x_m: float, y_m: float) -> float:
        """Positive when the vehicle is left of the path (inside a left circle)."""
        cx, cy = self.centre
        dist = math.hypot(x_m - cx, y_m - cy)
        return self.direction * (self.radius_m - dist)


class SplinePath:
    """A smooth path ``y = y_ref(x)`` through grid points, x increasing (straight courses).

    A C2 cubic spline with zero slope at both ends (scipy's ``CubicSpline``, ``clamped``); before
    the first and after the last point the path continues straight at the end values. Besides
    the :class:`Path` interface it gives the slope and the curvature the path-tracking driver
    needs.

    Parameters
    ----------
    x_m, y_m : sequence of float
        Grid points (earth frame), m; at least 4, x strictly increasing.
    margin_m : float
        Clearance the planner reports for the path (``nan`` when not planned), m.

    Raises
    ------
    ParameterError
        Fewer than 4 points, unequal lengths, non-finite values or x not increasing.
    """

    def __init__(self, x_m: Any, y_m: Any, margin_m: float = math.nan) -> None:
        from scipy.interpolate import CubicSpline  # scipy: only a path driver needs it

        x = np.asarray(x_m, dtype=float)
        y = np.asarray(y_m, dtype=float)
        if x.ndim != 1 or x.shape != y.shape or x.size < 4:
            raise ParameterError("path", "needs x and y of equal length >= 4")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise ParameterError("path", "points must be finite")
        if np.any(np.diff(x) <= 0.0):
            raise ParameterError("path", "x must increase strictly")
        spline = CubicSpline(x, y, bc_type="clamped")
        self.x_m = x
        self.y_m = y
        self.margin_m = float(margin_m)
        # per interval [c3, c2, c1, c0] of c3 s^3 + c2 s^2 + c1 s + c0, s = x - x_i; Python
        # floats so a call costs microseconds (the driver runs at the control rate)
        self._xs: list[float] = x.tolist()
        self._coeffs: list[list[float]] = spline.c.T.tolist()

    def _piece(self, x_m: float) -> tuple[list[float], float]:
        i = bisect.bisect_right(self._xs, x_m) - 1
        i = min(max(i, 0), len(self._coeffs) - 1)
        return self._coeffs[i], x_m - self._xs[i]

    def y_ref(self, x_m: float) -> float:
        """Reference lateral position (m) at longitudinal position ``x_m``."""
        if x_m <= self._xs[0]:
            return float(self.y_m[0])
        if x_m >= self._xs[-1]:
            return float(self.y_m[-1])
        (c3, c2, c1, c0), s = self._piece(x_m)
        return ((c3 * s + c2) * s + c1) * s + c0

    def slope(self, x_m: float) -> float:
        """``dy_ref/dx`` at ``x_m`` (0 outside the grid)."""
        if x_m <= self._xs[0] or x_m >= self._xs[-1]:
            return 0.0
        (c3, c2, c1, _), s = self._piece(x_m)
        return (3.0 * c3 * s + 2.0 * c2) * s + c1

    def curvature(self, x_m: float) -> float:
        """Signed path curvature ``y'' / (1 + y'^2)^(3/2)`` in 1/m (positive turning left)."""
        if x_m <= self._xs[0] or x_m >= self._xs[-1]:
            return 0.0
        (c3, c2, c1, _), s = self._piece(x_m)
        slope = (3.0 * c3 * s + 2.0 * c2) * s + c1
        return (6.0 * c3 * s + 2.0 * c2) / (1.0 + slope * slope) ** 1.5

    def preview_point(self, x_m: float, y_m: float, heading_rad: float,
                      distance_m: float) -> tuple[float, float]:
        """Path point ``distance_m`` ahead along x."""
        xp = x_m + distance_m * math.cos(heading_rad)
        return (xp, self.y_ref(xp))

    def lateral_error(self, x_m: float, y_m: float) -> float:
        """``y - y_ref(x)`` in m."""
        return y_m - self.y_ref(x_m)


@dataclass(frozen=True)
class PathDriverSpec:
    """Parameters of the preview path follower (YAML key ``path_driver``).

    Defaults: preview time 0.8 s (within MacAdam's 0.5–1.5 s of human drivers; shorter makes
    the closed loop with the car's own yaw lag oscillatory, longer cuts the lane-change gates),
    minimum preview 5 m for low speed, integral gain 0.02 rad of road-wheel angle per (m s) of
    lateral error — a trim that acts over ~10 s, well below the path loop's bandwidth — and a
    road-wheel angle limit of 0.6 rad (a passenger car's lock).
    """

    preview_time_s: float = _spec(default=0.8, doc="T_p, preview time", bounds=(0.01, 10.0))
    min_preview_m: float = _spec(default=5.0, doc="L_min, minimum preview distance",
                                 bounds=(0.01, 100.0))
    integral_gain_rad_per_ms: float = _spec("nonnegative", default=0.02,
                                            doc="k_i, road-wheel rad per (m s) of path error",
                                            bounds=(0.0, 10.0))
    yaw_rate_gain_s: float = _spec("nonnegative", default=0.0,
                                   doc="k_r, road-wheel rad per rad/s of yaw-rate shortfall",
                                   bounds=(0.0, 10.0))
    steer_limit_rad: float = _spec(default=0.6, doc="|delta_f| limit", bounds=(1e-3, 1.0))


class PreviewPathDriver:
    """Single-point preview (pure pursuit) steering driver on a :class:`Path` (module doc).

    Parameters
    ----------
    spec : PathDriverSpec
        Preview and trim parameters.
    vehicle : Vehicle
        Wheelbase L (m) and understeer gradient K_us (rad s^2/m) of the driver's car model.
    path : Path
        Reference path in the earth frame.
    """

    def __init__(self, spec: PathDriverSpec, vehicle: Vehicle, path: Path) -> None:
        self.spec = spec
        self.path = path
        self._wheelbase_m = vehicle.chassis.wheelbase_m
        self._k_us = vehicle.understeer_gradient_rad_per_mps2
        self._integral_ms = 0.0
        self._t_prev: float | None = None

    def reset(self) -> None:
        """Clear the integrator (a new run)."""
        self._integral_ms = 0.0
        self._t_prev = None

    def steer(self, t_s: float, outputs: Mapping[str, Any]) -> float:
        """Front road-wheel angle (rad) from the vehicle pose and speed in ``outputs``."""
        dt = 0.0 if self._t_prev is None else max(t_s - self._t_prev, 0.0)
        self._t_prev = t_s
        x = float(outputs["x_m"])
        y = float(outputs["y_m"])
        psi = float(outputs["heading_rad"])
        speed = float(outputs["speed_mps"])
        preview = max(self.spec.min_preview_m, abs(speed) * self.spec.preview_time_s)
        px, py = self.path.preview_point(x, y, psi, preview)
        dx, dy = px - x, py - y
        lateral = -math.sin(psi) * dx + math.cos(psi) * dy
        dist2 = dx * dx + dy * dy
        curvature = 2.0 * lateral / dist2 if dist2 > 0.0 else 0.0
        error = self.path.lateral_error(x, y)
        self._integral_ms += error * dt
        yaw_rate = float(outputs["yaw_rate_radps"])
        delta = ((self._wheelbase_m + self._k_us * speed * speed) * curvature
                 + self.spec.yaw_rate_gain_s * (speed * curvature - yaw_rate)
                 - self.spec.integral_gain_rad_per_ms * self._integral_ms)
        limit = self.spec.steer_limit_rad
        return min(max(delta, -limit), limit)


@dataclass(frozen=True)
class TrackingDriverSpec:
    """Parameters of the path-tracking driver (YAML key ``tracking_driver``; module doc).

    The defaults are the one set that drives every stable rear-steer law of fourws_control
    through the ISO 3888-2 course at 60 km/h on table_8_1 (``config/maneuvers/
    double_lane_change.yaml`` gives the values, their reasons and the margins they keep).
    """

    preview_time_s: float = _spec("nonnegative", default=0.047,
                                  doc="T_p, curvature preview, s", bounds=(0.0, 5.0))
    path_frequency_radps: float = _spec(default=4.6,
                                        doc="w_n, natural frequency of the path error, rad/s",
                                        bounds=(0.01, 100.0))
    path_damping: float = _spec(default=1.1, doc="zeta, damping ratio of the path error",
                                bounds=(0.01, 10.0))
    turn_rate_gain_s: float = _spec("nonnegative", default=0.37,
                                    doc="k_p, road-wheel rad per rad/s of turning-rate error",
                                    bounds=(0.0, 100.0))
    turn_integral_gain: float = _spec("nonnegative", default=1.2,
                                      doc="k_i, road-wheel rad per rad of its integral",
                                      bounds=(0.0, 100.0))
    yaw_rate_weight: float = _spec("fraction", default=0.79,
                                   doc="w, yaw-rate share of the felt turning rate",
                                   bounds=(0.0, 1.0))
    lateral_accel_lag_s: float = _spec("nonnegative", default=0.078,
                                       doc="T_a, lag of the lateral-acceleration cue, s",
                                       bounds=(0.0, 5.0))
    sideslip_gain: float = _spec("nonnegative", default=0.63,
                                 doc="k_b, road-wheel rad of countersteer per rad of sideslip",
                                 bounds=(0.0, 100.0))
    neuromuscular_lag_s: float = _spec("nonnegative", default=0.047,
                                       doc="T_n, first-order steering lag, s", bounds=(0.0, 5.0))
    steer_limit_rad: float = _spec(default=0.6, doc="|delta_f| limit, rad", bounds=(1e-3, 1.0))
    min_speed_mps: float = _spec(default=2.0, doc="floor of U in the 1/U terms, m/s",
                                 bounds=(0.01, MAX_SPEED_MPS))


class PathTrackingDriver:
    """Course-tracking steering driver on a :class:`SplinePath` (see the module docstring).

    Parameters
    ----------
    spec : TrackingDriverSpec
        Gains and lags.
    vehicle : Vehicle
        Wheelbase L (m) and understeer gradient K_us (rad s^2/m) of the driver's internal
        steady-state model.
    path : SplinePath
        Reference line in the earth frame.
    """

    def __init__(self, spec: TrackingDriverSpec, vehicle: Vehicle, path: SplinePath) -> None:
        self.spec = spec
        self.path = path
        self._wheelbase_m = vehicle.chassis.wheelbase_m
        self._k_us = vehicle.understeer_gradient_rad_per_mps2
        self.reset()

    def reset(self) -> None:
        """Clear the integrator and the lags (a new run)."""
        self._integral_rad = 0.0
        self._accel_mps2 = 0.0
        self._steer_rad = 0.0
        self._t_prev: float | None = None

    def steer(self, t_s: float, outputs: Mapping[str, Any]) -> float:
        """Front road-wheel angle (rad) at time ``t_s`` from the ``VehicleState`` fields
        ``x_m``, ``y_m``, ``heading_rad``, ``speed_mps``, ``yaw_rate_radps``, ``sideslip_rad``
        and ``lateral_accel_mps2``; advances the integrator and the lags by
        ``t_s - t_previous``."""
        p = self.spec
        dt = 0.0 if self._t_prev is None else max(t_s - self._t_prev, 0.0)
        first = self._t_prev is None
        self._t_prev = t_s
        x = float(outputs["x_m"])
        y = float(outputs["y_m"])
        speed = max(float(outputs["speed_mps"]), p.min_speed_mps)
        beta = float(outputs["sideslip_rad"])
        accel = float(outputs["lateral_accel_mps2"])
        if first or p.lateral_accel_lag_s == 0.0:
            self._accel_mps2 = accel
        else:
            self._accel_mps2 += (accel - self._accel_mps2) * dt / (p.lateral_accel_lag_s + dt)
        theta = math.atan(self.path.slope(x))
        e_y = (y - self.path.y_ref(x)) * math.cos(theta)
        chi = float(outputs["heading_rad"]) + beta - theta
        e_chi = math.atan2(math.sin(chi), math.cos(chi))
        w_n = p.path_frequency_radps
        a_c = (speed * speed * self.path.curvature(x + speed * p.preview_time_s)
               - w_n * w_n * e_y - 2.0 * p.path_damping * w_n * speed * math.sin(e_chi))
        felt = (p.yaw_rate_weight * float(outputs["yaw_rate_radps"])
                + (1.0 - p.yaw_rate_weight) * self._accel_mps2 / speed)
        error = a_c / speed - felt
        self._integral_rad += error * dt
        command = ((self._wheelbase_m + self._k_us * speed * speed) * a_c / (speed * speed)
                   + p.turn_rate_gain_s * error + p.turn_integral_gain * self._integral_rad
                   + p.sideslip_gain * beta)
        if p.neuromuscular_lag_s == 0.0:
            self._steer_rad = command
        else:
            self._steer_rad += (command - self._steer_rad) * dt / (p.neuromuscular_lag_s + dt)
        limit = p.steer_limit_rad
        self._steer_rad = min(max(self._steer_rad, -limit), limit)
        return self._steer_rad


def speed_hold_spec_from(data: Any, source: str | None, prefix: str = "speed_hold.",
                         unchecked: frozenset[str] = frozenset()) -> SpeedHoldSpec:
    """Validate a ``speed_hold`` mapping (``None`` gives the defaults); ``unchecked``: dotted
    names whose plausibility bounds are lifted."""
    return _from_mapping(SpeedHoldSpec, {} if data is None else data, source, prefix,
                         unchecked)


def path_driver_spec_from(data: Any, source: str | None, prefix: str = "path_driver.",
                          unchecked: frozenset[str] = frozenset()) -> PathDriverSpec:
    """Validate a ``path_driver`` mapping (``None`` gives the defaults)."""
    return _from_mapping(PathDriverSpec, {} if data is None else data, source, prefix,
                         unchecked)


def tracking_driver_spec_from(data: Any, source: str | None, prefix: str = "tracking_driver.",
                              unchecked: frozenset[str] = frozenset()) -> TrackingDriverSpec:
    """Validate a ``tracking_driver`` mapping (``None`` gives the defaults)."""
    return _from_mapping(TrackingDriverSpec, {} if data is None else data, source, prefix,
                         unchecked)


__all__ = [
    "CirclePath", "DriverCommand", "Path", "PathDriverSpec",
    "PathTrackingDriver", "PreviewPathDriver", "SplinePath", "SpeedHoldDriver", "SpeedHoldSpec",
    "TrackingDriverSpec", "path_driver_spec_from", "speed_hold_request", "speed_hold_spec_from",
    "drive_fractions", "speed_hold_torque", "split_brake_torque",
    "tracking_driver_spec_from",
]
