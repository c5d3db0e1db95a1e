# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Speed of studies (``fourws bench --study``): closed-loop vehicle-steps per second.

A vehicle-step is one 1-ms RK4 step of the 8-DOF model (STI tire) inside a closed loop whose
law and driver answer every 10 ms. Reported (:func:`run_study_benchmark`):

``loop_kernel_steps_per_s``
    one core, the compiled closed loop alone (:mod:`fourws_study.loop_kernels`: law, driver,
    actuator and RK4 in one call), best of the repetitions;
``loop_kernel_us_per_step``
    its inverse, microseconds; compare ``fourws bench``'s ``kernel_us_per_step_8dof`` (the
    bare RK4 loop of one run);
``batch_kernel_steps_per_s``, ``batch_kernel_us_per_step``
    one core, the batch kernel alone over one group of ``LANES`` points (16: the first
    points of the study), the way a study runs them (vector instructions for the STI tire);
``compiled_run_steps_per_s``
    one core, the compiled run with its Python preparation (maneuver, parameters);
``study_first_run``
    the benchmark study on one worker in this process, its caches empty (laws, Jacobians
    per speed, steering): whole points with the ``fourws analyze`` metrics, extremes and
    linear eigenvalues, written block by block, wall time to the merged table;
``study_steps_per_s``
    the same study again per worker count (local processes forked from this one, caches
    filled): the steady state of a long study; ``rhs_per_s`` counts the four right-hand
    sides of each RK4 step (tools that count one evaluation per step compare with it);
``dask``
    the study on a Dask LocalCluster: its start-up, the round trip of an empty task
    (median of ``dask_tasks``), the study's first run (fourws loaded into the workers) and
    a second run;
``machine``: CPU count and load average when the benchmark started (the machine may be
shared: numbers from a loaded machine are lower).

Timings are reported, never asserted (``test/test_study.py`` asserts counts and values).
"""

from __future__ import annotations

import os
import platform
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from fourws_study.execute import run_study
from fourws_sim.lanes import LANES
from fourws_study.kernel import (build_law, compiled_plan, prepare_compiled, run_compiled,
                                 run_compiled_block)
from fourws_study.point import run_point
from fourws_study.spec import Study, study_from_mapping

#: The benchmark study: the default scenario's ISO 7401 step (table_8_1, 8-DOF, STI, RK4 at
#: 1 ms, laws at 100 Hz, 5 s per point), four laws over speed and belief error.
BENCH_STUDY = {
    "name": "bench",
    "scenario": "default",
    "grid": {"belief.cornering_stiffness_scale": [0.7, 1.0, 1.3],
             "speed_kmh": {"from": 60, "to": 140, "step": 2.5},
             "law": ["fws", "sol1", "rwc2_3dof", "rwc4_3dof"]},
    "block_size": 16,
}


#: Right-hand-side evaluations per RK4 step (to compare with tools that count a step as one
#: evaluation of the model).
RHS_PER_STEP = 4


def bench_study() -> Study:
    """The benchmark study (396 points: 3 beliefs x 33 speeds x 4 laws, in blocks of 16)."""
    return study_from_mapping(dict(BENCH_STUDY), "<fourws bench --study>")


def _loop_kernel(study: Study, repeats: int) -> dict[str, float]:
    """Steps/s of the compiled closed loop alone (the compiled call of one point, best and
    median of ``repeats``), and of the whole compiled run with its Python preparation."""
    config = study.config(study.point(study.n_points // 2))
    law = build_law(config)
    assert not compiled_plan(config, law)
    loop, whole = [], []
    steps = 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        record = run_compiled(config, law)
        whole.append(time.perf_counter() - t0)
        assert not isinstance(record, str), record
        loop.append(record.loop_seconds)
        steps = record.time_s.size * int(round(config.controller_period_s
                                               / config.integration_step_s))
    return {"loop_kernel_steps_per_s": steps / min(loop),
            "loop_kernel_steps_per_s_median": steps / statistics.median(loop),
            "loop_kernel_us_per_step": min(loop) / steps * 1e6,
            "compiled_run_steps_per_s": steps / min(whole)}


def _batch_kernel(study: Study, repeats: int) -> dict[str, Any]:
    """Steps/s of the batch kernel alone: one compiled call over one group of
    :data:`fourws_sim.lanes.LANES` points (vector instructions when the tire has lane
    kernels), best and median of ``repeats``."""
    preps = []
    for i in range(min(LANES, study.n_points)):
        config = study.config(study.point(i))
        prep = prepare_compiled(config, build_law(config))
        assert not isinstance(prep, str), prep
        preps.append(prep)
    steps = sum(p.front.size for p in preps) * preps[0].group[2]
    times = []
    for _ in range(repeats):
        records = run_compiled_block(preps)
        times.append(sum(r.loop_seconds for r in records if not isinstance(r, str)))
    return {"batch_kernel_points": len(preps), "batch_kernel_lanes": all(p.lanes for p in preps),
            "batch_kernel_steps_per_s": steps / min(times),
            "batch_kernel_steps_per_s_median": steps / statistics.median(times),
            "batch_kernel_us_per_step": min(times) / steps * 1e6}


def _study_run(study: Study, out: Path, **kw: Any) -> dict[str, float]:
    result = run_study(study, out, **kw)
    return {"steps_per_s": result.vehicle_steps / result.seconds,
            "rhs_per_s": RHS_PER_STEP * result.vehicle_steps / result.seconds,
            "points_per_s": result.ran / result.seconds, "seconds": result.seconds,
            "ms_per_point_per_worker": result.seconds / result.ran * 1e3
            * kw.get("workers", 1)}


def _dask(study: Study, tmp: Path, workers: int, tasks: int) -> dict[str, float]:
    """The study twice on one LocalCluster (the first run loads fourws into the workers),
    and the round trip of an empty task."""
    # distributed: about 0.5 s to load; only the dask backend needs it
    from distributed import Client, LocalCluster

    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    client = Client(cluster)
    out: dict[str, float] = {"workers": workers, "cluster_startup_s": time.perf_counter() - t0}
    try:
        trips = []
        for i in range(tasks):
            t1 = time.perf_counter()
            client.submit(int, i, pure=False).result()
            trips.append(time.perf_counter() - t1)
        out["task_overhead_s"] = statistics.median(trips)
        address = cluster.scheduler_address
        first = _study_run(study, tmp / "dask1", workers=workers, backend="dask",
                           scheduler=address)
        second = _study_run(study, tmp / "dask2", workers=workers, backend="dask",
                            scheduler=address)
        out.update({"first_run_steps_per_s": first["steps_per_s"],
                    "first_run_s": first["seconds"],
                    "steps_per_s": second["steps_per_s"], "seconds": second["seconds"]})
    finally:
        client.close()
        cluster.close()
    return out


def run_study_benchmark(workers: tuple[int, ...] = (1, 2), repeats: int = 5,
                        dask: bool = True, dask_tasks: int = 50) -> dict[str, Any]:
    """Measure the study speeds of the module docstring."""
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    study = bench_study()
    out: dict[str, Any] = {"machine": {"cpus": os.cpu_count(), "platform": platform.machine(),
                                       "python": platform.python_version(),
                                       "load_average_1_5_15": list(load)},
                           "study_points": study.n_points, "model": "8dof", "tire": "sti",
                           "integrator": "rk4", "step_s": 1e-3, "control_period_s": 0.01,
                           "seconds_per_point": 5.0}
    t0 = time.perf_counter()
    run_point(study, 0)  # compiled loop loaded (or compiled) in this process
    out["first_point_s"] = time.perf_counter() - t0
    out.update(_loop_kernel(study, repeats))
    out.update(_batch_kernel(study, repeats))
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        # the first run fills this process's caches (laws, Jacobians per speed, steering),
        # which forked workers inherit; the runs after it are the steady state of a study
        out["study_first_run"] = _study_run(study, root / "first", workers=1)
        out["study_steps_per_s"] = {str(n): _study_run(study, root / f"local{n}", workers=n)
                                    for n in workers}
        if dask:
            out["dask"] = _dask(study, root, max(workers), dask_tasks)
    out["ends_load_average_1_5_15"] = list(os.getloadavg()) if hasattr(os, "getloadavg") \
        else None
    return out


__all__ = ["BENCH_STUDY", "bench_study", "run_study_benchmark"]
