# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The fourws node graph on a system ROS 2 install: ``ros2 launch fourws fourws.launch.py``.

Starts the node set of ``fourws run`` -- simulator, maneuver, controller and recorder -- with
a shipped parameter file, ``share/fourws/config/params/<clock>.yaml``::

    ros2 launch fourws fourws.launch.py                       # lockstep, recorded
    ros2 launch fourws fourws.launch.py clock:=realtime
    ros2 launch fourws fourws.launch.py record:=false params_file:=my_params.yaml

The recorder writes the ``bag_path`` of the parameter file, relative to the working directory;
it must not exist yet. For system installs only: launch and launch_ros are not on PyPI, so in
the project venv ``fourws run`` (the project's own launcher) starts the same graph.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = "fourws"
#: The shipped parameter file of each clock mode (in share/fourws/config/params).
PARAMS_FILES = {"lockstep": "lockstep.yaml", "realtime": "realtime.yaml"}


def _nodes(context: object) -> list[Node]:
    clock = LaunchConfiguration("clock").perform(context)
    record = LaunchConfiguration("record").perform(context) == "true"
    params_file = LaunchConfiguration("params_file").perform(context) or os.path.join(
        get_package_share_directory(PACKAGE), "config", "params", PARAMS_FILES[clock])
    simulator = {}
    if clock == "lockstep" and not record:
        # the shipped file waits for the recorder too (3 state subscribers) and runs at most
        # recorder_window messages ahead of it: without a recorder, neither
        simulator = {"expected_state_subscribers": 2, "recorder_window": 0}
    nodes = [
        Node(package=PACKAGE, executable="simulator", name="fourws_simulator",
             parameters=[params_file, simulator], output="screen"),
        Node(package=PACKAGE, executable="maneuver", name="fourws_maneuver",
             parameters=[params_file], output="screen"),
        Node(package=PACKAGE, executable="controller", name="fourws_controller",
             parameters=[params_file], output="screen"),
    ]
    if record:
        nodes.append(Node(package=PACKAGE, executable="recorder", name="fourws_recorder",
                          parameters=[params_file], output="screen"))
    return nodes


def generate_launch_description() -> LaunchDescription:
    """The launch arguments and the nodes."""
    return LaunchDescription([
        DeclareLaunchArgument("clock", default_value="lockstep", choices=list(PARAMS_FILES),
                              description="clock mode; selects the shipped parameter file"),
        DeclareLaunchArgument("record", default_value="true", choices=["true", "false"],
                              description="start the recorder (writes the file's bag_path)"),
        DeclareLaunchArgument("params_file", default_value="",
                              description="a parameter file to use instead of the shipped one"),
        OpaqueFunction(function=_nodes),
    ])
