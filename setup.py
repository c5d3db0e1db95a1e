"""ament_python package setup for fourws (also installs with plain pip into a venv)."""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = "fourws"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(include=["fourws_sim*", "fourws_control*", "fourws_run*",
                                    "fourws_analysis*", "fourws_study*",
                                    "fourws_ros*", "fourws_cli*"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config/vehicles", glob("config/vehicles/*.yaml")),
        (f"share/{PACKAGE}/config/maneuvers", glob("config/maneuvers/*.yaml")),
        (f"share/{PACKAGE}/config/scenarios", glob("config/scenarios/*.yaml")),
        (f"share/{PACKAGE}/config/studies", glob("config/studies/*.yaml")),
        (f"share/{PACKAGE}/config/params", glob("config/params/*.yaml")),
        (f"share/{PACKAGE}/config/dds", glob("config/dds/*.xml")),
    ],
    install_requires=["setuptools", "numpy", "scipy", "pyyaml"],
    zip_safe=True,
    maintainer="fourws developers",
    maintainer_email="fourws@example.org",
    description="Real-time 4WS vehicle-dynamics simulator and analysis as a ROS 2 node graph",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "fourws = fourws_cli.main:main",
            # one console script per node: `ros2 run fourws <node> --ros-args ...`
            "simulator = fourws_ros.simulator_node:main",
            "maneuver = fourws_ros.maneuver_node:main",
            "controller = fourws_ros.controller_node:main",
            "recorder = fourws_ros.recorder_node:main",
            "replay = fourws_ros.replay_node:main",
            "example_controller = fourws_ros.example_controller:main",
        ],
    },
)
