"""The 2-DOF (bicycle) parameters of a vehicle, as the closed-form laws and the handling
analysis use them."""

from __future__ import annotations

from typing import NamedTuple

from fourws_sim.params import Vehicle


class Bicycle(NamedTuple):
    """2-DOF (bicycle) parameters in SI: m kg, Iz kg m^2, a, b, L m, Cf, Cr N/rad per axle."""

    m: float
    iz: float
    a: float
    b: float
    L: float
    cf: float
    cr: float


def bicycle(vehicle: Vehicle) -> Bicycle:
    """The bicycle-model parameters of ``vehicle``."""
    c, t = vehicle.chassis, vehicle.axle_tires
    return Bicycle(c.mass_kg, c.yaw_inertia_kgm2, c.cg_to_front_axle_m, c.cg_to_rear_axle_m,
                   c.wheelbase_m, t.cornering_stiffness_front_n_per_rad,
                   t.cornering_stiffness_rear_n_per_rad)
