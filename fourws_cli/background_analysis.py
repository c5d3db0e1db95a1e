# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws analyze`` in a process of its own, fed one bag at a time: ``fourws demo``'s report.

The demo's report took about 4 s after its last run (the analysis modules' imports, python-
control's alone about 1 s, then about 1 s per bag). The worker imports them while the first
run starts and analyses each bag while the next run goes on, so after the last run only that
bag and the report remain. The worker is ``nice`` (the graph's runs keep the CPU: their answer
chain runs at SCHED_FIFO, the recorder and the launcher at normal priority) and ignores SIGINT
(the demo decides what an interrupt stops; it ends the worker).

Whatever happens to the worker (it cannot start, dies, is killed or stopped with SIGSTOP,
raises), :meth:`BackgroundAnalysis.finish` returns None and says why in one line: the demo then
analyses the bags in its own process, so a report is always written or its failure named.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import signal
import sys
import traceback
from typing import Any

from fourws_cli import cmd_analyze
from fourws_ros.oslevel import is_stopped
from fourws_sim.errors import FourwsError, one_line

#: How the worker is started: a fresh interpreter (the demo's process holds DDS threads,
#: which a fork must not copy).
START_METHOD = "spawn"
#: The worker's niceness increment (``os.nice``).
NICENESS = 10
#: How often the demo looks at a worker it waits for (alive, not stopped), s.
POLL_S = 0.5
#: How long a worker whose end failed is given to exit, so its exit code can be named, s.
GONE_WAIT_S = 5.0


def _serve(conn: Any, argv: list[str]) -> None:
    """The worker: ``add`` and ``finish`` requests on ``conn``, each answered; leaves at
    ``finish`` or when the demo's end closes ``conn``. ``argv``: ``fourws analyze``'s
    arguments, its bags the ones expected (only the bags added are analysed)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        os.nice(NICENESS)
    except OSError:
        pass  # a priority is a preference
    try:
        # scipy, control, matplotlib: imported here, ahead of the first bag (the purpose)
        from fourws_analysis import bag, compare, report  # noqa: F401

        parser = argparse.ArgumentParser()
        cmd_analyze.add_arguments(parser)
        analysis = cmd_analyze.BagAnalysis(parser.parse_args(argv))
        conn.send(("ready", None))
        while True:
            try:
                kind, path = conn.recv()
            except (EOFError, OSError):
                return  # the demo ended
            if kind == "add":
                analysis.add(path)
                conn.send(("added", path))
                continue
            try:
                code = analysis.finish()
            except Exception as exc:  # noqa: BLE001 - the package's one-line errors
                code = _one_line_error(exc)
            sys.stdout.flush()
            sys.stderr.flush()
            conn.send(("done", code))
            return
    except SystemExit as exc:  # argparse's refusal, already printed
        conn.send(("failed", f"its arguments were refused (exit code {exc.code})"))
    except Exception:  # noqa: BLE001 - the demo analyses in its own process instead
        conn.send(("failed", traceback.format_exc(limit=-1).strip().splitlines()[-1]))


def _one_line_error(exc: Exception) -> int:
    if not isinstance(exc, FourwsError):
        raise exc
    print(f"fourws analyze: error: {one_line(exc)}", file=sys.stderr)
    return 2


class BackgroundAnalysis:
    """The worker process seen from the demo: :meth:`add` a bag (returns at once),
    :meth:`finish` (the report's exit code, or None: analyse in this process), :meth:`close`."""

    def __init__(self, argv: list[str]) -> None:
        """Start the worker for ``fourws analyze`` ``argv``: its bags are the ones expected,
        but only those given to :meth:`add` are analysed (a run that failed has none)."""
        context = multiprocessing.get_context(START_METHOD)
        self._conn, child = context.Pipe()
        self._proc = context.Process(target=_serve, args=(child, argv), daemon=True,
                                     name="fourws-report")
        self.problem = ""
        self.added: list[str] = []
        try:
            self._proc.start()
        except OSError as exc:
            self.problem = f"cannot start the report's process: {exc.strerror or exc}"
        child.close()

    def add(self, path: str) -> None:
        """Have the worker analyse the bag ``path`` (queued; nothing waits for it here)."""
        if self.problem:
            return
        try:
            self._conn.send(("add", path))
            self.added.append(path)
        except OSError as exc:
            self._gone(f"cannot be reached: {exc.strerror or exc}")

    def finish(self) -> int | None:
        """Write the report and print what ``fourws analyze`` prints: its exit code, or None
        (``problem`` says why) when the worker could not do it."""
        if not self.problem:
            try:
                self._conn.send(("finish", None))
            except OSError as exc:
                self._gone(f"cannot be reached: {exc.strerror or exc}")
        while not self.problem:
            try:
                if not self._conn.poll(POLL_S):
                    self._check_alive()
                    continue
                kind, value = self._conn.recv()
            except (EOFError, OSError):
                self._gone("closed its end")
                break
            if kind == "done":
                self.close()
                return int(value)
            if kind == "failed":
                self.problem = f"the report's process failed: {value}"
        self.close()
        return None

    def _gone(self, otherwise: str) -> None:
        """The worker's end failed: name why, its exit above all (a killed process closes its
        end before its exit status can be read, so wait for it a moment)."""
        self._proc.join(timeout=GONE_WAIT_S)
        self._check_alive()
        self.problem = self.problem or f"the report's process {otherwise}"

    def _check_alive(self) -> None:
        if not self._proc.is_alive():
            self.problem = f"the report's process ended (exit code {self._proc.exitcode})"
        elif is_stopped(self._proc.pid):
            self.problem = "the report's process is stopped (SIGSTOP)"

    def close(self) -> None:
        """End the worker (at once if it has not finished)."""
        if self._proc.pid is None:
            return
        if self._proc.is_alive():
            self._proc.kill()
        self._proc.join(timeout=5.0)
        self._conn.close()


__all__ = ["BackgroundAnalysis", "GONE_WAIT_S", "NICENESS", "POLL_S", "START_METHOD"]
