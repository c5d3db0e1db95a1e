# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A rogue ROS node for the fault tests: publishes what no node of a fourws run sends.

Run as ``python rogue_node.py KIND SECONDS`` on the run's ROS domain; ``KIND``:

* ``garbage`` -- states with a simulation time of 1e6 s, NaN and far-future states, commands
  with future stamps and impossible angles, a 100 rad driver input, a ``done`` maneuver
  status for no state of the run, a final simulator status at t = 1e6 s, a flood of each, for
  ``SECONDS``;
* ``mimic`` -- answers every state of the run with a plausible driver input and rear-steer
  command (a second publisher where one is expected);
* ``done`` -- from the run's 200th state on, a ``done`` maneuver status stamped with each
  state (as the maneuver node ends a run);
* ``clock`` -- copies of the run's states, one step ahead of each (on the run's clock);
* ``driver_grid`` -- 100 rad driver inputs stamped on the run's control grid (every 10 ms of
  the first 60 s, cycling), so some carry the stamp of a state the run is answering.

Once every publisher of its kind has matched every subscriber of its topic that the graph
shows from the run's nodes (at least one), and a rogue that answers states has had one, it
prints ``rogue met the run``: the fault tests hold the run (its maneuver node stopped) until
then, so the attack meets the run however long discovery takes on a loaded machine.
"""

from __future__ import annotations

import math
import sys
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor

from fourws_ros import conversions, topics
from fourws_sim.drivers import DriverCommand


def main(kind: str, seconds: float) -> int:
    rclpy.init()
    node = rclpy.create_node("rogue")
    msg = topics.message_class
    pubs = {t: node.create_publisher(msg(t), t, topics.TOPIC_QOS[t])
            for t in (topics.STATE, topics.DRIVER_INPUT, topics.REAR_STEER_CMD,
                      topics.MANEUVER_STATUS, topics.SIM_STATUS)}
    sent = 0
    print("rogue ready", flush=True)
    end = time.monotonic() + seconds
    used = {"mimic": (topics.DRIVER_INPUT, topics.REAR_STEER_CMD),
            "done": (topics.MANEUVER_STATUS,), "clock": (topics.STATE,),
            "driver_grid": (topics.DRIVER_INPUT,)}.get(kind, tuple(pubs))
    answers = kind in ("mimic", "done", "clock")
    heard = [False]  # a state of the run reached the rogue (kinds that answer states)
    met = [False]

    def check_met() -> None:
        """Print ``rogue met the run`` once (module docstring)."""
        if met[0] or (answers and not heard[0]):
            return
        for topic in used:
            run_subs = [i for i in node.get_subscriptions_info_by_topic(topic)
                        if i.node_name.startswith("fourws")]
            if not run_subs or pubs[topic].get_subscription_count() < len(run_subs):
                return
        met[0] = True
        print("rogue met the run", flush=True)
    if kind == "mimic":
        def answer(state) -> None:
            nonlocal sent
            heard[0] = True
            pubs[topics.DRIVER_INPUT].publish(
                conversions.driver_msg(DriverCommand(0.5, 0.03), state.sim_time_s))
            cmd = msg(topics.REAR_STEER_CMD)()
            cmd.header.stamp = state.header.stamp
            cmd.angle_rad = 0.08
            cmd.law = "rogue"
            cmd.state_stamp = state.header.stamp
            cmd.state_step = state.step
            pubs[topics.REAR_STEER_CMD].publish(cmd)
            sent += 2
        node.create_subscription(msg(topics.STATE), topics.STATE, answer, topics.STREAM_QOS)
    elif kind == "done":
        def finish(state) -> None:
            nonlocal sent
            heard[0] = True
            if state.step >= 200 * 10:
                status = msg(topics.MANEUVER_STATUS)()
                status.header.stamp = state.header.stamp
                status.maneuver = "step_steer_85kmh"
                status.phase = "done"
                status.done = True
                status.end = "completed"
                status.event = "completed"
                pubs[topics.MANEUVER_STATUS].publish(status)
                sent += 1
        node.create_subscription(msg(topics.STATE), topics.STATE, finish, topics.STREAM_QOS)
    elif kind == "clock":
        own: set[int] = set()

        def ahead(state) -> None:
            nonlocal sent
            heard[0] = True
            if state.step in own:
                return  # its own copy
            state.step += 10
            own.add(state.step)
            state.sim_time_s = state.step * 1e-3
            conversions.set_stamp(state.header.stamp, state.sim_time_s)
            pubs[topics.STATE].publish(state)
            sent += 1
        node.create_subscription(msg(topics.STATE), topics.STATE, ahead, topics.STREAM_QOS)
    elif kind == "driver_grid":
        k = 0
        while time.monotonic() < end:
            k += 1
            pubs[topics.DRIVER_INPUT].publish(
                conversions.driver_msg(DriverCommand(1600.0, 100.0), 0.01 * (k % 6000)))
            sent += 1
            if k % 200 == 0:
                check_met()
            time.sleep(0.0005)
    if kind in ("mimic", "done", "clock"):
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
            check_met()
    elif kind != "driver_grid":
        k = 0
        while time.monotonic() < end:
            k += 1
            state = msg(topics.STATE)()
            conversions.set_stamp(state.header.stamp, 1e6 + k)
            state.sim_time_s = 1e6 + k
            state.step = 10 ** 9 + k
            state.yaw_rate_radps = math.nan if k % 2 else 1e300
            pubs[topics.STATE].publish(state)
            cmd = msg(topics.REAR_STEER_CMD)()
            conversions.set_stamp(cmd.state_stamp, 1e5 + k)  # a state of the future
            cmd.state_step = 10 ** 8 + k
            cmd.angle_rad = 0.08 if k % 3 else math.nan
            cmd.law = "rogue"
            pubs[topics.REAR_STEER_CMD].publish(cmd)
            pubs[topics.DRIVER_INPUT].publish(
                conversions.driver_msg(DriverCommand(1600.0, 100.0), 1e5 + k))
            status = msg(topics.MANEUVER_STATUS)()
            conversions.set_stamp(status.header.stamp, 1e6 + k)
            status.done = True
            status.end = "completed"
            pubs[topics.MANEUVER_STATUS].publish(status)
            final = msg(topics.SIM_STATUS)()
            conversions.set_stamp(final.header.stamp, 1e6 + k)
            final.sim_time_s = 1e6 + k
            final.final = True
            final.end_reason = "maneuver completed"
            pubs[topics.SIM_STATUS].publish(final)
            sent += 5
            if k % 50 == 0:
                check_met()
            time.sleep(0.002)
    print(f"rogue {kind}: sent {sent} messages", flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], float(sys.argv[2])))
