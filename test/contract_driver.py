# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A driver written from docs/driver-contract.md alone (no fourws import but its messages):
the test of the contract. For every state it answers one DriverInput stamped with the state's
stamp: a steering sine of the state's exact time,

    front_wheel_angle_rad = 0.02 sin(2 pi 0.5 t),

the hand wheel at the steering ratio of /fourws/run_config's vehicle, and a constant drive
torque of 40 N m on each rear wheel (no brake). It stops at the simulator's final status.
"""

import json
import math
import sys

import rclpy
from fourws.msg import DriverInput, SimulatorStatus, VehicleState
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

STREAM = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=2000,
                    reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.TRANSIENT_LOCAL)
LATCHED = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                     reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
STATUS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                    reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)


def steer(t: float) -> float:
    return 0.02 * math.sin(2 * math.pi * 0.5 * t)


class ContractDriver(Node):
    def __init__(self) -> None:
        super().__init__("my_driver")
        self.ratio = None
        self.pending = []
        self.done = False
        self.pub = self.create_publisher(DriverInput, "/fourws/driver_input", STREAM)
        self.create_subscription(String, "/fourws/run_config", self.on_config, LATCHED)
        self.create_subscription(VehicleState, "/fourws/state", self.on_state, STREAM)
        self.create_subscription(SimulatorStatus, "/fourws/sim_status", self.on_status, STATUS)

    def on_config(self, msg: String) -> None:
        steering = json.loads(msg.data)["vehicle"].get("steering") or {}
        self.ratio = float(steering.get("ratio", 1.0))
        for state in self.pending:
            self.answer(state)
        self.pending = []

    def on_state(self, state: VehicleState) -> None:
        if self.ratio is None:
            self.pending.append(state)  # the ratio comes with the run description
        else:
            self.answer(state)

    def answer(self, state: VehicleState) -> None:
        msg = DriverInput()
        msg.header.stamp = state.header.stamp
        msg.header.frame_id = "base_link"
        delta = steer(state.sim_time_s)
        msg.front_wheel_angle_rad = delta
        msg.steering_wheel_angle_rad = delta * self.ratio
        msg.drive_torque_nm = [0.0, 0.0, 40.0, 40.0]
        self.pub.publish(msg)

    def on_status(self, msg: SimulatorStatus) -> None:
        if msg.final:
            self.done = True


def main() -> int:
    rclpy.init(args=sys.argv)
    node = ContractDriver()
    try:
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.1)
    except KeyboardInterrupt:
        pass
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
