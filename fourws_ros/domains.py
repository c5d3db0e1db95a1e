# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""ROS domains of fourws runs: one per run, exclusive on this machine, discovery kept local.

A run's processes talk on one ROS domain with discovery limited to this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``), so runs and tests side by side never see each
other and nothing leaves the machine. If the user set ``ROS_DOMAIN_ID``, the run uses that
domain (and says so); otherwise it leases a free one from :data:`DOMAIN_ID_RANGE`. Either way
the domain is locked (a file lock under the temporary directory) for the run's duration, so two
fourws runs never share one.
"""

from __future__ import annotations

import fcntl
import os
import tempfile
from pathlib import Path
from typing import TextIO

from fourws_sim.errors import FourwsError
from fourws_sim.params import CONFIG_DIR

#: Domain IDs handed out (Linux: 0..101 are safe with the default port mapping; 0 is the
#: default domain users' other ROS graphs live on, so it is never picked).
DOMAIN_ID_RANGE = range(1, 101)
#: Largest domain ID ROS 2 accepts with the default port mapping on Linux.
MAX_DOMAIN_ID = 232
_LOCK_DIR = Path(tempfile.gettempdir()) / "fourws-domains"


class DomainError(FourwsError):
    """No ROS domain can be used for the run (all taken, or the user's is busy/invalid)."""


class DomainLease:
    """An exclusive lock on one ROS domain ID of this machine (released by :meth:`release`).

    Attributes
    ----------
    domain_id : int
    from_user : bool
        The ID came from the user's ``ROS_DOMAIN_ID``.
    """

    def __init__(self, domain_id: int, handle: TextIO, from_user: bool = False) -> None:
        self.domain_id = domain_id
        self.from_user = from_user
        self._handle: TextIO | None = handle

    def release(self) -> None:
        """Give the domain ID back."""
        if self._handle is not None:
            fcntl.flock(self._handle, fcntl.LOCK_UN)
            self._handle.close()
            self._handle = None

    def __enter__(self) -> "DomainLease":
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _try_lock(domain: int) -> TextIO | None:
    _LOCK_DIR.mkdir(parents=True, exist_ok=True)
    handle = open(_LOCK_DIR / f"{domain}.lock", "w")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.close()
        return None
    return handle


def _last_leased(domain: int) -> float:
    """When ``domain`` was last leased on this machine (its lock file's mtime; 0: never)."""
    try:
        return (_LOCK_DIR / f"{domain}.lock").stat().st_mtime
    except OSError:
        return 0.0


def reserve_domain_id(start: int | None = None) -> DomainLease:
    """Lock a ROS domain ID no other fourws run or test on this machine holds.

    By default the free ID leased longest ago: two runs one after the other (a series, the
    runs of one process) never share a domain, so nothing a run left behind on its domain
    -- a node still in its teardown, a participant the run could not close, a shared-memory
    port of a killed node that Fast DDS reopens for a later participant -- meets the next
    run; a domain comes back only after every other one was used.

    Parameters
    ----------
    start : int, optional
        First ID to try instead (then upwards, wrapping around).

    Raises
    ------
    DomainError
        If every ID of :data:`DOMAIN_ID_RANGE` is taken.
    """
    ids = list(DOMAIN_ID_RANGE)
    if start is None:
        order = sorted(ids, key=_last_leased)
    else:
        first = start % len(ids)
        order = ids[first:] + ids[:first]
    for domain in order:
        handle = _try_lock(domain)
        if handle is not None:
            try:
                os.utime(handle.fileno())
            except OSError:
                pass  # the order is a preference, the lock is the guarantee
            return DomainLease(domain, handle)
    raise DomainError(f"no free ROS domain ID in {DOMAIN_ID_RANGE.start}.."
                      f"{DOMAIN_ID_RANGE.stop - 1} (every one is used by a fourws run)")


def domain_for_run(environ: dict[str, str] | None = None) -> DomainLease:
    """The domain of a new run: the user's ``ROS_DOMAIN_ID`` if set, else a leased one.

    Raises
    ------
    DomainError
        The user's ID is not a valid domain ID, or another fourws run holds it.
    """
    env = os.environ if environ is None else environ
    text = env.get("ROS_DOMAIN_ID", "").strip()
    if not text:
        return reserve_domain_id()
    if not text.isdigit() or int(text) > MAX_DOMAIN_ID:
        raise DomainError(f"ROS_DOMAIN_ID={text!r} is not a ROS domain ID (0..{MAX_DOMAIN_ID})")
    handle = _try_lock(int(text))
    if handle is None:
        raise DomainError(f"ROS domain {text} (from ROS_DOMAIN_ID) is used by another fourws "
                          "run on this machine; unset ROS_DOMAIN_ID to let fourws pick a free "
                          "domain, or choose another")
    return DomainLease(int(text), handle, from_user=True)


#: Fast DDS settings of a run (``config/dds/fastdds.xml``: a reliable writer's heartbeat every
#: 20 ms instead of 3 s, so a message lost in a transport queue is asked for again at once).
DDS_PROFILES = CONFIG_DIR / "dds" / "fastdds.xml"
_DDS_PROFILES_VARS = ("FASTDDS_DEFAULT_PROFILES_FILE", "FASTRTPS_DEFAULT_PROFILES_FILE")


def graph_env(domain_id: int, base: dict[str, str] | None = None) -> dict[str, str]:
    """Environment of a node process: the run's domain, discovery on this machine only, the
    run's Fast DDS settings (unless the user gave a profiles file of their own)."""
    env = dict(os.environ if base is None else base)
    env["ROS_DOMAIN_ID"] = str(domain_id)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.pop("ROS_STATIC_PEERS", None)
    env["PYTHONUNBUFFERED"] = "1"
    if not any(env.get(var) for var in _DDS_PROFILES_VARS) and DDS_PROFILES.is_file():
        env["FASTDDS_DEFAULT_PROFILES_FILE"] = str(DDS_PROFILES)
    return env


__all__ = ["DDS_PROFILES", "DOMAIN_ID_RANGE", "DomainError", "DomainLease", "MAX_DOMAIN_ID",
           "domain_for_run", "graph_env", "reserve_domain_id"]
