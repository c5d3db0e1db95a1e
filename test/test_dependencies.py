# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Every import of the code is declared: in package.xml with its rosdep key (a ROS workspace:
``rosdep install --from-paths src --ignore-src``), in requirements.txt (the venv of
``make setup``) and, for the Python libraries of the runtime, in setup.py (pip).

Source: the imports themselves (``ast`` of every ``.py`` file of the package), and the ament
index of this environment's ROS packages (a ROS package's rosdep key is its name). The rosdep
keys of the libraries that are not ROS packages are in :data:`LIBRARIES` below, each with
where it is defined in the rosdep index (ros/rosdistro ``rosdep/python.yaml``); how they were
chosen: docs/architecture.md, "Dependencies".
"""

from __future__ import annotations

import ast
import os
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: Folders whose modules run in the installed package (exec dependencies): every Python package
#: fourws_* (what setup.py and CMakeLists.txt install) and the launch file.
RUNTIME_DIRS = (*sorted(p.parent.name for p in ROOT.glob("fourws_*/__init__.py")), "launch")
#: Import name -> (rosdep key, PyPI distribution) of the libraries that are not ROS packages.
#: Evidence for each key (ros/rosdistro, rosdep/python.yaml): python3-numpy, python3-scipy,
#: python3-yaml, python3-matplotlib, python3-pytest, python3-hypothesis, python-control-pip:
#: present in the file;
#: python3-numba: rosdistro PR 32274, all Ubuntu releases since PR 36477;
#: python3-rosbags-pip: PR 37795; mcap-ros2-support: PR 36081 (pip mcap-ros2-support, which
#: requires the mcap library the code imports). No key names the mcap library itself
#: (rosdep/python.yaml and base.yaml at ros/rosdistro 8468e88, 2026-08-22, hold only
#: mcap-ros2-support; Debian has no python3-mcap), so package.xml declares the key that brings
#: it, and :data:`VIA_REQUIREMENT` records the requirement that does.
LIBRARIES: dict[str, tuple[str, str]] = {
    "numpy": ("python3-numpy", "numpy"),
    "scipy": ("python3-scipy", "scipy"),
    "yaml": ("python3-yaml", "pyyaml"),
    "numba": ("python3-numba", "numba"),
    "matplotlib": ("python3-matplotlib", "matplotlib"),
    "control": ("python-control-pip", "control"),
    "rosbags": ("python3-rosbags-pip", "rosbags"),
    "mcap": ("mcap-ros2-support", "mcap"),
    "pytest": ("python3-pytest", "pytest"),
    "hypothesis": ("python3-hypothesis", "hypothesis"),
    # the ROS package urdfdom_py (ros/urdf_parser_py) installs the module urdf_parser_py; its
    # rosdep key is the package name (rosdistro: distribution.yaml, repository urdfdom_py)
    "urdf_parser_py": ("urdfdom_py", "urdf-parser-py"),
}
#: Import name -> (the distribution its rosdep key installs, the requirement of that
#: distribution that brings the imported library): mcap-ros2-support 0.6.0's requires_dist on
#: PyPI is ``mcap>=1.6.0``.
VIA_REQUIREMENT: dict[str, tuple[str, str, tuple[int, ...]]] = {
    "mcap": ("mcap-ros2-support", "mcap", (1, 6, 0)),
}
#: Import name -> PyPI distribution of the libraries of ``fourws study`` that have no key in the
#: rosdep index (none found for pyarrow, dask/distributed or threadpoolctl): not in package.xml,
#: so ``rosdep install`` stays resolvable; a ROS install gets them with pip (README, Studies).
PIP_ONLY: dict[str, str] = {
    "pyarrow": "pyarrow",
    "distributed": "dask",
    "threadpoolctl": "threadpoolctl",
    # the live view's Foxglove WebSocket server (fourws run --live): no rosdep key either
    "foxglove": "foxglove-sdk",
    # a forked node's command line as its process title (fourws_ros.node_starter): no key
    # (rosdep/python.yaml at ros/rosdistro 000730d has none between python3-serial and
    # python3-setuptools); optional, without it a forked node shows the starter's
    "setproctitle": "setproctitle",
}
#: ROS packages imported only by the launch file: ``ros2 launch`` brings them on a system ROS
#: install; they are not on PyPI (the venv uses ``fourws run`` instead).
NOT_ON_PYPI = ("launch", "launch_ros")
#: ROS interface packages with no PyPI wheel: ``make setup`` builds them from the definitions
#: vendored in interfaces/ (interfaces/SOURCE.md); a system ROS install has them (rosdep key =
#: the package name).
VENDORED = ("tf2_msgs", "ackermann_msgs")
#: Keys of package.xml that no module imports: the build and test tools of the package.
TOOL_KEYS = ("ament_cmake", "ament_cmake_python", "rosidl_default_generators",
             "rosidl_default_runtime", "builtin_interfaces", "std_msgs", "ament_cmake_pytest",
             "python3-colcon-common-extensions")
#: This package's own Python modules (and the messages it generates as ``fourws.msg``).
OWN = {p.parent.name for p in ROOT.glob("fourws_*/__init__.py")} | {"fourws"}


def _imports(paths: list[Path]) -> dict[str, set[str]]:
    """Top-level module name -> files importing it (absolute imports, lazy ones included)."""
    found: dict[str, set[str]] = {}
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                found.setdefault(name.split(".")[0], set()).add(path.name)
    return found


def _external(found: dict[str, set[str]]) -> dict[str, set[str]]:
    local = OWN | {p.stem for p in (ROOT / "test").glob("*.py")}
    return {m: files for m, files in found.items()
            if m not in sys.stdlib_module_names and m not in local and m != "__future__"}


def _package_xml() -> dict[str, set[str]]:
    """Dependency kind (exec, test, build...) -> rosdep keys of package.xml."""
    kinds: dict[str, set[str]] = {}
    for element in ET.parse(ROOT / "package.xml").getroot():
        if element.tag.endswith("depend"):
            kinds.setdefault(element.tag, set()).add((element.text or "").strip())
    return kinds


def _requirements() -> set[str]:
    names = set()
    for line in (ROOT / "requirements.txt").read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            names.add(re.split(r"[<>=!~\[; ]", line)[0].lower())
    return names


def _install_requires() -> set[str]:
    for node in ast.walk(ast.parse((ROOT / "setup.py").read_text())):
        if isinstance(node, ast.keyword) and node.arg == "install_requires":
            return {name.lower() for name in ast.literal_eval(node.value)}
    return set()


def _ros_packages() -> set[str]:
    """ROS packages of this environment's ament prefixes (the venv's ROS wheels, or a system
    ROS 2 install on AMENT_PREFIX_PATH)."""
    prefixes = [sys.prefix, *os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep)]
    return {p.name for prefix in prefixes if prefix
            for p in (Path(prefix) / "share/ament_index/resource_index/packages").glob("*")}


def _key_and_pip(module: str, ros: set[str]) -> tuple[str, str | None]:
    """The rosdep key and PyPI distribution of an imported module."""
    if module in LIBRARIES:
        return LIBRARIES[module]
    if module in PIP_ONLY:
        return "", PIP_ONLY[module]
    if module in NOT_ON_PYPI or module in VENDORED:
        return module, None
    if module in ros:
        return module, "ros-" + module.replace("_", "-")  # the ROS 2 wheels' naming
    raise AssertionError(f"import {module!r} is neither a ROS package of this environment nor "
                         "in LIBRARIES: add its rosdep key there and to package.xml")


@pytest.fixture(scope="module")
def imports() -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    runtime = [p for d in RUNTIME_DIRS for p in (ROOT / d).rglob("*.py")]
    tests = sorted((ROOT / "test").glob("*.py"))
    return _external(_imports(runtime)), _external(_imports(tests))


def test_every_runtime_import_is_an_exec_dependency(imports) -> None:
    runtime, _ = imports
    ros, xml = _ros_packages(), _package_xml()
    exec_keys = xml.get("exec_depend", set()) | xml.get("depend", set())
    missing = {m: sorted(files) for m, files in runtime.items()
               if m not in PIP_ONLY and _key_and_pip(m, ros)[0] not in exec_keys}
    assert not missing, f"imports with no <exec_depend> in package.xml: {missing}"
    # the venv and pip installs: requirements.txt, and setup.py for the plain libraries
    requirements, install_requires = _requirements(), _install_requires()
    no_pip = {m for m in runtime if (_key_and_pip(m, ros)[1] or "") not in requirements
              and m not in NOT_ON_PYPI and m not in VENDORED}
    assert not no_pip, f"imports missing from requirements.txt: {sorted(no_pip)}"
    plain = {LIBRARIES[m][1] for m in runtime if m in LIBRARIES}
    assert plain <= install_requires, \
        f"missing from setup.py install_requires: {sorted(plain - install_requires)}"


def test_every_test_import_is_declared(imports) -> None:
    _, tests = imports
    ros, xml = _ros_packages(), _package_xml()
    keys = set().union(*(xml.get(kind, set()) for kind in ("test_depend", "exec_depend",
                                                           "depend")))
    missing = {m: sorted(files) for m, files in tests.items()
               if m not in PIP_ONLY and _key_and_pip(m, ros)[0] not in keys}
    assert not missing, f"test imports with no <test_depend> in package.xml: {missing}"
    requirements = _requirements()
    no_pip = {m for m in tests if (_key_and_pip(m, ros)[1] or "") not in requirements
              and m not in VENDORED}
    assert not no_pip, f"test imports missing from requirements.txt: {sorted(no_pip)}"


def test_every_vendored_interface_is_built_by_setup() -> None:
    """interfaces/ holds exactly the packages of :data:`VENDORED`, each with its licence, and
    the Makefile builds each (VENDORED_INTERFACES)."""
    folders = sorted(p.parent.name for p in (ROOT / "interfaces").glob("*/package.xml"))
    assert folders == sorted(VENDORED)
    assert all((ROOT / "interfaces" / name / "LICENSE").is_file() for name in folders)
    makefile = (ROOT / "Makefile").read_text()
    line = next(s for s in makefile.splitlines() if s.startswith("VENDORED_INTERFACES :="))
    assert sorted(p.split("/")[-1] for p in line.split(":=")[1].split()) == folders


def test_every_declared_key_is_known(imports) -> None:
    """No key of package.xml is a typo or stale: each one is a ROS package (of this
    environment, or one of the launch file's), a library of LIBRARIES that the code still
    imports, or a build/test tool of the package."""
    runtime, tests = imports
    ros = _ros_packages()
    used = {_key_and_pip(m, ros)[0] for m in (*runtime, *tests)}
    declared = set().union(*_package_xml().values())
    library_keys = {key for key, _ in LIBRARIES.values()}
    unknown = declared - used - set(TOOL_KEYS) - (ros - library_keys) - set(NOT_ON_PYPI)
    assert not unknown, f"package.xml keys that nothing uses: {sorted(unknown)}"
    stale = {m for m in (*LIBRARIES, *PIP_ONLY) if m not in runtime and m not in tests}
    assert not stale, f"LIBRARIES entries no module imports: {sorted(stale)}"
    # the build and test tools are ROS packages too, but for colcon
    ros_tools = [k for k in TOOL_KEYS if not k.startswith("python3-")]
    assert all(k in ros for k in ros_tools), sorted(set(ros_tools) - ros)


def test_a_library_brought_by_another_key_is_pinned_within_its_requirement() -> None:
    """mcap is imported, and its rosdep key is mcap-ros2-support's (none names mcap itself):
    what rosdep installs then is mcap-ros2-support's ``mcap>=1.6.0``, and the venv's pin of
    requirements.lock lies inside it, so both installs run a version that satisfies it."""
    pins = dict(line.split("==", 1) for line in (ROOT / "requirements.lock").read_text()
                .splitlines() if "==" in line and not line.startswith("#"))
    for module, (key_dist, dist, minimum) in VIA_REQUIREMENT.items():
        assert LIBRARIES[module] == (key_dist, dist), module
        pinned = tuple(int(x) for x in pins[dist].split(".")[:3])
        assert pinned >= minimum, (dist, pins[dist], minimum)


def test_an_undeclared_import_is_reported(tmp_path: Path) -> None:
    """The check itself: a module importing a library that package.xml lacks is found."""
    module = tmp_path / "extra.py"
    module.write_text("import json\nimport numpy\nfrom fourws_sim import params\n"
                      "def f():\n    import requests\n")
    assert sorted(_external(_imports([module]))) == ["numpy", "requests"]
    with pytest.raises(AssertionError, match="requests"):
        _key_and_pip("requests", _ros_packages())
