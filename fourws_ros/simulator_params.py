# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The ROS parameters of the simulator node (:mod:`fourws_ros.simulator_node`), declared with
their descriptors: units, ranges, what is read-only."""

from __future__ import annotations

from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

from fourws_ros import peers, topics

#: Shortest/longest integration step a parameter may set, s.
MIN_STEP_S, MAX_STEP_S = 1e-5, 0.1


def _frange(lo: float, hi: float) -> list[FloatingPointRange]:
    return [FloatingPointRange(from_value=lo, to_value=hi)]


def _irange(lo: int, hi: int) -> list[IntegerRange]:
    return [IntegerRange(from_value=lo, to_value=hi, step=1)]


def declare_parameters(node: Any) -> None:
    """Declare every simulator parameter on ``node``."""
    ro = dict(read_only=True)
    declare = node.declare_parameter
    declare("vehicle", "table_8_1", ParameterDescriptor(
        description="vehicle (config/vehicles name or YAML path)", **ro))
    declare("vehicle_json", "", ParameterDescriptor(
        description="the simulated vehicle as a whole vehicle-file mapping in JSON "
                    "(overrides vehicle when not empty)", **ro))
    declare("model", "8dof", ParameterDescriptor(
        description="vehicle model (fourws_sim.models name)", **ro))
    declare("tire", "", ParameterDescriptor(
        description="tire model override ('' = the vehicle file's)", **ro))
    declare("integrator", "rk4", ParameterDescriptor(description="integrator name", **ro))
    declare("integration_step_s", 1e-3, ParameterDescriptor(
        description="integration step, s",
        floating_point_range=_frange(MIN_STEP_S, MAX_STEP_S), **ro))
    declare("control_period_s", 0.01, ParameterDescriptor(
        description="control period (driver/controller tick), s; whole multiple of the "
                    "integration step", floating_point_range=_frange(MIN_STEP_S, 1.0), **ro))
    declare("state_period_s", 0.01, ParameterDescriptor(
        description="realtime: state publish period, s; whole multiple of the step",
        floating_point_range=_frange(MIN_STEP_S, 1.0), **ro))
    declare("viz_period_s", 0.02, ParameterDescriptor(
        description="odometry/IMU publish period (simulation time), s",
        floating_point_range=_frange(MIN_STEP_S, 10.0)))
    declare("status_period_s", 0.1, ParameterDescriptor(
        description="sim_status publish period (simulation time), s",
        floating_point_range=_frange(1e-3, 10.0)))
    declare("clock_mode", "lockstep", ParameterDescriptor(
        description="lockstep | realtime", **ro))
    declare("initial_speed_mps", 23.611111111111111, ParameterDescriptor(
        description="forward speed at reset, m/s", floating_point_range=_frange(0.0, 100.0)))
    declare("answer_timeout_s", 60.0, ParameterDescriptor(
        description="wall time to wait for a lockstep tick's answers (realtime: for the "
                    "first state's) before the run stops as failed (no tick runs on an "
                    "input that was not sent), s",
        floating_point_range=_frange(1e-3, 3600.0)))
    declare("recorder_timeout_s", 60.0, ParameterDescriptor(
        description="lockstep: wall time a tick may be held for the recorder (more than "
                    "its flow-control window behind) before the run stops as failed, s; "
                    "apart from answer_timeout_s, since a recorder on a slow disk has not "
                    "stopped answering",
        floating_point_range=_frange(1e-3, 3600.0)))
    declare("command_stale_periods", 10, ParameterDescriptor(
        description="realtime: a rear-steer command is fresh while the state it answers "
                    "is at most this many control periods old (simulation time); a tick "
                    "without a fresh command applies zero rear steer and is counted",
        integer_range=_irange(1, 100000)))
    declare("driver_timeout_s", 1.0, ParameterDescriptor(
        description="realtime: simulation time without a new driver input after which "
                    "the run stops (the maneuver node stopped answering), s",
        floating_point_range=_frange(1e-3, 60.0)))
    declare("startup_timeout_s", peers.STARTUP_TIMEOUT_S, ParameterDescriptor(
        description="wall time to wait for the run's other nodes before giving up with "
                    "a line naming the missing ones, s (0: wait forever)",
        floating_point_range=_frange(0.0, 86400.0), **ro))
    declare("autostart", True, ParameterDescriptor(
        description="start running once the graph is complete (false: paused until "
                    "/fourws/pause false)"))
    declare("controller_node", topics.NODE_NAMES[topics.Role.CONTROLLER], ParameterDescriptor(
        description="ROS node name of the controller (named when it stops answering; "
                    "realtime takes commands only from it)", read_only=True))
    declare("maneuver_node", topics.NODE_NAMES[topics.Role.MANEUVER], ParameterDescriptor(
        description="ROS node name of the driver (named when it stops answering; "
                    "realtime takes driver inputs only from it)", read_only=True))
    declare("exit_when_done", True, ParameterDescriptor(
        description="exit once the run has ended and everything published is delivered "
                    "(false: stay up, paused)"))
    declare("expected_state_subscribers", 0, ParameterDescriptor(
        description="wait for this many /fourws/state subscribers before the first tick "
                    "(used when expected_subscribers_json does not name the topic)",
        integer_range=_irange(0, 64), **ro))
    declare("realtime_priority", 20, ParameterDescriptor(
        description="realtime: SCHED_FIFO priority of the integration thread (1-99; 0 = "
                    "normal scheduling). Needs CAP_SYS_NICE; without it the node warns "
                    "and runs with normal priority", integer_range=_irange(0, 99),
        read_only=True))
    declare("recorder_window", 0, ParameterDescriptor(
        description="lockstep: run at most this many messages of any recorded topic "
                    "ahead of what the recorder reports stored (0 = no recorder flow "
                    "control; must stay below the stream history depth)",
        integer_range=_irange(0, topics.STREAM_DEPTH // 2), read_only=True))
    declare("maneuver_json", "", ParameterDescriptor(
        description="the run's maneuver mapping as JSON, for the course markers (its cones "
                    "and target line; '' = none)", **ro))
    declare("publish_scene", True, ParameterDescriptor(
        description="publish the car in 3D: /tf, /tf_static, /robot_description, "
                    "/fourws/markers", **ro))
    declare("path_period_s", 0.1, ParameterDescriptor(
        description="driven-path and course markers publish period (simulation time), s",
        floating_point_range=_frange(1e-3, 10.0), **ro))
    declare("end_time_s", 0.0, ParameterDescriptor(
        description="end the run at the first state at or after this simulation time (an "
                    "external driver that does not end it itself; 0 = the maneuver node "
                    "ends it), s", floating_point_range=_frange(0.0, 1e5), **ro))


__all__ = ["MAX_STEP_S", "MIN_STEP_S", "declare_parameters"]
