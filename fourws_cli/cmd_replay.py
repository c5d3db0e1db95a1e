# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""``fourws replay BAG [--topics T ...] [--rate R] [--mode timed|answer]``: play a recorded bag
into a running graph (on the current ``ROS_DOMAIN_ID``), e.g. a recorded driver input into a
new run with another controller. See :mod:`fourws_ros.replay_node`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from fourws_cli._bounds import bounded
from fourws_sim.errors import ParameterError

HELP = "play a recorded bag back into the ROS 2 graph (all or chosen topics, rate, /clock)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``fourws replay``."""
    parser.add_argument("bag", type=Path, help="bag directory (rosbag2, MCAP)")
    parser.add_argument("--topics", nargs="+", default=[], metavar="TOPIC",
                        help="topics to play (default: every graph topic in the bag)")
    parser.add_argument("--rate", type=float, default=1.0, help="rate factor (timed mode)")
    parser.add_argument("--mode", choices=("timed", "answer"), default="timed",
                        help="timed: at the recorded times; answer: one tick per state of a "
                             "running lockstep simulator")
    parser.add_argument("--no-clock", action="store_true", help="do not publish /clock")


def run(args: argparse.Namespace) -> int:
    """Replay the bag; returns the node's exit code."""
    from fourws_ros.replay_node import main  # rclpy: not for --help

    bounded("--rate", args.rate, 0.0, 1000.0, low_open=True)
    if not args.bag.is_dir():
        raise ParameterError("bag", f"no bag directory {str(args.bag)!r}")
    ros_args = ["fourws_replay", "--ros-args", "-p", f"bag_path:={args.bag}",
                "-p", f"rate:={float(args.rate)}", "-p", f"mode:={args.mode}",
                "-p", f"publish_clock:={'false' if args.no_clock else 'true'}"]
    if args.topics:
        ros_args += ["-p", "topics:=[" + ",".join(args.topics) + "]"]
    return main(ros_args)
