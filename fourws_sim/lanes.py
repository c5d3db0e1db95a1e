# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Lane layout of the batch kernels (the study advances many points at once).

A batch kernel holds ``LANES`` points ("lanes") side by side: quantity ``row`` of lane ``l``
is element ``row * LANES + l`` of a flat float64 array. Loops over the lanes of one row then
read and write consecutive memory at distances the compiler knows (``LANES`` is a constant),
so it turns them into vector instructions without run-time checks of overlapping arrays. A
block of more points runs as several groups of ``LANES``; a group of fewer is padded with
idle lanes.
"""

from __future__ import annotations

import os
import platform
from typing import MutableMapping

#: Points per group of a batch kernel: four AVX2 vectors of float64 (LLVM vectorizes a loop
#: of fewer than 16 iterations only where it needs no run-time overlap checks).
LANES = 16

#: Environment variables through which the user chooses numba's target CPU themselves.
_USER_CPU_SETTINGS = ("NUMBA_CPU_FEATURES", "NUMBA_CPU_NAME")


def use_wide_vectors(environ: MutableMapping[str, str] | None = None) -> bool:
    """Let numba compile with 512-bit vectors on x86-64 CPUs that have them.

    LLVM's tuning for recent Intel CPUs prefers 256-bit vectors (older ones lowered their
    clock for 512-bit instructions); the study's batch kernel runs 20 % faster with 512-bit
    ones (126 vs 157 ns per point and right-hand side here, on a 2-core Xeon of the Emerald
    Rapids family), with the same bits. ``fourws study`` and ``fourws bench --study`` call
    this before they compile anything; the simulator keeps the default. It sets numba's CPU
    features to the host's without that preference, for this process and (through
    ``NUMBA_CPU_FEATURES`` in ``environ``, default ``os.environ``) the worker processes it
    starts, unless the user set ``NUMBA_CPU_FEATURES`` or ``NUMBA_CPU_NAME`` (their choice
    stands) or the CPU is not an x86-64 with AVX-512; returns whether it did. Dask workers
    started elsewhere keep their own environment.
    """
    env = os.environ if environ is None else environ
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return False
    if any(name in env for name in _USER_CPU_SETTINGS):
        return False
    # numba: the host's CPU features as numba's compiler sees them (only these commands)
    from numba.core import codegen, config

    features = codegen.get_host_cpu_features()
    if "+avx512f" not in features.split(","):
        return False
    wide = f"{features},-prefer-256-bit"
    env["NUMBA_CPU_FEATURES"] = wide
    if environ is None:
        config.CPU_FEATURES = wide  # numba read the environment when it was imported
    return True


__all__ = ["LANES", "use_wide_vectors"]
