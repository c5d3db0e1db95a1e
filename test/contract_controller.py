# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A rear-steer controller written from docs/controller-contract.md alone (no fourws import):
the test of the contract. It reads the vehicle it controls from /fourws/run_config and runs
the zero-sideslip feed-forward of the linear single-track model on the belief vehicle,

    delta_r = -k delta_f,   k = (b - a m U^2 / (Cr L)) / (a + b m U^2 / (Cf L)),

with a = CG to front axle, b = CG to rear axle, L = a + b, m the mass, Cf/Cr the belief's axle
cornering stiffnesses and U the state's speed (the steady-state sideslip of the 2-DOF model is
zero with this ratio), clipped to the rear angle limit.

``--nan-from T`` (tests of the simulator's input checks): from simulation time T on, every
command it sends is NaN.
"""

import json
import sys

import rclpy
from fourws.msg import DriverInput, RearSteerCommand, VehicleState
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


def ratio(car: dict, speed: float) -> float:
    """k of the module docstring for the belief vehicle mapping ``car``."""
    c, t = car["chassis"], car["axle_tires"]
    a, b, m = c["cg_to_front_axle_m"], c["cg_to_rear_axle_m"], c["mass_kg"]
    cf, cr = t["cornering_stiffness_front_n_per_rad"], t["cornering_stiffness_rear_n_per_rad"]
    wheelbase = a + b
    mu2 = m * speed ** 2 / wheelbase
    return (b - a * mu2 / cr) / (a + b * mu2 / cf)


class ContractController(Node):
    def __init__(self, nan_from: float = float("inf")) -> None:
        super().__init__("my_controller")
        self.nan_from = nan_from
        self.config = None
        self.states = {}
        self.fronts = {}
        self.pub = self.create_publisher(RearSteerCommand, "/fourws/rear_steer_cmd", STREAM)
        self.create_subscription(String, "/fourws/run_config", self.on_config, LATCHED)
        self.create_subscription(VehicleState, "/fourws/state", self.on_state, STREAM)
        self.create_subscription(DriverInput, "/fourws/driver_input", self.on_driver, STREAM)
        from fourws.msg import SimulatorStatus
        self.create_subscription(SimulatorStatus, "/fourws/sim_status", self.on_status, STATUS)
        self.done = False

    def on_config(self, msg: String) -> None:
        self.config = json.loads(msg.data)
        self.answer_all()

    def on_status(self, msg) -> None:
        self.done = self.done or msg.final

    def on_state(self, msg: VehicleState) -> None:
        self.states[(msg.header.stamp.sec, msg.header.stamp.nanosec)] = msg
        self.answer_all()

    def on_driver(self, msg: DriverInput) -> None:
        self.fronts[(msg.header.stamp.sec, msg.header.stamp.nanosec)] = msg.front_wheel_angle_rad
        self.answer_all()

    def answer_all(self) -> None:
        if self.config is None:
            return
        belief = self.config["belief_vehicle"]
        limit = belief["actuators"]["rear_angle_limit_rad"]
        for key in sorted(set(self.states) & set(self.fronts)):
            state = self.states.pop(key)
            front = self.fronts.pop(key)
            angle = -ratio(belief, state.speed_mps) * front
            cmd = RearSteerCommand()
            cmd.header.stamp = state.header.stamp
            cmd.header.frame_id = "base_link"
            cmd.angle_rad = (min(max(angle, -limit), limit) if state.sim_time_s < self.nan_from
                             else float("nan"))
            cmd.law = "contract_zero_sideslip"
            cmd.state_stamp = state.header.stamp
            cmd.state_step = state.step
            self.pub.publish(cmd)


def main() -> int:
    args = list(sys.argv)
    nan_from = float("inf")
    if "--nan-from" in args:
        k = args.index("--nan-from")
        nan_from = float(args[k + 1])
        del args[k:k + 2]
    rclpy.init(args=args)
    node = ContractController(nan_from)
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
