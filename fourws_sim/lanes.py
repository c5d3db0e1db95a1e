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

#: Points per group of a batch kernel: four AVX2 vectors of float64 (LLVM vectorizes a loop
#: of fewer than 16 iterations only where it needs no run-time overlap checks).
LANES = 16

__all__ = ["LANES"]
