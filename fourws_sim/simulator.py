# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The real-time simulator: one vehicle model, one integrator, a fixed step.

::

    sim = Simulator(load_vehicle("table_8_1"))          # 8-DOF, RK4, 1 ms, the vehicle's tire
    sim.reset(speed_mps=85 / 3.6)
    sim.step(Inputs(front_wheel_angle_rad=0.01), n_steps=10)
    y = sim.outputs()                                   # the fields of msg/VehicleState.msg

The 8-DOF model runs through its numba-compiled kernels (one RK4 or Euler loop per call of
:meth:`Simulator.step`, so ``step(u, 10)`` costs one Python call); the ``solve_ivp`` integrator
uses the NumPy reference model instead. The linear models (``2dof``, ``3dof``, ...) run at the
fixed forward speed given to :meth:`Simulator.reset`; the simulator integrates their earth-frame
pose alongside and fills the outputs they have (per-wheel fields stay zero).

Inputs are held constant over a call of :meth:`step` (zero-order hold). A non-finite input
or state raises :class:`~fourws_sim.errors.NonFiniteError` naming the component; the simulator
then keeps its last finite state, so nothing non-finite ever leaves it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any, Sequence

import numpy as np

from fourws_sim.errors import DivergedError, NonFiniteError, ParameterError
from fourws_sim.integrators import DEFAULT_STEP_S, get_integrator
from fourws_sim.models import eightdof, get_model
from fourws_sim.models.eightdof import (_AUX_ALPHA, _AUX_AX, _AUX_AY, _AUX_DELTA_F, _AUX_DELTA_R,
                                        _AUX_FX, _AUX_FY, _AUX_FZ, _AUX_KAPPA, _AUX_MZ, STATE,
                                        evaluate)
from fourws_sim.params import N_WHEELS, Vehicle, load_vehicle

#: Forward speed of the linear models when :meth:`Simulator.reset` gets none, m/s: the
#: paper's reference speed (85 km/h, chapters 4 and 8).
DEFAULT_LINEAR_SPEED_MPS = 85.0 / 3.6
#: Name of the nonlinear model that runs through compiled kernels.
EIGHT_DOF = "8dof"
#: The same model with its free steering system (the front angle a state, driven by the
#: driver's steering torque).
EIGHT_DOF_FREE = "8dof-free"
#: dtype of the input vectors the compiled kernels take without conversion.
_FLOAT64 = np.dtype(np.float64)


@dataclass(frozen=True)
class Inputs:
    """Simulator inputs (SI units; wheel order FL, FR, RL, RR).

    Attributes
    ----------
    front_wheel_angle_rad : float
        Commanded front road-wheel angle, rad (positive left); the steering-wheel angle over
        the steering ratio (:func:`fourws_sim.models.eightdof.road_wheel_angle`).
    rear_wheel_angle_rad : float
        Commanded rear road-wheel angle, rad.
    steering_torque_nm : float
        Driver torque on the steering wheel for the free-control models, N m (``8dof-free``
        takes it through the steering ratio in its steering system; for ``2dof-free``, whose
        input is the torque about the kingpin, it is multiplied by the ratio here).
    drive_torque_nm : sequence of 4 float
        Drive torque per wheel, N m (positive forward).
    brake_torque_nm : sequence of 4 float
        Brake torque per wheel, N m (>= 0; opposes the wheel's spin).
    """

    front_wheel_angle_rad: float = 0.0
    rear_wheel_angle_rad: float = 0.0
    steering_torque_nm: float = 0.0
    drive_torque_nm: Sequence[float] = (0.0, 0.0, 0.0, 0.0)
    brake_torque_nm: Sequence[float] = (0.0, 0.0, 0.0, 0.0)


def _semi_implicit_step(x: np.ndarray, k: np.ndarray, h: float) -> np.ndarray:
    """One semi-implicit Euler step of the 8-DOF state (``eightdof_kernels``' arithmetic)."""
    S = eightdof.STATE
    xt = x + h * k
    xt[S.PHI] = x[S.PHI] + h * xt[S.P]
    xt[S.PSI] = x[S.PSI] + h * xt[S.R]
    sps, cps = math.sin(x[S.PSI]), math.cos(x[S.PSI])
    xt[S.X] = x[S.X] + h * (xt[S.U] * cps - xt[S.V] * sps)
    xt[S.Y] = x[S.Y] + h * (xt[S.U] * sps + xt[S.V] * cps)
    xt[S.DELTA_S] = x[S.DELTA_S] + h * xt[S.DELTA_S_RATE]
    return xt


def _field_names() -> list[str]:
    """Input field name of each 8-DOF input slot (for error messages)."""
    names = []
    for member in eightdof.INPUT:
        n = member.name
        if n == "DELTA_F":
            names.append("front_wheel_angle_rad")
        elif n == "DELTA_R":
            names.append("rear_wheel_angle_rad")
        elif n == "STEER_TORQUE":
            names.append("steering_torque_nm")
        else:
            kind = "drive_torque_nm" if n.startswith("DRIVE") else "brake_torque_nm"
            names.append(f"{kind}[{n[-2:]}]")
    return names


class Simulator:
    """Fixed-step simulator of one vehicle model.

    Parameters
    ----------
    vehicle : Vehicle or str or Path
        The vehicle, or its name (file stem under ``config/vehicles``) or YAML path.
    model : str
        Model name (``fourws_sim.models.MODELS``): ``8dof`` (default), ``2dof``, ``3dof``, ...
    integrator : str
        ``rk4`` (default), ``euler``, ``semi_implicit_euler`` (8-DOF models) or ``solve_ivp``.
    dt_s : float
        Integration step in s (default 1 ms).
    tire : str, optional
        Tire model of the 8-DOF, overriding ``vehicle.tire.model``.
    speed_mps : float, optional
        Initial forward speed for the first :meth:`reset` (8-DOF: 0; linear models: 85 km/h).

    Raises
    ------
    UnknownNameError
        Unknown model, integrator or tire name.
    ParameterError
        Bad step, the vehicle lacks what the model needs, or (8-DOF) its wheels are too
        light for the step (:func:`fourws_sim.models.eightdof.check_step`).
    """

    def __init__(self, vehicle: Vehicle | str | Path, model: str = EIGHT_DOF,
                 integrator: str = "rk4", dt_s: float = DEFAULT_STEP_S,
                 tire: str | None = None, speed_mps: float | None = None) -> None:
        self.vehicle = vehicle if isinstance(vehicle, Vehicle) else load_vehicle(vehicle)
        self.model_name = model
        self.model: ModuleType = get_model(model)
        self.integrator = get_integrator(integrator)
        if not (isinstance(dt_s, (int, float)) and math.isfinite(dt_s) and dt_s > 0.0):
            raise ParameterError("dt_s", f"must be a finite number > 0, got {dt_s!r}")
        self.dt_s = float(dt_s)
        self._is_8dof = model in (EIGHT_DOF, EIGHT_DOF_FREE)
        self.integrator.check_model(model)
        self._n_input = len(self.model.INPUT)
        self._u = np.zeros(self._n_input)
        self._u_shape = (self._n_input,)
        self._u_held = np.zeros(self._n_input)  # the fast path's held input (see step)
        self._kernel = None
        if self._is_8dof:
            self._p = eightdof.params_for(self.vehicle, tire,
                                          free_steering=model == EIGHT_DOF_FREE)
            # a wheel too light for the step is refused here, not found diverging later
            eightdof.check_step(self._p, self.dt_s, integrator,
                                self.vehicle.source or self.vehicle.name)
            self._q = self._p.arr
            self._cf = self._p.coeffs_front
            self._cr = self._p.coeffs_rear
            kern = eightdof.kernels_for(self._p.tire_name)
            self._kernels = kern
            if self.integrator.compiled_name is not None:
                self._kernel = getattr(kern, self.integrator.compiled_name)
            self._dx = np.zeros(eightdof.N_STATE)
            self._aux = np.zeros(eightdof.N_AUX)
            self._input_names = _field_names()
            self._brakes: slice | None = slice(int(eightdof.INPUT.BRAKE_FL),
                                               int(eightdof.INPUT.BRAKE_RR) + 1)
        else:
            self._brakes = None
            if tire is not None:
                raise ParameterError("tire", f"only the {EIGHT_DOF} models have a tire choice")
            self._input_names = [m.name for m in self.model.INPUT]
        self._speed = 0.0
        self._kingpin_per_wheel = (self.vehicle.steering.ratio
                                   if self.vehicle.steering is not None else 1.0)
        self.reset(speed_mps=speed_mps)

    # ------------------------------------------------------------------ state
    def reset(self, speed_mps: float | None = None) -> None:
        """Straight running at ``speed_mps`` (m/s) at the origin, time and step count 0.

        8-DOF: wheel spins ``U / R`` (free rolling, zero slip). Linear models: ``speed_mps``
        is the fixed forward speed of the model (default 85 km/h).

        Raises
        ------
        ParameterError
            If the speed is not finite (8-DOF) or not > 0 (linear models).
        """
        if self._is_8dof:
            speed = 0.0 if speed_mps is None else speed_mps
            if isinstance(speed, bool) or not isinstance(speed, (int, float, np.floating)) \
                    or not math.isfinite(speed):
                raise ParameterError("speed_mps", f"must be a finite number, got {speed!r}")
            self._x = eightdof.initial_state(self._p, float(speed))
            self._mp = self._p
        else:
            speed = DEFAULT_LINEAR_SPEED_MPS if speed_mps is None else speed_mps
            self._mp = self.model.params_for(self.vehicle, speed)
            n = len(self.model.STATE)
            self._x = np.zeros(n + 3)  # model state + X, Y, heading
        self._speed = float(speed)
        self._u = np.zeros(self._n_input)
        self._t = 0.0
        self._step = 0

    @property
    def state(self) -> np.ndarray:
        """Copy of the model state in the model's ``STATE`` order (SI)."""
        if self._is_8dof:
            return self._x.copy()
        return self._x[:len(self.model.STATE)].copy()

    @state.setter
    def state(self, x: np.ndarray) -> None:
        arr = np.array(x, dtype=float).reshape(-1)
        n = len(self.model.STATE)
        if arr.shape[0] != n:
            raise ParameterError("state", f"must have {n} components, got {arr.shape[0]}")
        self._check_finite_state(arr, integrated=False)
        self._x[:n] = arr

    @property
    def time_s(self) -> float:
        """Simulation time since :meth:`reset`, s."""
        return self._t

    @property
    def step_count(self) -> int:
        """Integration steps since :meth:`reset`."""
        return self._step

    @property
    def speed_mps(self) -> float:
        """Forward speed given to the last :meth:`reset`, m/s."""
        return self._speed

    # ------------------------------------------------------------------ inputs
    def input_vector(self, u: Inputs | np.ndarray | Sequence[float]) -> np.ndarray:
        """The model's input vector (its ``INPUT`` order) from :class:`Inputs` or an array.

        Raises
        ------
        NonFiniteError
            If an input is NaN or infinite (the message names it).
        ParameterError
            If an array has the wrong length or a brake torque is negative.
        """
        if isinstance(u, Inputs):
            arr = self._from_inputs(u)
        else:
            arr = np.array(u, dtype=np.float64).reshape(-1)  # a copy: the caller may reuse u
            if arr.shape[0] != self._n_input:
                raise ParameterError("u", f"must have {self._n_input} components in "
                                     f"{self.model_name} INPUT order, got {arr.shape[0]}")
        # cheap checks on a Python list (this runs at every simulator tick); the precise
        # search for the bad component only runs when one fails
        values = arr.tolist()
        if not math.isfinite(sum(values)):
            finite = np.isfinite(arr)
            if not finite.all():
                bad = int(np.flatnonzero(~finite)[0])
                raise NonFiniteError(f"input {self._input_names[bad]} is not finite "
                                     f"({arr[bad]!r})")
        if self._brakes is not None and min(values[self._brakes]) < 0.0:
            bad = self._brakes.start + int(np.flatnonzero(arr[self._brakes] < 0.0)[0])
            raise ParameterError(self._input_names[bad],
                                 f"must be >= 0 (a brake only opposes spin), got "
                                 f"{arr[bad]!r}")
        return arr

    def _from_inputs(self, u: Inputs) -> np.ndarray:
        arr = np.zeros(self._n_input)
        drive = np.asarray(u.drive_torque_nm, dtype=float).reshape(-1)
        brake = np.asarray(u.brake_torque_nm, dtype=float).reshape(-1)
        for name, vec in (("drive_torque_nm", drive), ("brake_torque_nm", brake)):
            if vec.shape[0] != N_WHEELS:
                raise ParameterError(name, f"must have {N_WHEELS} values (FL, FR, RL, RR), "
                                     f"got {vec.shape[0]}")
        for member in self.model.INPUT:
            name = member.name
            if name == "DELTA_F":
                arr[member] = u.front_wheel_angle_rad
            elif name == "DELTA_R":
                arr[member] = u.rear_wheel_angle_rad
            elif name == "STEER_TORQUE":
                arr[member] = u.steering_torque_nm
            elif name == "T_F":  # the 2-DOF free model's kingpin torque: through the ratio
                arr[member] = u.steering_torque_nm * self._kingpin_per_wheel
            elif name.startswith("DRIVE_"):
                arr[member] = drive[("FL", "FR", "RL", "RR").index(name[-2:])]
            elif name.startswith("BRAKE_"):
                arr[member] = brake[("FL", "FR", "RL", "RR").index(name[-2:])]
        return arr

    # ------------------------------------------------------------------ stepping
    def step(self, u: Inputs | np.ndarray | Sequence[float], n_steps: int = 1) -> None:
        """Advance ``n_steps`` integration steps with the input ``u`` held.

        Parameters
        ----------
        u : Inputs or array_like
            :class:`Inputs`, or a vector in the model's ``INPUT`` order (the fast path).
        n_steps : int
            Number of steps of ``dt_s``.

        Raises
        ------
        NonFiniteError
            Non-finite input, or the state became non-finite (the simulator keeps the last
            finite state and time).
        ParameterError
            Bad input vector length, negative brake torque, negative ``n_steps``.
        """
        if (self._kernel is not None and type(u) is np.ndarray and type(n_steps) is int
                and u.shape == self._u_shape and u.dtype == _FLOAT64 and n_steps >= 0):
            # fast path (the simulator node's call at every tick): a float64 vector in INPUT
            # order; the compiled loop checks it as input_vector does and copies it into the
            # held-input buffer (the caller may reuse u; outputs() reads the held input).
            # A rejected input (-1, nothing done) takes the general path below for its error.
            done = int(self._kernel(self._x, u, self._q, self._cf, self._cr, self.dt_s,
                                    n_steps, self._u_held))
            if done >= 0:
                self._u = self._u_held
                self._step += done
                self._t = self._step * self.dt_s
                if done < n_steps:
                    self._raise_diverged()
                return
        arr = self.input_vector(u)
        if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)) \
                or n_steps < 0:
            raise ParameterError("n_steps", f"must be an integer >= 0, got {n_steps!r}")
        self._u = arr
        if self._kernel is not None:
            done = int(self._kernel(self._x, arr, self._q, self._cf, self._cr, self.dt_s,
                                    int(n_steps)))
            self._step += done
            self._t = self._step * self.dt_s
            if done < n_steps:
                self._raise_diverged()
            return
        f = self._derivatives
        try:
            with np.errstate(all="ignore"):
                x_new = self.integrator.advance(f, self._t, self._x, arr, self._mp,
                                                self.dt_s, int(n_steps))
        except NonFiniteError as exc:
            raise DivergedError(f"{self.model_name}: {exc}", self._t) from None
        self._check_finite_state(x_new)
        self._x = x_new
        self._step += int(n_steps)
        self._t = self._step * self.dt_s

    def _derivatives(self, t: float, z: np.ndarray, u: np.ndarray, p: Any) -> np.ndarray:
        """Model derivative; for linear models with the pose appended."""
        if self._is_8dof:
            return self.model.derivatives(t, z, u, p)
        n = len(self.model.STATE)
        dz = np.empty_like(z)
        dz[:n] = self.model.derivatives(t, z[:n], u, p)
        vy = z[self._index("V")] if self._has("V") else 0.0
        psi = z[n + 2]
        U = self._speed
        dz[n] = U * math.cos(psi) - vy * math.sin(psi)
        dz[n + 1] = U * math.sin(psi) + vy * math.cos(psi)
        dz[n + 2] = z[self._index("R")] if self._has("R") else 0.0
        return dz

    def _raise_diverged(self) -> None:
        """Name the component that goes non-finite in the next step from the kept state.

        Replays that step with the compiled right-hand side (RK4 stages, or Euler, in the
        step's sub-steps), which turns overflow into NaN where the NumPy reference's ``math``
        calls would raise.
        """
        rhs = self._kernels.rhs
        dx = np.zeros(eightdof.N_STATE)
        aux = np.zeros(eightdof.N_AUX)
        args = (self._u, self._q, self._cf, self._cr)

        def f(z: np.ndarray) -> np.ndarray:
            rhs(z, *args, dx, aux)
            return dx.copy()

        x = self._x.copy()
        k1 = f(x)
        n_sub = eightdof.substeps(float(aux[eightdof._AUX_RATE]), self.dt_s,
                                  self.integrator.name)
        h = self.dt_s / n_sub
        with np.errstate(all="ignore"):
            for sub in range(n_sub):
                k1 = k1 if sub == 0 else f(x)
                if self.integrator.name == "euler":
                    x = x + h * k1
                elif self.integrator.name == "semi_implicit_euler":
                    x = _semi_implicit_step(x, k1, h)
                else:
                    k2 = f(x + 0.5 * h * k1)
                    k3 = f(x + 0.5 * h * k2)
                    x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + f(x + h * k3))
                if not np.isfinite(x).all():
                    break
        bad = np.flatnonzero(~np.isfinite(x))
        name = eightdof.STATE(int(bad[0])).name if bad.size else "unknown"
        raise DivergedError(f"{self.model_name}: state {name} became non-finite at "
                            f"t = {self._t:.6g} s (simulator kept the last finite state)",
                            self._t)

    def _check_finite_state(self, x: np.ndarray, integrated: bool = True) -> None:
        """Raise on a non-finite state: :class:`DivergedError` for one the integration
        produced, :class:`NonFiniteError` for one given by the caller."""
        if not np.isfinite(x).all():
            bad = int(np.flatnonzero(~np.isfinite(x))[0])
            n = len(self.model.STATE)
            name = self.model.STATE(bad).name if bad < n else ("X", "Y", "HEADING")[bad - n]
            if not integrated:
                raise NonFiniteError(f"state {name} is not finite ({x[bad]!r})")
            raise DivergedError(f"{self.model_name}: state {name} became non-finite near "
                                f"t = {self._t:.6g} s (simulator kept the last finite state)",
                                self._t)

    def _has(self, name: str) -> bool:
        return name in self.model.STATE.__members__

    def _index(self, name: str) -> int:
        return int(self.model.STATE[name])

    # ------------------------------------------------------------------ outputs
    def outputs(self) -> dict[str, Any]:
        """The fields of ``msg/VehicleState.msg`` (without ``header``) for the current state.

        Accelerations and applied road-wheel angles are evaluated with the input of the last
        :meth:`step` (zero before the first). Per-wheel fields are length-4 arrays (FL, FR,
        RL, RR); zeros for the single-track models.
        """
        if self._is_8dof:
            return self._outputs_8dof()
        return self._outputs_linear()

    def _outputs_8dof(self) -> dict[str, Any]:
        x = self._x
        if self._kernel is not None:
            self._kernels.rhs(x, self._u, self._q, self._cf, self._cr, self._dx, self._aux)
            aux = self._aux
            fz = aux[_AUX_FZ:_AUX_FZ + 4].copy()
            alpha = aux[_AUX_ALPHA:_AUX_ALPHA + 4].copy()
            kappa = aux[_AUX_KAPPA:_AUX_KAPPA + 4].copy()
            fx = aux[_AUX_FX:_AUX_FX + 4].copy()
            fy = aux[_AUX_FY:_AUX_FY + 4].copy()
            mz = aux[_AUX_MZ:_AUX_MZ + 4].copy()
            d_f, d_r, ax, ay = (float(aux[_AUX_DELTA_F]), float(aux[_AUX_DELTA_R]),
                                float(aux[_AUX_AX]), float(aux[_AUX_AY]))
        else:
            _, a = evaluate(self._t, x, self._u, self._p)
            fz, alpha, kappa, fx, fy, mz = a.fz_n, a.alpha_rad, a.kappa, a.fx_n, a.fy_n, a.mz_nm
            d_f, d_r, ax, ay = a.delta_f_rad, a.delta_r_rad, a.ax_mps2, a.ay_mps2
        U = float(x[STATE.U])
        V = float(x[STATE.V])
        return {
            "step": self._step,
            "sim_time_s": self._t,
            "model": self.model_name,
            "x_m": float(x[STATE.X]),
            "y_m": float(x[STATE.Y]),
            "heading_rad": float(x[STATE.PSI]),
            "speed_mps": U,
            "lateral_velocity_mps": V,
            "yaw_rate_radps": float(x[STATE.R]),
            "roll_rad": float(x[STATE.PHI]),
            "roll_rate_radps": float(x[STATE.P]),
            "sideslip_rad": math.atan2(V, U) if (U != 0.0 or V != 0.0) else 0.0,
            "longitudinal_accel_mps2": ax,
            "lateral_accel_mps2": ay,
            "front_wheel_angle_rad": d_f,
            "rear_wheel_angle_rad": d_r,
            "wheel_speed_radps": x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1].copy(),
            "normal_load_n": fz,
            "slip_angle_rad": alpha,
            "slip_ratio": kappa,
            "fx_n": fx,
            "fy_n": fy,
            "mz_nm": mz,
        }

    def _outputs_linear(self) -> dict[str, Any]:
        n = len(self.model.STATE)
        z = self._x
        dz = self._derivatives(self._t, z, self._u, self._mp)
        U = self._speed

        def get(name: str, arr: np.ndarray = z) -> float:
            return float(arr[self._index(name)]) if self._has(name) else 0.0

        V, r = get("V"), get("R")
        roll = get("PHI")
        roll_rate = get("PHI_DOT") if self._has("PHI_DOT") else get("P")
        if self._has("DELTA_F"):  # free steering control: the front angle is a state
            d_f = get("DELTA_F")
        else:
            d_f = float(self._u[self.model.INPUT["DELTA_F"]]) \
                if "DELTA_F" in self.model.INPUT.__members__ else 0.0
        d_r = float(self._u[self.model.INPUT["DELTA_R"]]) \
            if "DELTA_R" in self.model.INPUT.__members__ else 0.0
        zeros = np.zeros(N_WHEELS)
        return {
            "step": self._step,
            "sim_time_s": self._t,
            "model": self.model_name,
            "x_m": float(z[n]),
            "y_m": float(z[n + 1]),
            "heading_rad": float(z[n + 2]),
            "speed_mps": U,
            "lateral_velocity_mps": V,
            "yaw_rate_radps": r,
            "roll_rad": roll,
            "roll_rate_radps": roll_rate,
            "sideslip_rad": math.atan2(V, U),
            "longitudinal_accel_mps2": -V * r,
            "lateral_accel_mps2": get("V", dz) + U * r,
            "front_wheel_angle_rad": d_f,
            "rear_wheel_angle_rad": d_r,
            "wheel_speed_radps": zeros.copy(),
            "normal_load_n": zeros.copy(),
            "slip_angle_rad": zeros.copy(),
            "slip_ratio": zeros.copy(),
            "fx_n": zeros.copy(),
            "fy_n": zeros.copy(),
            "mz_nm": zeros.copy(),
        }
