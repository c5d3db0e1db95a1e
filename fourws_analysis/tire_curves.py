# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Tire characteristic curves in the axes of the paper's Figures C.1 and C.2.

Figure C.1: normalized lateral force ``Fy/Fz`` against slip angle (0-20 deg) for longitudinal
(braking) slip 0, 0.1, 0.2. Figure C.2: ``Fy/Fz`` against longitudinal slip (0-1) for slip
angles 0, 10, 20 deg. The figures plot the magnitude of the side force (positive) against
positive slip angle and braking slip, so the curves here are ``-Fy/Fz`` at ``alpha > 0``
(fourws's ``Fy = -C alpha``) and braking slip ``s = -kappa``.

Load: the paper does not state it. The OCR of the figure axes reaches 0.8, and the figures
come with the tire data (Table C.1), whose only reference load is the design load
``FZT = 1000 lb`` (4448 N); the curves are drawn there for the ``sti`` tire. For the other
tire models the default load is the static load of one tire on the chosen axle.

:func:`tire_curves` returns data; :func:`plot_tire_curves` draws it (matplotlib, Agg).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fourws_sim.errors import ParameterError
from fourws_sim.params import GRAVITY_MPS2, Vehicle
from fourws_sim.tires import get_tire, sti

#: Slip ratios (braking) of Figure C.1.
FIG_C1_SLIP_RATIOS = (0.0, 0.1, 0.2)
#: Slip angles of Figure C.2, deg.
FIG_C2_SLIP_ANGLES_DEG = (0.0, 10.0, 20.0)
#: x-axis range of Figure C.1, deg (OCR ticks 0.0-2.0 read as tens of degrees: the curves need
#: 10-20 deg to reach the 0.8 of the y axis, and Figure C.2 uses 10 and 20 deg).
FIG_C1_MAX_SLIP_ANGLE_DEG = 20.0
#: Forward speed at which the curves are evaluated, m/s (85 km/h, the paper's test speed).
CURVE_SPEED_MPS = 85.0 / 3.6
_N_POINTS = 201


@dataclass(frozen=True)
class Curve:
    """One curve: ``x`` (deg or slip ratio) against ``Fy/Fz`` (positive = side force magnitude)."""

    label: str
    x: np.ndarray
    fy_over_fz: np.ndarray
    fx_over_fz: np.ndarray

    @property
    def peak(self) -> float:
        """Largest ``Fy/Fz`` on the curve."""
        return float(np.max(self.fy_over_fz))

    @property
    def x_at_peak(self) -> float:
        """``x`` where ``Fy/Fz`` is largest."""
        return float(self.x[int(np.argmax(self.fy_over_fz))])


@dataclass(frozen=True)
class TireCurves:
    """Curves of Figures C.1 (``vs_slip_angle``) and C.2 (``vs_slip_ratio``)."""

    tire_model: str
    fz_n: float
    mu: float
    vs_slip_angle: list[Curve] = field(default_factory=list)
    vs_slip_ratio: list[Curve] = field(default_factory=list)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready mapping (lists of floats, peaks included)."""
        def conv(c: Curve) -> dict[str, object]:
            return {"label": c.label, "x": c.x.tolist(), "fy_over_fz": c.fy_over_fz.tolist(),
                    "fx_over_fz": c.fx_over_fz.tolist(), "peak_fy_over_fz": c.peak,
                    "x_at_peak": c.x_at_peak}
        return {"tire_model": self.tire_model, "fz_n": self.fz_n, "mu": self.mu,
                "fig_c1_vs_slip_angle_deg": [conv(c) for c in self.vs_slip_angle],
                "fig_c2_vs_slip_ratio": [conv(c) for c in self.vs_slip_ratio]}


def default_load_n(vehicle: Vehicle, axle: str, tire_model: str, coeffs: np.ndarray) -> float:
    """Load of the curves: FZT for ``sti``, else the static load of one tire on ``axle``, N."""
    if tire_model == "sti":
        return float(coeffs[sti.COEF.FZT_LB]) * sti.N_PER_LBF
    c = vehicle.chassis
    lever = c.cg_to_rear_axle_m if axle == "front" else c.cg_to_front_axle_m
    return 0.5 * c.mass_kg * GRAVITY_MPS2 * lever / c.wheelbase_m


def tire_curves(vehicle: Vehicle, axle: str = "front", fz_n: float | None = None,
                tire_model: str | None = None, mu: float | None = None) -> TireCurves:
    """Normalized lateral force curves of Figures C.1 and C.2 for the vehicle's tire.

    Parameters
    ----------
    vehicle : Vehicle
        Supplies the tire model and its coefficients (``tire`` subsystem; ``linear`` without).
    axle : str
        ``"front"`` or ``"rear"`` (coefficients and default load).
    fz_n : float, optional
        Normal load in N (default: :func:`default_load_n`).
    tire_model : str, optional
        Override the vehicle's tire model name.
    mu : float, optional
        Friction argument (default: ``tire.friction_coefficient``, else 1).

    Raises
    ------
    ParameterError
        If ``fz_n`` is not positive and finite or ``axle`` is invalid.
    """
    tire = vehicle.tire
    name = tire_model or (tire.model if tire is not None else "linear")
    module = get_tire(name)
    coeffs = module.pack(vehicle, axle)
    if mu is None:
        mu = tire.friction_coefficient if tire is not None else 1.0
    if fz_n is None:
        fz_n = default_load_n(vehicle, axle, name, coeffs)
    if not (math.isfinite(fz_n) and fz_n > 0.0):
        raise ParameterError("fz_n", f"must be a positive finite load in N, got {fz_n!r}",
                             vehicle.source or None)

    def evaluate(alpha_deg: np.ndarray, slip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        fy = np.empty(alpha_deg.size)
        fx = np.empty(alpha_deg.size)
        for i, (a, s) in enumerate(zip(alpha_deg, slip)):
            f_x, f_y, _ = module.forces(fz_n, math.radians(a), -s, CURVE_SPEED_MPS, mu, coeffs)
            fy[i] = -f_y / fz_n + 0.0  # + 0.0 turns -0.0 into 0.0 for printing
            fx[i] = f_x / fz_n + 0.0
        return fx, fy

    out = TireCurves(tire_model=name, fz_n=float(fz_n), mu=float(mu))
    alphas = np.linspace(0.0, FIG_C1_MAX_SLIP_ANGLE_DEG, _N_POINTS)
    for s in FIG_C1_SLIP_RATIOS:
        fx, fy = evaluate(alphas, np.full(alphas.size, s))
        out.vs_slip_angle.append(Curve(f"s = {s:.1f}", alphas, fy, fx))
    slips = np.linspace(0.0, 1.0, _N_POINTS)
    for a in FIG_C2_SLIP_ANGLES_DEG:
        fx, fy = evaluate(np.full(slips.size, a), slips)
        out.vs_slip_ratio.append(Curve(f"alpha = {a:.1f} deg", slips, fy, fx))
    return out


def plot_tire_curves(curves: TireCurves, path: str | Path) -> Path:
    """Draw Figures C.1 and C.2 side by side into a PNG (matplotlib Agg backend)."""
    import matplotlib  # matplotlib: about 0.5 s to load, only the plots need it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: about 0.5 s to load, only the plots need it

    path = Path(path)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11.0, 4.2), constrained_layout=True)
    for c in curves.vs_slip_angle:
        ax1.plot(c.x, c.fy_over_fz, label=c.label)
    ax1.set_xlabel("Slip angle (deg)")
    ax1.set_ylabel("Normalized lateral force Fy/Fz (-)")
    ax1.set_title("Fig. C.1: Fy/Fz vs slip angle")
    for c in curves.vs_slip_ratio:
        ax2.plot(c.x, c.fy_over_fz, label=c.label)
    ax2.set_xlabel("Longitudinal slip (-)")
    ax2.set_ylabel("Normalized lateral force Fy/Fz (-)")
    ax2.set_title("Fig. C.2: Fy/Fz vs longitudinal slip")
    for ax in (ax1, ax2):
        ax.set_ylim(0.0, 1.0)
        ax.grid(True, alpha=0.3)
        ax.legend()
    fig.suptitle(f"{curves.tire_model} tire, Fz = {curves.fz_n:.0f} N, mu = {curves.mu:g}")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
