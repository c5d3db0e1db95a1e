# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws analyze`` in a process of its own, fed one bag at a time: ``fourws demo``'s report.

The demo's report took about 4 s after its last run (the analysis modules' imports, python-
control's alone about 1 s, then about 1 s per bag). The worker imports them while the first
run starts and analyses each bag while the next run goes on, so after the last run only that
bag and the report remain. The worker is ``nice`` while the runs go on (the graph's runs keep
the CPU: their answer chain runs at SCHED_FIFO, the recorder and the launcher at normal
priority), and back at the demo's niceness once the demo waits for it, where that is
permitted (CAP_SYS_NICE or RLIMIT_NICE: beside two CPU hogs the niced worker took 31 s for
the default report, 47 s after the last run; an ordinary user's stays nice), and ignores SIGINT
(the demo decides what an interrupt stops; it ends the worker). It is a program of its own
(``python -m fourws_cli.background_analysis FD``, a socket to the demo), not a
:mod:`multiprocessing` child: the demo's process holds DDS threads, which a fork must not copy,
and multiprocessing's spawn runs the caller's main script again in the child (a user's script
that calls the demo without a ``__main__`` guard would run twice).

Whatever happens to the worker (it cannot start, dies, is killed or stopped with SIGSTOP,
raises), :meth:`BackgroundAnalysis.finish` returns None and says why in one line: the demo then
analyses the bags in its own process, so a report is always written or its failure named. A
demo that dies (SIGKILL) takes its worker with it (the parent-death signal): nobody waits for
that report any more.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import traceback
from multiprocessing.connection import Connection
from typing import Any

from fourws_cli import cmd_analyze
from fourws_ros.oslevel import PR_SET_PDEATHSIG, is_stopped, niceness, prctl
from fourws_sim.errors import FourwsError, one_line

#: The worker's niceness increment (``os.nice``).
NICENESS = 10
#: Sent by the demo when it starts waiting for the report: the worker takes the demo's
#: niceness back where permitted.
HURRY_SIGNAL = signal.SIGUSR1
#: How often the demo looks at a worker it waits for (alive, not stopped), s.
POLL_S = 0.5
#: How long a worker whose end failed is given to exit, so its exit code can be named, s.
GONE_WAIT_S = 5.0


def _serve(conn: Any, argv: list[str]) -> None:
    """The worker: ``prepare`` and ``add`` requests on ``conn``, then ``finish``, answered
    ``done`` (the exit code) or ``failed`` (why); it leaves after ``finish`` or when the demo's
    end closes ``conn``. ``argv``: ``fourws analyze``'s arguments, its bags the ones expected
    (only the bags added are analysed)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    base = os.getpriority(os.PRIO_PROCESS, 0)
    # the demo's runs are over and it waits for this report (HURRY_SIGNAL: at once, between
    # two bytecodes, even while earlier bags are still being analysed): nothing is left to
    # yield to, and beside a CPU hog a worker niced by 10 gets about 5 % of a core
    signal.signal(HURRY_SIGNAL, lambda _signum, _frame: _restore_priority(base))
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
        while True:
            try:
                kind, value = conn.recv()
            except (EOFError, OSError):
                return  # the demo ended
            if kind == "prepare":
                try:
                    analysis.prepare(json.loads(value))
                except Exception:  # noqa: BLE001 - ahead of time only: the bag's says why
                    pass
            elif kind == "add":
                analysis.add(value)
            else:
                _restore_priority(base)  # should the demo's HURRY_SIGNAL have been lost
                try:
                    code = analysis.finish()
                except Exception as exc:  # noqa: BLE001 - the package's one-line errors
                    code = _one_line_error(exc)
                sys.stdout.flush()
                sys.stderr.flush()
                _answer(conn, "done", code)
                return
    except SystemExit as exc:  # argparse's refusal, already printed
        _answer(conn, "failed", f"its arguments were refused (exit code {exc.code})")
    except Exception:  # noqa: BLE001 - the demo analyses in its own process instead
        _answer(conn, "failed", traceback.format_exc(limit=-1).strip().splitlines()[-1])


def _restore_priority(base: int) -> None:
    """Back to the demo's niceness ``base``: permitted with CAP_SYS_NICE or an RLIMIT_NICE that
    allows it; an ordinary user's worker stays nice (the report then takes longer beside
    other load)."""
    try:
        os.setpriority(os.PRIO_PROCESS, 0, base)
    except OSError:
        pass


def _answer(conn: Any, kind: str, value: Any) -> None:
    """Answer the demo (nothing if it has gone: nobody waits for the answer)."""
    try:
        conn.send((kind, value))
    except OSError:
        pass


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
        self.problem = ""
        ours, theirs = socket.socketpair()
        self._conn = Connection(ours.detach())
        self._proc: subprocess.Popen[bytes] | None = None
        try:
            self._proc = subprocess.Popen(
                [sys.executable, "-m", "fourws_cli.background_analysis",
                 str(theirs.fileno()), str(os.getpid()), *argv],
                stdin=subprocess.DEVNULL, pass_fds=(theirs.fileno(),))
        except OSError as exc:
            self.problem = f"cannot start the report's process: {exc.strerror or exc}"
        finally:
            theirs.close()

    def prepare(self, config_json: str) -> None:
        """Have the worker compute ahead what the bags of a run of ``config_json`` (the text
        of its ``/fourws/run_config``) share with the runs of its car and law (queued)."""
        self._request("prepare", config_json)

    def add(self, path: str) -> None:
        """Have the worker analyse the bag ``path`` (queued; nothing waits for it here)."""
        self._request("add", path)

    def _request(self, kind: str, value: str) -> bool:
        """Send a request (False: the worker cannot take it, ``problem`` says why)."""
        if self.problem:
            return False
        try:
            self._conn.send((kind, value))
        except OSError as exc:
            self._gone(f"cannot be reached: {exc.strerror or exc}")
            return False
        return True

    def finish(self) -> int | None:
        """Write the report and print what ``fourws analyze`` prints: its exit code, or None
        (``problem`` says why) when the worker could not do it."""
        if not self.problem:
            try:
                # only to a worker that has niced itself: its handler is installed before
                # (the signal's default action would end it)
                if self._proc is not None and self._proc.poll() is None and \
                        (niceness(self._proc.pid) or 0) > os.getpriority(os.PRIO_PROCESS, 0):
                    self._proc.send_signal(HURRY_SIGNAL)
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
        try:
            if self._proc is not None:
                self._proc.wait(timeout=GONE_WAIT_S)
        except subprocess.TimeoutExpired:
            pass
        self._check_alive()
        self.problem = self.problem or f"the report's process {otherwise}"

    def _check_alive(self) -> None:
        if self._proc is None:
            return
        if self._proc.poll() is not None:
            self.problem = f"the report's process ended (exit code {self._proc.returncode})"
        elif is_stopped(self._proc.pid):
            self.problem = "the report's process is stopped (SIGSTOP)"

    def close(self) -> None:
        """End the worker (at once if it has not finished)."""
        self._conn.close()
        if self._proc is None:
            return
        if self._proc.poll() is None:
            self._proc.kill()
        self._proc.wait()


def main(argv: list[str]) -> int:
    """The worker process (``python -m fourws_cli.background_analysis FD DEMO_PID ARGS...``):
    exit code 0, or 1 when the demo had already gone."""
    prctl(PR_SET_PDEATHSIG, signal.SIGKILL)  # (set before the check: no gap for a death)
    if os.getppid() != int(argv[1]):
        return 1
    _serve(Connection(int(argv[0])), argv[2:])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))


__all__ = ["BackgroundAnalysis", "GONE_WAIT_S", "NICENESS", "POLL_S", "main"]
