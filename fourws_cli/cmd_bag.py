# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws bag verify BAG...`` / ``fourws bag repair BAG...``: check and mend recorded bags.

``verify`` checks every chunk's checksum, the data section's checksum, the metadata's counts
and the recorder's accounting (does the bag hold every message the run published?), and
prints one line per bag: complete, or what is missing or damaged.

``repair`` rebuilds a bag whose recorder was killed (no ``metadata.yaml``, no MCAP summary):
it keeps every message of the complete, checksum-verified chunks, writes a new MCAP file with
summary and checksums and a ``metadata.yaml`` (the damaged file stays beside as
``*.mcap.damaged``), so rosbags, Foxglove and ``fourws analyze --allow-incomplete`` open it.
Its accounting is recomputed from the publishers' final counts found in the bag.

Both refuse a bag that is still being recorded (its writer holds the lock of
``fourws_run.bagfile.LOCK_FILE``): a repair would rewrite the file under the recorder.

Exit code: 0 every bag complete; 1 a bag is incomplete or damaged (repaired or not); 2 a path
is not a bag, is still being recorded, or cannot be written.
"""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "verify bags (checksums, completeness) or repair a bag whose recorder was killed"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``fourws bag``."""
    parser.add_argument("action", choices=("verify", "repair"))
    parser.add_argument("bags", nargs="+", type=Path, metavar="BAG")


def run(args: argparse.Namespace) -> int:
    """Verify or repair each bag; returns the exit code."""
    from fourws_run.bagfile import repair_bag, verify_bag  # rosbags, mcap: not for --help

    worst = 0
    for bag in args.bags:
        if args.action == "verify":
            check = verify_bag(bag)
        else:
            result = repair_bag(bag)
            recovered = ", ".join(f"{t} {n}" for t, n in sorted(result.recovered.items()))
            print(f"{bag}: repaired; recovered {sum(result.recovered.values())} messages "
                  f"({recovered}); damaged file kept as {result.backup}")
            check = result.check
        print(check.summary())
        if not check.complete:
            worst = max(worst, 1)
    return worst
