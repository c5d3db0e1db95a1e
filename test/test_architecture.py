"""House-style guarantees: the core imports no rclpy and no message types.

Source of the rule: docs/architecture.md (core packages are plain Python so they are testable and
fast). The check imports every core module in a fresh interpreter in which importing ``rclpy``,
``rosidl_runtime_py`` or any ``*_msgs`` package raises ImportError.
"""

from __future__ import annotations

import pkgutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CORE = ("fourws_sim", "fourws_control", "fourws_analysis", "fourws_study")

_BLOCKER = r"""
import importlib.abc, sys
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        top = name.split('.')[0]
        if top in ('rclpy', 'rosidl_runtime_py') or top.endswith('_msgs') or top.endswith('_srvs'):
            raise ImportError(f'{name} is blocked: core modules must not import ROS')
        return None
sys.meta_path.insert(0, Block())
import importlib
for mod in sys.argv[1:]:
    importlib.import_module(mod)
print(len(sys.argv) - 1)
"""


def _core_modules() -> list[str]:
    mods = []
    for pkg in CORE:
        mods.append(pkg)
        for info in pkgutil.walk_packages([str(ROOT / pkg)], prefix=f"{pkg}."):
            mods.append(info.name)
    return mods


def test_core_imports_without_ros() -> None:
    mods = _core_modules()
    proc = subprocess.run([sys.executable, "-c", _BLOCKER, *mods], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    # every module was imported: the printed count equals the number of modules listed
    assert int(proc.stdout.strip().splitlines()[-1]) == len(mods)
    assert len(mods) >= 4
