# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""pip packaging of fourws (the venv of ``make setup``; a ROS workspace builds with CMake).

The ROS package is the ament_cmake package of ``CMakeLists.txt``/``package.xml``; this file is
only for pip. Its console scripts carry a ``fourws-`` prefix (``fourws-simulator``...): on a
venv's PATH, generic names such as ``simulator`` or ``controller`` would collide with other
tools. ``ros2 run fourws simulator`` is unaffected (CMake installs the unprefixed executables
under ``lib/fourws``, where ``ros2 run`` looks).
"""

import runpy
import xml.etree.ElementTree as ET
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "fourws"
#: The version is package.xml's.
VERSION = ET.parse("package.xml").getroot().findtext("version")
#: Node name -> module, the one table (fourws_cli/nodes.py); read without importing fourws_cli.
NODES = runpy.run_path("fourws_cli/nodes.py")["NODES"]

setup(
    name=PACKAGE,
    version=VERSION,
    packages=find_packages(include=["fourws_*"]),
    data_files=[
        (f"share/{PACKAGE}/config/{sub}", glob(f"config/{sub}/*.{ext}"))
        for sub, ext in (("vehicles", "yaml"), ("maneuvers", "yaml"), ("scenarios", "yaml"),
                         ("studies", "yaml"), ("params", "yaml"), ("dds", "xml"),
                         ("foxglove", "json"), ("drivers", "yaml"))
    ],
    # the Python libraries the code imports (ROS wheels: requirements.txt; ROS: package.xml)
    install_requires=["numpy", "scipy", "pyyaml", "numba", "control", "matplotlib", "rosbags",
                      "mcap"],
    zip_safe=True,
    maintainer="fourws developers",
    maintainer_email="fourws@example.org",
    description="Real-time 4WS vehicle-dynamics simulator and analysis as a ROS 2 node graph",
    license="Apache-2.0",
    entry_points={
        "console_scripts": ["fourws = fourws_cli.main:entry"]
        # through fourws_cli.nodes, which handles a stop while the node is still importing
        + [f"fourws-{name} = fourws_cli.nodes:entry.{name}" for name in NODES],
    },
)
