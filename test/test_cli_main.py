# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The ``fourws`` command itself: its help lists every subcommand, ``--version`` gives the
package's version, and a subcommand's unknown option gets that subcommand's usage.

Sources: the subcommand modules (``fourws_cli/cmd_*.py`` and their ``HELP`` lines), the node
table ``fourws_cli.nodes``, and the version in ``package.xml`` (the version setup.py
installs).
"""

from __future__ import annotations

import pkgutil
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import fourws_cli
from fourws_cli import nodes
from fourws_cli.main import DESCRIPTION, main

ROOT = Path(__file__).resolve().parent.parent
COMMANDS = sorted(info.name[4:].replace("_", "-") for info in
                  pkgutil.iter_modules(fourws_cli.__path__) if info.name.startswith("cmd_"))


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    try:
        code = main(list(argv))
    except SystemExit as exc:  # argparse's --help, --version and usage errors
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


def test_help_describes_fourws_and_lists_every_subcommand(capsys):
    """``fourws --help`` showed the module docstring ("Entry point of the ``fourws``
    command.") and no ``node``: it gives the description and one help line per subcommand,
    every cmd_*.py module and ``node``, in alphabetical order."""
    code, out, _ = _run(capsys, "--help")
    assert code == 0
    assert "Entry point" not in out
    assert " ".join(DESCRIPTION.split()) in " ".join(out.split())
    assert re.findall(r"^ {4}([a-z][a-z-]*)", out, re.M) == sorted([*COMMANDS, "node"])
    listed = "".join(out.split())  # argparse wraps the lines (also at hyphens)
    for name in [*COMMANDS, "node"]:
        module = nodes if name == "node" else __import__(
            f"fourws_cli.cmd_{name.replace('-', '_')}", fromlist=["HELP"])
        assert name + "".join(module.HELP.split()) in listed, name


def test_version_is_the_package_version(capsys):
    """``fourws --version`` prints package.xml's version (setup.py installs that one)."""
    expected = ET.parse(ROOT / "package.xml").getroot().findtext("version")
    code, out, _ = _run(capsys, "--version")
    assert code == 0 and out == f"fourws {expected}\n"


@pytest.mark.parametrize("command", COMMANDS)
def test_unknown_option_gives_the_subcommands_usage(capsys, command):
    """``fourws handling ... --speed-kmh 85`` printed the top-level usage ("usage: fourws
    [-h] COMMAND ..."): every subcommand's unknown option gets the subcommand's own usage
    and one error line naming the command and the option, exit 2."""
    args = {"handling": ["--vehicle", "table_4_4", "--law", "sol1"],
            "study": ["x"], "analyze": ["bag"], "bag": ["verify", "bag"], "replay": ["bag"],
            "linear": ["--vehicle", "table_4_4", "--model", "2dof", "--law", "sol1",
                       "--speed-kmh", "85"],
            "lqr-gains": ["--vehicle", "table_4_4"],
            "equilibria": ["--vehicle", "table_7_1_set_1", "--speed-mps", "20"],
            "tire-curves": ["--vehicle", "table_8_1"],
            "export": ["bag", "--format", "csv"],
            "identify": ["log.csv", "--vehicle", "table_8_1"],
            "validate": ["sim", "ref"]}.get(command, [])
    code, _, err = _run(capsys, command, *args, "--no-such-option")
    lines = err.strip().splitlines()
    assert code == 2, err
    assert lines[0].startswith(f"usage: fourws {command} "), err
    assert lines[-1] == f"fourws {command}: error: unrecognized arguments: --no-such-option", \
        err
    assert sum(line.startswith("fourws") for line in lines) == 1


def test_the_reported_unknown_option_case(capsys):
    """The case as reported: ``fourws handling --vehicle table_4_4 --law sol1 --speed-kmh 85``
    (``handling`` takes ``--speeds-mps``)."""
    code, _, err = _run(capsys, "handling", "--vehicle", "table_4_4", "--law", "sol1",
                        "--speed-kmh", "85")
    assert code == 2 and err.startswith("usage: fourws handling [-h] --vehicle VEHICLE")
    assert err.strip().splitlines()[-1] == ("fourws handling: error: unrecognized arguments: "
                                            "--speed-kmh 85")
