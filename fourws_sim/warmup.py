# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Compile the simulator's numba kernels into their disk cache: ``make setup`` runs
``python -m fourws_sim.warmup`` once, so no run compiles them.

A cold compile of the 8-DOF kernels takes seconds to minutes per tire model (three on a busy
two-core machine for the shipped tires); four node processes compiling at once made the first
``fourws run`` after a setup wait about 40 s for its graph. numba keeps each compiled kernel in
a cache beside its source (``__pycache__``, or ``NUMBA_CACHE_DIR``) and checks it against the
source's time stamp, so this step is repeated only when the kernel sources changed. Every tire
of :data:`fourws_sim.tires.TIRES` with every fixed-step integrator is compiled through the
public :class:`~fourws_sim.simulator.Simulator`, so a tire added to the registry is warmed
without editing this file.
"""

from __future__ import annotations

import sys
import time

from fourws_sim.integrators import INTEGRATORS
from fourws_sim.params import load_vehicle
from fourws_sim.simulator import Inputs, Simulator
from fourws_sim.tires import TIRES

#: The vehicle whose kernels are warmed (every 8-DOF vehicle shares them).
VEHICLE = "table_8_1"
#: Integrators that run the compiled kernels (``solve_ivp`` runs the NumPy reference).
COMPILED_INTEGRATORS = tuple(name for name in INTEGRATORS if name != "solve_ivp")


def warm(echo=print) -> float:  # type: ignore[no-untyped-def]
    """Compile (or load from the cache) every tire's 8-DOF kernels; the seconds it took."""
    vehicle = load_vehicle(VEHICLE)
    start = time.monotonic()
    for tire in TIRES:
        t0 = time.monotonic()
        for integrator in COMPILED_INTEGRATORS:
            sim = Simulator(vehicle, model="8dof", integrator=integrator, dt_s=1e-3, tire=tire)
            sim.reset(speed_mps=20.0)
            sim.step(Inputs(0.01, 0.0, 0.0, (0.0,) * 4, (0.0,) * 4), n_steps=2)
            sim.outputs()
        echo(f"  8-DOF kernels, {tire} tire: {time.monotonic() - t0:.1f} s")
    return time.monotonic() - start


if __name__ == "__main__":
    seconds = warm()
    print(f"  kernels ready ({seconds:.1f} s)")
    sys.exit(0)
