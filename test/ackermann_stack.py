# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Another stack's Ackermann publisher, as docs/driver-contract.md asks it of a lockstep run
(no fourws import but its messages): for every state one AckermannDriveStamped on /drive
stamped with the state's stamp, steering a sine of the state's exact time at 20 m/s,

    steering_angle = 0.03 sin(2 pi 0.4 t),   speed = 20.

/drive is volatile (as F1TENTH stacks publish it), so it publishes once the driver's
subscription has matched. It stops at the simulator's final status.
"""

import math
import sys

import rclpy
from ackermann_msgs.msg import AckermannDriveStamped
from fourws.msg import SimulatorStatus, VehicleState
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

STREAM = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=2000,
                    reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.TRANSIENT_LOCAL)
STATUS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                    reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)


class Stack(Node):
    def __init__(self) -> None:
        super().__init__("my_stack")
        self.pub = self.create_publisher(AckermannDriveStamped, "/drive", 10)
        self.pending = []
        self.done = False
        self.create_subscription(VehicleState, "/fourws/state", self.on_state, STREAM)
        self.create_subscription(SimulatorStatus, "/fourws/sim_status", self.on_status, STATUS)

    def on_state(self, state: VehicleState) -> None:
        self.pending.append(state)
        self.flush()

    def flush(self) -> None:
        if self.pub.get_subscription_count() == 0:
            return  # volatile: a message before the driver matched would be lost
        for state in self.pending:
            msg = AckermannDriveStamped()
            msg.header.stamp = state.header.stamp
            msg.drive.steering_angle = 0.03 * math.sin(2 * math.pi * 0.4 * state.sim_time_s)
            msg.drive.speed = 20.0
            self.pub.publish(msg)
        self.pending = []

    def on_status(self, msg: SimulatorStatus) -> None:
        if msg.final:
            self.done = True


def main() -> int:
    rclpy.init(args=sys.argv)
    node = Stack()
    try:
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.05)
            node.flush()
    except KeyboardInterrupt:
        pass
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
