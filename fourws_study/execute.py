# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Running a study: blocks of points as tasks, on this machine's cores or on Dask.

A task is one block (:meth:`fourws_study.store.StudyStore.block_points`):
:func:`run_encoded_block` runs its points in one process (their compiled runs in one call of
the batch kernel) and returns their rows encoded as the block's Parquet file; the process
that runs the study writes each block as it comes back
(:meth:`~fourws_study.store.StudyStore.write_block`). Backends:

* ``local`` (default): ``workers`` processes of this machine (a :mod:`multiprocessing`
  pool; one worker runs the blocks in this process);
* ``dask``: Dask distributed -- a :class:`distributed.LocalCluster` of ``workers`` processes
  when no scheduler is given, else the cluster at ``scheduler`` (``tcp://host:8786``). fourws
  writes no scheduler of its own; the README says how to start workers elsewhere.

A point's row depends only on the study and the point's number (each point builds its own
run from the study's resolved base and its seed; the caches of a worker hold laws and
Jacobians, not state), so the table is the same whatever the backend, the number of workers
or the order blocks finish in (``test/test_study.py``: serial, 2 local workers and a Dask
LocalCluster give identical rows, ``wall_time_s`` apart).
"""

from __future__ import annotations

import math
import multiprocessing
import signal
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, TextIO

import pyarrow as pa
from threadpoolctl import threadpool_limits

from fourws_sim.errors import ParameterError, one_line
from fourws_study.point import run_points
from fourws_study.spec import MAX_POINTS, Study
from fourws_study.store import RESULTS, StudyStore, encode_block, rows_to_table, schema

BACKENDS = ("local", "dask")


def run_block(study: Study, points: range | list[int], compiled: bool = True) -> pa.Table:
    """The rows of ``points`` (one task), as an Arrow table of the study's schema: their
    compiled runs in one call of the batch kernel (:func:`fourws_study.point.run_points`).

    The BLAS of numpy runs single-threaded meanwhile: a study already keeps every core busy
    with one point per worker, and threads contending for them made the small least-squares
    fits of the analysis several times slower (0.15 ms one thread, 0.86 ms two, measured on
    a 1000 x 10 ``lstsq`` here).
    """
    with threadpool_limits(limits=1):
        rows = run_points(study, points, compiled)
    return rows_to_table(rows, schema(study))


@dataclass(frozen=True)
class BlockResult:
    """A finished block as its worker returns it: the rows already encoded as the block's
    Parquet file (the worker does that work, not the process that writes the files), how
    many they are, and the vehicle-steps they ran."""

    block: int
    data: bytes
    rows: int
    vehicle_steps: int


def run_encoded_block(study: Study, block: int, points: range | list[int],
                      compiled: bool = True) -> BlockResult:
    """:func:`run_block`, encoded for :meth:`~fourws_study.store.StudyStore.write_block`
    (a task of either backend)."""
    table = run_block(study, points, compiled)
    steps = int(sum(v or 0 for v in table.column("vehicle_steps").to_pylist()))
    return BlockResult(block, encode_block(table, schema(study)), table.num_rows, steps)


@dataclass
class StudyRun:
    """What a study run did.

    Attributes
    ----------
    out : Path
    points : int
        Points of the study.
    done : int
        Points finished (this run and earlier ones).
    ran : int
        Points run by this run.
    statuses : Counter
        Status counts over the finished points.
    seconds : float
        Wall time of this run, s.
    vehicle_steps : int
        Integration steps run by this run.
    workers : int
    backend : str
    interrupted : bool
    failed : str
        Why the run stopped before its end ('' if it did not): a worker process that died
        (killed, out of memory) or a Dask worker that kept dying on a block.
    results : Path or None
    """

    out: Path
    points: int
    done: int = 0
    ran: int = 0
    statuses: Counter[str] = field(default_factory=Counter)
    seconds: float = 0.0
    vehicle_steps: int = 0
    workers: int = 1
    backend: str = "local"
    interrupted: bool = False
    failed: str = ""
    results: Path | None = None

    def summary_line(self, name: str) -> str:
        """The one-line summary printed at the end."""
        counts = ", ".join(f"{s} {self.statuses.get(s, 0)}"
                           for s in ("ok", "spun", "diverged", "error"))
        rate = self.ran / self.seconds if self.seconds > 0 else 0.0
        steps = self.vehicle_steps / self.seconds if self.seconds > 0 else 0.0
        state = ("INTERRUPTED, " if self.interrupted else
                 "STOPPED (a worker died), " if self.failed else "")
        return (f"fourws study {name}: {state}{self.done}/{self.points} points ({counts}); "
                f"ran {self.ran} in {self.seconds:.1f} s ({rate:.1f} points/s, "
                f"{steps:.3g} vehicle-steps/s) on {self.workers} {self.backend} worker(s); "
                f"results {self.results or self.out}")


class Progress:
    """A progress bar on a terminal (points done/total, points/s, ETA); silent otherwise."""

    def __init__(self, total: int, done: int, stream: TextIO | None = None) -> None:
        self.total = total
        self.start_done = done
        self.done = done
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.t0 = time.perf_counter()

    def update(self, done: int) -> None:
        """Draw the bar for ``done`` finished points."""
        self.done = done
        if not self.enabled:
            return
        elapsed = time.perf_counter() - self.t0
        ran = done - self.start_done
        rate = ran / elapsed if elapsed > 0 else 0.0
        eta = (self.total - done) / rate if rate > 0 else math.inf
        width = 30
        filled = int(width * done / self.total) if self.total else width
        eta_s = f"{eta:6.0f} s" if math.isfinite(eta) else "     ? s"
        self.stream.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{self.total} "
                          f"points  {rate:6.1f} points/s  ETA {eta_s} ")
        self.stream.flush()

    def close(self) -> None:
        """End the bar's line."""
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


def _dask_client(workers: int, scheduler: str | None) -> Any:
    """A Dask distributed client: of the cluster at ``scheduler``, or of a new LocalCluster
    with ``workers`` single-threaded worker processes."""
    try:
        # distributed: about 0.5 s to load; only the dask backend needs it
        from distributed import Client, LocalCluster
    except ImportError:
        raise ParameterError("--backend", "dask needs the 'dask[distributed]' package "
                             "(pip install 'dask[distributed]')") from None
    if scheduler:
        try:
            return Client(scheduler, timeout=30)
        except (OSError, TimeoutError) as exc:
            raise ParameterError("--scheduler", f"cannot reach the Dask scheduler at "
                                 f"{scheduler}: {exc}") from None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    return Client(cluster)


class WorkerLost(Exception):
    """A worker process died while it ran a block (its message says which and how); the
    study stops, keeping every finished block."""


def _exit_text(code: int | None) -> str:
    if code is None:
        return "still running"
    if code < 0:
        try:
            return f"killed by signal {-code} ({signal.Signals(-code).name})"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"


def _dead(procs: set[multiprocessing.process.BaseProcess],
          wait_s: float = 2.0) -> list[tuple[int | None, str]]:
    """The worker processes that died, with how (PID, text). The executor can see a worker
    gone (its pipe closed) a moment before the system reports its exit status, so this waits
    up to ``wait_s`` for one; the workers the executor itself then stops (SIGTERM) are left
    out when another one died first."""
    deadline = time.monotonic() + wait_s
    while True:
        ended = [p for p in procs if p.exitcode not in (None, 0)]
        if ended or time.monotonic() >= deadline:
            break
        time.sleep(0.01)
    first = [p for p in ended if p.exitcode != -signal.SIGTERM] or ended
    return sorted(((p.pid, _exit_text(p.exitcode)) for p in first), key=lambda d: d[0] or 0)


def _worker_init() -> None:
    """Local workers leave Ctrl-C to the study's process, which stops them (a terminal sends
    SIGINT to the whole process group)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _block_task(args: tuple[Study, int, list[int], bool]) -> BlockResult:
    study, block, points, compiled = args
    return run_encoded_block(study, block, points, compiled)


def _local_tasks(study: Study, blocks: list[tuple[int, range]], workers: int,
                 compiled: bool) -> Iterator[BlockResult]:
    """Run blocks on local processes; yields each as it finishes.

    Raises
    ------
    WorkerLost
        A worker process died (a ``multiprocessing.Pool`` would wait for its block forever;
        the executor reports it).
    """
    if workers <= 1:
        for b, points in blocks:
            yield run_encoded_block(study, b, points, compiled)
        return
    before = set(multiprocessing.active_children())
    executor = ProcessPoolExecutor(min(workers, max(len(blocks), 1)),
                                   mp_context=multiprocessing.get_context(),
                                   initializer=_worker_init)
    procs: set[multiprocessing.process.BaseProcess] = set()
    finished = False
    try:
        futures = {executor.submit(_block_task, (study, b, list(points), compiled)): b
                   for b, points in blocks}
        procs = set(multiprocessing.active_children()) - before
        for fut in as_completed(futures):
            try:
                result = fut.result()
            except BrokenProcessPool:
                who = "; ".join(f"worker {pid} {how}" for pid, how in _dead(procs)) or \
                    "a worker process ended abruptly"
                raise WorkerLost(f"a local worker process died while running a block "
                                 f"({who})") from None
            yield result
        finished = True
    finally:
        if not finished:
            # an interrupted or broken study stops its workers now, not after their blocks
            for proc in procs | (set(multiprocessing.active_children()) - before):
                proc.terminate()
        executor.shutdown(wait=True, cancel_futures=True)


def _dask_tasks(study: Study, blocks: list[tuple[int, range]], workers: int,
                scheduler: str | None, compiled: bool) -> Iterator[BlockResult]:
    """Run blocks on Dask; yields each as it finishes."""
    # distributed: about 0.5 s to load; only the dask backend needs it
    from distributed import KilledWorker
    from distributed import as_completed as dask_completed

    client = _dask_client(workers, scheduler)
    try:
        remote_study = client.scatter(study, broadcast=True)
        futures = {client.submit(run_encoded_block, remote_study, b, list(points), compiled,
                                 pure=False,
                                 key=f"fourws-study-{study.name}-block-{b}-{time.time_ns()}"): b
                   for b, points in blocks}
        try:
            for fut in dask_completed(futures):
                try:
                    result = fut.result()
                except KilledWorker as exc:
                    raise WorkerLost(f"Dask workers kept dying while running block "
                                     f"{futures[fut]} ({one_line(exc)})") from None
                yield result
        finally:
            client.cancel(list(futures))
    finally:
        cluster = getattr(client, "cluster", None)
        client.close()
        if cluster is not None and scheduler is None:
            cluster.close()


def check_size(study: Study, force: bool) -> None:
    """Refuse a study of more than :data:`fourws_study.spec.MAX_POINTS` points unless
    ``force``.

    Raises
    ------
    ParameterError
        Too many points.
    """
    if study.n_points > MAX_POINTS and not force:
        raise ParameterError("points", f"the study has {study.n_points} points (more than "
                             f"{MAX_POINTS}); give --force to run it", study.source)


def run_study(study: Study, out: str | Path, *, workers: int = 1, backend: str = "local",
              scheduler: str | None = None, resume: bool = False, force: bool = False,
              compiled: bool = True, progress_stream: TextIO | None = None,
              on_start: Callable[[int], None] | None = None,
              on_block: Callable[[int], None] | None = None) -> StudyRun:
    """Run every missing block of ``study`` into ``out`` (module docstring).

    Parameters
    ----------
    study : Study
    out : str or Path
        The study folder (:mod:`fourws_study.store`).
    workers : int
        Worker processes (local, or of the Dask LocalCluster).
    backend : {"local", "dask"}
    scheduler : str, optional
        Address of a running Dask scheduler (``dask`` only).
    resume : bool
        Continue the study already in ``out``: run only the blocks not written yet.
    force : bool
        Allow more than :data:`fourws_study.spec.MAX_POINTS` points.
    compiled : bool
        Use the compiled closed loop where it applies (the rows do not change).
    progress_stream : text stream, optional
        Where the progress bar goes (default stderr; drawn only on a terminal).
    on_start : callable, optional
        Called with the number of points to run once the folder is ready (before any runs).
    on_block : callable, optional
        Called with the number of each block written (tests interrupt a study here).

    Returns
    -------
    StudyRun
        ``interrupted`` if Ctrl-C stopped it; the finished blocks are kept and
        ``results.parquet`` holds them.

    Raises
    ------
    ParameterError
        Bad backend or worker count, too many points without ``force``, a folder that
        holds other results.
    """
    if backend not in BACKENDS:
        raise ParameterError("--backend", f"must be one of {', '.join(BACKENDS)}, got "
                             f"{backend!r}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError("--workers", f"must be an integer >= 1, got {workers!r}")
    if scheduler and backend != "dask":
        raise ParameterError("--scheduler", "only with --backend dask")
    check_size(study, force)
    store = StudyStore(Path(out), study, study.block_size)
    store.open(resume)
    missing = store.missing_blocks()
    run = StudyRun(Path(out), study.n_points, workers=workers, backend=backend)
    run.done = study.n_points - sum(len(store.block_points(b)) for b in missing)
    if on_start is not None:
        on_start(study.n_points - run.done)
    bar = Progress(study.n_points, run.done, progress_stream)
    blocks = [(b, store.block_points(b)) for b in missing]
    t0 = time.perf_counter()
    tasks = (_dask_tasks(study, blocks, workers, scheduler, compiled) if backend == "dask"
             else _local_tasks(study, blocks, workers, compiled))
    try:
        for result in tasks:
            store.write_block(result.block, result.data)
            run.ran += result.rows
            run.done += result.rows
            run.vehicle_steps += result.vehicle_steps
            bar.update(run.done)
            if on_block is not None:
                on_block(result.block)
    except KeyboardInterrupt:
        run.interrupted = True
    except WorkerLost as exc:
        run.failed = str(exc)
    finally:
        bar.close()
        run.seconds = time.perf_counter() - t0
    if run.done:
        run.results, _ = store.merge()
        statuses = store.read_results().column("status").to_pylist()
        run.statuses = Counter(statuses)
    return run


__all__ = ["BACKENDS", "BlockResult", "Progress", "RESULTS", "StudyRun", "WorkerLost",
           "check_size", "run_block", "run_encoded_block", "run_study"]
