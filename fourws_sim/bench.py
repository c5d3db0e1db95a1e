# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Speed benchmark of the real-time simulator (``fourws bench``).

Runs the 8-DOF model of one vehicle (default ``table_8_1``) with its STI tire, RK4 at 1 ms,
on one CPU core, through :class:`fourws_sim.simulator.Simulator` the way the simulator node
drives it (``step(u, 10)`` per 100-Hz tick, a step steer at 85 km/h), and through the bare
compiled RK4 loop. Each measurement is repeated and the best and median repetitions are
reported (the machine may be shared; the best is the achievable speed, the median the
typical one).

Numbers reported (:func:`run_benchmark`):

``realtime_factor_8dof``
    simulated seconds per wall second through ``Simulator.step(u, 10)`` (best repetition);
``us_per_step_8dof``
    wall microseconds per 1-ms integration step on that path (best repetition);
``kernel_us_per_step_8dof``, ``kernel_realtime_factor_8dof``
    the same for one compiled call of many steps (no Python per tick);
``first_use_s``
    time to obtain the compiled kernels in this process (numba's disk cache hit or compile);
``cold_compile_s``
    compile time with an empty numba cache, measured in a subprocess (``cold=True``).
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Any

import numpy as np

from fourws_sim.models.eightdof import INPUT
from fourws_sim.simulator import Simulator

#: Speed of the benchmark maneuver, m/s (85 km/h, the paper's chapter-8 speed).
BENCH_SPEED_MPS = 85.0 / 3.6
#: Front road-wheel angle of the step steer, rad (about 0.3 g at 85 km/h on table_8_1).
BENCH_STEER_RAD = 0.01
#: Integration step, s, and steps per simulator tick (100-Hz tick of the simulator node).
BENCH_STEP_S = 1.0e-3
STEPS_PER_TICK = 10


def _pin_one_core() -> int | None:
    """Restrict this process to one CPU (the one it runs on); returns it, or None."""
    if not hasattr(os, "sched_setaffinity"):
        return None
    cpus = sorted(os.sched_getaffinity(0))
    cpu = cpus[0]
    os.sched_setaffinity(0, {cpu})
    return cpu


def _cold_compile_seconds(vehicle: str, tire: str | None) -> float | None:
    """Compile time of the kernels with an empty numba cache (fresh subprocess), s."""
    code = ("import time; t0 = time.perf_counter();"
            "from fourws_sim.simulator import Simulator;"
            f"s = Simulator({vehicle!r}, tire={tire!r}); s.reset(speed_mps=20.0);"
            "s.step(s.input_vector([0.0] * len(s.model.INPUT)), 1); s.outputs();"
            "print(time.perf_counter() - t0)")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        try:
            out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                                 text=True, timeout=600, check=True)
        except (subprocess.SubprocessError, OSError):
            return None
    try:
        return float(out.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return None


def run_benchmark(vehicle: str = "table_8_1", sim_seconds: float = 20.0,
                  repeats: int = 5, tire: str | None = None, cold: bool = True,
                  pin: bool = True) -> dict[str, Any]:
    """Measure the 8-DOF simulator speed.

    Parameters
    ----------
    vehicle : str
        Vehicle name or YAML path.
    sim_seconds : float
        Simulated time per repetition, s.
    repeats : int
        Repetitions of each measurement.
    tire : str, optional
        Tire model (default: the vehicle's, ``sti`` for ``table_8_1``).
    cold : bool
        Also measure the compile time with an empty cache in a subprocess.
    pin : bool
        Run on one CPU core.

    Returns
    -------
    dict
        JSON-ready results (see the module docstring for the keys).
    """
    cpu = _pin_one_core() if pin else None
    t0 = time.perf_counter()
    sim = Simulator(vehicle, model="8dof", integrator="rk4", dt_s=BENCH_STEP_S, tire=tire)
    sim.reset(speed_mps=BENCH_SPEED_MPS)
    u = sim.input_vector(np.zeros(len(sim.model.INPUT)))
    sim.step(u, 1)
    sim.outputs()
    first_use = time.perf_counter() - t0

    u = np.zeros(len(INPUT))
    u[INPUT.DELTA_F] = BENCH_STEER_RAD
    n_ticks = int(round(sim_seconds / (BENCH_STEP_S * STEPS_PER_TICK)))
    n_steps = n_ticks * STEPS_PER_TICK

    tick_times = []
    for _ in range(repeats):
        sim.reset(speed_mps=BENCH_SPEED_MPS)
        start = time.perf_counter()
        for _ in range(n_ticks):
            sim.step(u, STEPS_PER_TICK)
        tick_times.append(time.perf_counter() - start)
    final = sim.outputs()

    kernel = sim._kernel  # the compiled RK4 loop the simulator uses
    kernel_times = []
    for _ in range(repeats):
        sim.reset(speed_mps=BENCH_SPEED_MPS)
        x = sim._x
        start = time.perf_counter()
        kernel(x, u, sim._q, sim._cf, sim._cr, BENCH_STEP_S, n_steps)
        kernel_times.append(time.perf_counter() - start)

    outputs_times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(1000):
            sim.outputs()
        outputs_times.append((time.perf_counter() - start) / 1000)

    sim_time = n_steps * BENCH_STEP_S
    best, med = min(tick_times), statistics.median(tick_times)
    kbest, kmed = min(kernel_times), statistics.median(kernel_times)
    result: dict[str, Any] = {
        "vehicle": vehicle,
        "model": "8dof",
        "tire": sim._p.tire_name,
        "integrator": "rk4",
        "step_s": BENCH_STEP_S,
        "steps_per_call": STEPS_PER_TICK,
        "simulated_s_per_repeat": sim_time,
        "repeats": repeats,
        "realtime_factor_8dof": sim_time / best,
        "us_per_step_8dof": best / n_steps * 1e6,
        "realtime_factor_8dof_median": sim_time / med,
        "us_per_step_8dof_median": med / n_steps * 1e6,
        "kernel_realtime_factor_8dof": sim_time / kbest,
        "kernel_us_per_step_8dof": kbest / n_steps * 1e6,
        "kernel_us_per_step_8dof_median": kmed / n_steps * 1e6,
        "outputs_us": min(outputs_times) * 1e6,
        "first_use_s": first_use,
        "cold_compile_s": _cold_compile_seconds(vehicle, tire) if cold else None,
        "final_lateral_accel_mps2": float(final["lateral_accel_mps2"]),
        "cpu_pinned": cpu,
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    return result


def format_text(result: dict[str, Any]) -> str:
    """Human-readable summary of :func:`run_benchmark`'s result."""
    lines = [
        f"8-DOF {result['tire']} tire, RK4 {result['step_s'] * 1e3:g} ms, "
        f"{result['vehicle']}, one core:",
        f"  Simulator.step(u, {result['steps_per_call']}): "
        f"{result['us_per_step_8dof']:.2f} us/step = "
        f"{result['realtime_factor_8dof']:.0f}x real time "
        f"(median {result['realtime_factor_8dof_median']:.0f}x)",
        f"  compiled loop:            {result['kernel_us_per_step_8dof']:.2f} us/step = "
        f"{result['kernel_realtime_factor_8dof']:.0f}x real time",
        f"  outputs(): {result['outputs_us']:.1f} us",
        f"  first use (cache or compile): {result['first_use_s']:.2f} s",
    ]
    if result.get("cold_compile_s") is not None:
        lines.append(f"  cold compile (empty cache): {result['cold_compile_s']:.2f} s")
    return "\n".join(lines)


def to_json(result: dict[str, Any]) -> str:
    """JSON text of the result."""
    return json.dumps(result, indent=2, sort_keys=True)
