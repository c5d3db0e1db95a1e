# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Style and license of the sources: ament_flake8 with the project's configuration
(setup.cfg: pycodestyle and pyflakes at 99 columns) finds nothing, and every source file
carries an SPDX license header (Apache-2.0, as package.xml declares).

Why ament_flake8 and which files carry headers: docs/architecture.md, "Lint".
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from ament_flake8.main import main_with_errors

ROOT = Path(__file__).resolve().parent.parent
#: Python sources checked by the linter.
PYTHON = [*sorted(ROOT.glob("fourws_*")), ROOT / "test", ROOT / "launch", ROOT / "bench",
          ROOT / "setup.py"]
#: Files with an SPDX header: code, configuration and build files. Not the message definitions
#: (their leading comment is the message's documentation, shown by ``ros2 interface show``
#: and stored in every bag), the docs, the generated or plain lists (requirements*) and the
#: recorded test data (test/data: a bag as an earlier fourws wrote it), nor the vendored
#: interface packages of interfaces/ (other projects' files under their own licences,
#: interfaces/SOURCE.md; test_dependencies checks each carries its LICENSE).
HEADER_SUFFIXES = (".py", ".yaml", ".cfg", ".ini", ".xml")
HEADER_NAMES = ("CMakeLists.txt", "Makefile", ".ci/run")
SPDX = "SPDX-License-Identifier: Apache-2.0"


def test_flake8_finds_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # ament_flake8 walks the working directory for folders to exclude: an empty one here, so
    # it does not walk the venv
    monkeypatch.chdir(tmp_path)
    rc, errors = main_with_errors(argv=["--config", str(ROOT / "setup.cfg"),
                                        *map(str, PYTHON)])
    assert (rc, errors) == (0, [])


def _sources() -> list[Path]:
    listed = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-co", "--exclude-standard"],
                            capture_output=True, text=True)
    if listed.returncode != 0:
        pytest.skip("not a git checkout: the source files are the tracked ones")
    names = [n for n in listed.stdout.splitlines() if (ROOT / n).is_file()]
    return [ROOT / n for n in names if (n.endswith(HEADER_SUFFIXES) or n in HEADER_NAMES)
            and not n.startswith(("test/data/", "interfaces/"))]


def test_every_source_file_has_an_spdx_header() -> None:
    sources = _sources()
    assert len(sources) > 100  # the package's modules, tests and configuration files
    missing = [str(p.relative_to(ROOT)) for p in sources
               if SPDX not in "\n".join(p.read_text().splitlines()[:5])]
    assert not missing, f"no '{SPDX}' in the first lines of: {missing}"
