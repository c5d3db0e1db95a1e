# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Example rear-steer controller: copy this file to write your own (see
docs/controller-contract.md).

It depends only on rclpy and the fourws message interfaces (``fourws.msg``) — none of the
fourws Python packages — and implements the simplest 4WS law there is, a steering-ratio rear
steer ``delta_r = rear_ratio * delta_f`` (negative ratio: counter-phase), clipped to
``angle_limit_rad``. Replace :meth:`ExampleController.law` with yours.

The contract it follows:

1. Subscribe to ``/fourws/state`` (``fourws/msg/VehicleState``) and
   ``/fourws/driver_input`` (``fourws/msg/DriverInput``), both reliable, keep last 2000.
2. For every state, once the driver input with the *same* ``header.stamp`` has arrived
   (lockstep: it always comes, right after the state), publish exactly one
   ``fourws/msg/RearSteerCommand`` on ``/fourws/rear_steer_cmd`` with
   ``state_step = state.step`` and ``state_stamp = state.header.stamp``.
3. Never publish a non-finite angle or one beyond the vehicle's rear angle limit: the
   simulator ignores it and, after its command timeout, steers the rear wheels to zero.

Run it in place of the built-in controller::

    fourws node example_controller --ros-args -p rear_ratio:=-0.1
    ros2 run fourws example_controller --ros-args -p rear_ratio:=-0.1   # system ROS 2
"""

from __future__ import annotations

import math
import sys

import rclpy
from fourws.msg import DriverInput, RearSteerCommand, VehicleState
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

#: QoS of the graph's message streams (fourws_ros/topics.py STREAM_QOS): transient local, so
#: the first command reaches the simulator and the recorder whenever they match this publisher.
STREAM_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=2000,
                        reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.TRANSIENT_LOCAL)


def _stamp_ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


class ExampleController(Node):
    """Ratio rear steer answering every state (the lockstep handshake)."""

    def __init__(self) -> None:
        super().__init__("fourws_controller")
        self.declare_parameter("rear_ratio", -0.1, ParameterDescriptor(
            description="rear/front road-wheel angle ratio, 1 (negative: counter-phase)",
            floating_point_range=[FloatingPointRange(from_value=-1.0, to_value=1.0)]))
        self.declare_parameter("angle_limit_rad", math.radians(5.0), ParameterDescriptor(
            description="rear angle limit, rad",
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=0.5)]))
        self.add_on_set_parameters_callback(self.on_set)
        self.pub = self.create_publisher(RearSteerCommand, "/fourws/rear_steer_cmd", STREAM_QOS)
        self.create_subscription(VehicleState, "/fourws/state", self.on_state, STREAM_QOS)
        self.create_subscription(DriverInput, "/fourws/driver_input", self.on_driver, STREAM_QOS)
        self.state = None
        self.front_by_stamp: dict[int, float] = {}

    def on_set(self, params) -> SetParametersResult:
        for p in params:
            if not math.isfinite(float(p.value)):
                return SetParametersResult(successful=False, reason=f"{p.name}: not finite")
        return SetParametersResult(successful=True)

    def law(self, state: VehicleState, front_rad: float) -> float:
        """Rear road-wheel angle command, rad. Replace with your law."""
        return self.get_parameter("rear_ratio").value * front_rad

    def on_state(self, msg: VehicleState) -> None:
        self.state = msg
        self.try_answer()

    def on_driver(self, msg: DriverInput) -> None:
        self.front_by_stamp[_stamp_ns(msg.header.stamp)] = msg.front_wheel_angle_rad
        self.try_answer()

    def try_answer(self) -> None:
        state = self.state
        if state is None:
            return
        key = _stamp_ns(state.header.stamp)
        if key not in self.front_by_stamp:
            return  # wait for the driver input of this tick
        front = self.front_by_stamp.pop(key)
        for old in [k for k in self.front_by_stamp if k < key]:
            del self.front_by_stamp[old]
        self.state = None
        angle = self.law(state, front)
        limit = self.get_parameter("angle_limit_rad").value
        if not math.isfinite(angle):
            self.get_logger().error(f"law gave {angle} at step {state.step}; not sent")
            return
        cmd = RearSteerCommand()
        cmd.header.stamp = state.header.stamp
        cmd.header.frame_id = "base_link"
        cmd.angle_rad = min(max(angle, -limit), limit)
        cmd.law = "example_ratio"
        cmd.state_stamp = state.header.stamp
        cmd.state_step = state.step
        self.pub.publish(cmd)


def main(args=None) -> int:
    """Console entry point ``example_controller``."""
    rclpy.init(args=args)
    node = ExampleController()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
