# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Draw a report's figures side by side: each in a forked copy of this process.

A report's figures are independent and cost CPU only (Agg rendering and the constrained
layout): the default report's three take about 1.6 s one after the other, the longest alone
0.7 s. :func:`draw_all` runs each drawing job in a child forked from this process, which
already holds matplotlib, the fonts and the data, so a child starts in milliseconds; at most
``workers`` at once.

The result is always the one-process result: a job whose child fails in any way (an
exception, a signal, a stop, no answer within :data:`CHILD_TIMEOUT_S`) is drawn again here
afterwards, so a figure is never missing
and a drawing error is raised exactly as without children. Children are used only where a
fork is safe and useful: a POSIX platform, more than one job and worker, and no other Python
thread in this process (a fork copies a lock another thread may hold). Children are waited
for by their own pid, never "any child", so a caller's other children are left alone.
"""

from __future__ import annotations

import os
import select
import signal
import threading
import time
from pathlib import Path
from typing import Any, Callable, Sequence

#: A drawing job: ``fn(members, path)`` draws into ``path`` and returns it, or None when it
#: has nothing to draw.
Job = tuple[Callable[[Any, Path], "Path | None"], Any, Path]

#: Children drawing at once by default: the cores of this machine (at most 4).
DEFAULT_WORKERS = max(1, min(4, os.cpu_count() or 1))
#: Environment variable that sets the number of workers (1: draw in this process).
WORKERS_ENV = "FOURWS_FIGURE_WORKERS"

#: How often the children are looked at while none answers, s.
POLL_S = 0.2
#: A child that has not answered this long after its fork is killed and its figure drawn
#: here, s: a figure takes about a second, so only a child that cannot go on (hung, or
#: starved for minutes) gets there, and drawing it here again is always right.
CHILD_TIMEOUT_S = 120.0

_DREW, _NOTHING = b"P", b"N"


def workers_from_env() -> int:
    """The number of workers: :data:`WORKERS_ENV` if it is a positive integer, else
    :data:`DEFAULT_WORKERS`."""
    value = os.environ.get(WORKERS_ENV, "")
    return int(value) if value.isdigit() and int(value) > 0 else DEFAULT_WORKERS


def can_fork() -> bool:
    """Whether a fork is safe here: POSIX, and no other Python thread."""
    return hasattr(os, "fork") and threading.active_count() == 1


def draw_all(jobs: Sequence[Job], workers: int | None = None,
             started: Callable[[int], None] | None = None,
             order: Sequence[int] | None = None) -> list[Path | None]:
    """Run every job; their results in order (module docstring).

    Parameters
    ----------
    jobs : sequence of (fn, members, path)
    workers : int, optional
        Children at once (default :func:`workers_from_env`); 1 draws here, one after the
        other.
    started : callable, optional
        Called with a job's index as it starts (a progress bar).
    order : sequence of int, optional
        The job indices in the order to start them (default: as given); the results stay in
        the jobs' order.
    """
    tick = started or (lambda _k: None)
    n = workers_from_env() if workers is None else int(workers)
    pending = list(range(len(jobs)) if order is None else order)
    if sorted(pending) != list(range(len(jobs))):
        raise ValueError(f"order {list(pending)} is not a permutation of the {len(jobs)} jobs")
    results: dict[int, Path | None] = {}
    if n <= 1 or len(jobs) < 2 or not can_fork():
        for k in pending:
            tick(k)
            fn, members, path = jobs[k]
            results[k] = fn(members, path)
        return [results[k] for k in range(len(jobs))]
    again: list[int] = []
    running: dict[int, tuple[int, int]] = {}  # read fd -> (job index, child pid)
    since: dict[int, float] = {}  # read fd -> when its child was forked
    answers: dict[int, bytes] = {}  # read fd -> what its child wrote so far
    try:
        while pending or running:
            while pending and len(running) < n:
                k = pending.pop(0)
                tick(k)
                fd, pid = _fork_job(jobs[k])
                running[fd] = (k, pid)
                since[fd] = time.monotonic()
            ready, _, _ = select.select(list(running), [], [], POLL_S)
            for fd in [fd for fd, (_k, pid) in running.items()
                       if _stopped(pid) or time.monotonic() - since[fd] > CHILD_TIMEOUT_S]:
                k, pid = running.pop(fd)  # stopped (SIGSTOP) or hung: drawn again here
                answers.pop(fd, None)
                _discard(fd, pid)
                again.append(k)
            for fd in ready:
                if fd not in running:
                    continue
                chunk = os.read(fd, 65536)
                if chunk:  # (the answer; the end of file comes with the child's exit)
                    answers[fd] = answers.get(fd, b"") + chunk
                    continue
                k, pid = running.pop(fd)
                answer = answers.pop(fd, b"")
                os.close(fd)
                os.waitpid(pid, 0)
                if answer.startswith(_DREW):
                    results[k] = Path(answer[1:].decode())
                elif answer == _NOTHING:
                    results[k] = None
                else:  # the child failed: drawn again here, below
                    again.append(k)
    finally:
        for fd, (_k, pid) in running.items():  # interrupted: no child outlives the call
            _discard(fd, pid)
    for k in sorted(again):
        fn, members, path = jobs[k]
        results[k] = fn(members, path)
    return [results[k] for k in range(len(jobs))]


def _fork_job(job: Job) -> tuple[int, int]:
    """Fork a child that runs ``job`` and writes its answer to a pipe; (read fd, pid)."""
    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns
        code = 1
        try:
            os.close(read_fd)
            fn, members, path = job
            drawn = fn(members, path)
            os.write(write_fd, _NOTHING if drawn is None else _DREW + str(drawn).encode())
            code = 0
        finally:
            os._exit(code)
    os.close(write_fd)
    return read_fd, pid


def _discard(fd: int, pid: int) -> None:
    """Kill a child and reap it (SIGKILL also ends a stopped process)."""
    os.close(fd)
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    os.waitpid(pid, 0)


def _stopped(pid: int) -> bool:
    """Child ``pid`` is stopped (SIGSTOP/SIGTSTP: state T or t in /proc/PID/stat)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            stat = f.read()
    except OSError:
        return False
    return stat[stat.rfind(b")") + 2:][:1] in (b"T", b"t")


__all__ = ["CHILD_TIMEOUT_S", "DEFAULT_WORKERS", "Job", "POLL_S", "WORKERS_ENV", "can_fork",
           "draw_all", "workers_from_env"]
