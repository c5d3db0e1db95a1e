# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Entry point of the ``fourws`` command.

Each subcommand is a module ``fourws_cli/cmd_<name>.py`` exposing::

    HELP: str                                   # one line for ``fourws --help``
    def add_arguments(parser) -> None           # fill its argparse sub-parser
    def run(args) -> int                        # exit code

Modules are discovered by name, so adding a subcommand is adding one file. User errors
(:class:`fourws_sim.errors.FourwsError`) and files that cannot be read or written
(:class:`OSError`: a missing or read-only folder, a full disk) become one line
``fourws COMMAND: error: ...`` on stderr and exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys
import xml.etree.ElementTree as ET
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import fourws_cli
from fourws_cli.nodes import HELP as NODE_HELP
from fourws_cli.nodes import NODES, run_node
from fourws_sim.errors import FourwsError, one_line

#: Exit code of a user error: bad input, or an output that cannot be written.
EXIT_USER_ERROR = 2
#: What ``fourws --help`` says first.
DESCRIPTION = ("fourws: a four-wheel-steering car simulated as a ROS 2 node graph (8-DOF model, "
               "rear-steer laws, maneuvers, recorded and checked bags), with the offline "
               "analyses of its runs, models and studies.")
EPILOG = ("'fourws COMMAND --help' gives a command's options; README.md the workflows, the "
          "files and the exit codes.")


def _commands() -> dict[str, object]:
    found = {}
    for info in pkgutil.iter_modules(fourws_cli.__path__):
        if info.name.startswith("cmd_"):
            found[info.name[4:].replace("_", "-")] = f"fourws_cli.{info.name}"
    return dict(sorted(found.items()))


def fourws_version() -> str:
    """The installed version of fourws: its pip metadata, else (a colcon install, which has
    none) the ``package.xml`` of its ament prefix or checkout."""
    try:
        return version("fourws")
    except PackageNotFoundError:
        pass
    # numpy with it: not at the top, where `fourws node` must not import it before its
    # stop-while-starting handler is set (fourws_cli.nodes)
    from fourws_sim.params import find_resource_dir
    root = find_resource_dir(Path(__file__).resolve().parent.parent, "fourws", "",
                             "package.xml")
    try:
        return ET.parse(root / "package.xml").getroot().findtext("version") or "unknown"
    except (OSError, ET.ParseError):
        return "unknown"


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (subcommands imported lazily, only their parsers)."""
    parser = argparse.ArgumentParser(prog="fourws", description=DESCRIPTION, epilog=EPILOG)
    parser.add_argument("--version", action="version",
                        version=f"fourws {fourws_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, modname in sorted({**_commands(), "node": ""}.items()):
        if name == "node":
            # listed for --help only: main() hands `fourws node ...` to run_node untouched
            p = sub.add_parser(name, help=NODE_HELP, description=NODE_HELP)
            p.add_argument("node", metavar="NAME", choices=list(NODES),
                           help=f"one of {', '.join(NODES)}")
            p.add_argument("ros_args", nargs=argparse.REMAINDER, metavar="--ros-args ...")
            continue
        mod = importlib.import_module(modname)
        p = sub.add_parser(name, help=getattr(mod, "HELP", ""),
                           description=getattr(mod, "HELP", ""))
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run, _parser=p)
    return parser


def main(argv: list[str] | None = None, *, own_process: bool = False) -> int:
    """Run the ``fourws`` command line; returns the exit code. ``own_process``: this is the
    process's own command (:func:`entry`): it leaves right after, so the runs' launcher
    participants are kept instead of destroyed, and the process leaves with ``os._exit``
    while it holds one (a caller in the same process, such as a test, gets neither)."""
    argv = sys.argv[1:] if argv is None else argv
    # `fourws node NAME ...` hands everything after NAME to the node untouched (--ros-args ...)
    if len(argv) >= 1 and argv[0] == "node":
        return run_node(argv[1:])
    # a command that runs the node graph: the node starter imports meanwhile (about 1.4 s
    # of the graph's start-up, fourws_cli.node_starter)
    if (argv[:1] in (["run"], ["demo"], ["bench-graph"]) or argv[:2] == ["study", "rerun"]) \
            and not {"-h", "--help"} & set(argv):
        from fourws_cli.node_starter import install  # the standard library, then rclpy
        install()
        if own_process:
            # the process leaves right after its command (_leave_if_stuck): each run's
            # launcher participant is kept, not destroyed (a Fast DDS destroy can deadlock)
            from fourws_ros import launcher_node
            launcher_node.KEEP_PARTICIPANTS = True
    # the batch kernel of a study (not its rerun through the node graph, whose nodes inherit
    # the environment) with 512-bit vectors; before anything is compiled (fourws_sim.lanes)
    if (argv[:1] == ["study"] and argv[1:2] != ["rerun"]) or (
            argv[:1] == ["bench"] and "--study" in argv):
        from fourws_sim.lanes import use_wide_vectors  # numpy: not for `fourws node`
        use_wide_vectors()
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra:
        # argparse blames the top level for a subcommand's unknown option (and prints the
        # top-level usage); the subcommand's own usage is the helpful one
        getattr(args, "_parser", parser).error(f"unrecognized arguments: {' '.join(extra)}")
    if not getattr(args, "_run", None):
        parser.print_help()
        return 1
    try:
        code = int(args._run(args) or 0)
        return _leave_if_stuck(code) if own_process else code
    except FourwsError as exc:
        print(f"fourws {args.command}: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_USER_ERROR
    except OSError as exc:
        # an --out/--report/plot path that cannot be written (missing or read-only folder, a
        # full disk) or an input that cannot be read; the message names the path
        print(f"fourws {args.command}: error: {_os_error(exc, args)}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        print(f"fourws {args.command}: interrupted", file=sys.stderr)
        return 130


def _leave_if_stuck(code: int) -> int:
    """``code``; but a process holding a launcher participant kept or stuck in Fast DDS (see
    ``fourws_ros.launcher_node.ABANDONED``) leaves at once with it: a normal exit would
    destroy the participant (and can hang)."""
    launcher = sys.modules.get("fourws_ros.launcher_node")
    if launcher is not None and launcher.ABANDONED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


#: Options of the subcommands that name a file or folder to write.
_OUTPUT_OPTIONS = ("out", "report", "bode_plot", "region", "plot", "png", "keep")


def _os_error(exc: OSError, args: argparse.Namespace) -> str:
    """One line for an OSError: its path first (as in the package errors) and the reason; an
    error raised while writing an already open file (a full disk) carries no path, so the
    output options given are named instead."""
    names = [repr(str(n)) for n in (exc.filename, exc.filename2) if n is not None]
    what = exc.strerror or one_line(exc)
    if names:
        return f"{' -> '.join(names)}: {what}"
    given = [f"--{k.replace('_', '-')} {str(getattr(args, k))!r}" for k in _OUTPUT_OPTIONS
             if getattr(args, k, None) is not None]
    return f"{what} (writing {', '.join(given)})" if given else what


def entry() -> int:
    """The ``fourws`` program (console script and ``python -m fourws_cli.main``)."""
    return main(own_process=True)


if __name__ == "__main__":
    sys.exit(entry())
