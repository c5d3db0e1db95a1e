"""Topic names, message types and QoS profiles of the fourws graph, named once.

Every node, the launcher, the recorder and the replay take names and QoS from here. The
offline bag tools (:mod:`fourws_analysis.bag`) spell the same names and types without rclpy;
``test/test_ros_graph.py`` checks that both agree.

QoS choice (why):

* ``STREAM_QOS`` (state, driver input, rear-steer command, odometry, IMU): reliable, keep last
  :data:`STREAM_DEPTH`. Lockstep runs must not lose a single message (the simulator waits for the
  answer to each state), and the recorder may lag the simulator for a while in a fast lockstep
  run: a deep history lets it catch up instead of dropping.
* ``STATUS_QOS`` (simulator and maneuver status): reliable, keep last 100 — events (``done``,
  stop reasons) must arrive.
* ``LATCHED_QOS`` (run configuration): reliable, transient local, depth 1 — a recorder that
  joins late still gets it.
* ``CLOCK_QOS``: reliable, keep last :data:`STREAM_DEPTH` for the recorder/replay; rclpy's own
  time source subscribes best effort, which is compatible with a reliable publisher.
"""

from __future__ import annotations

from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy)

NAMESPACE = "/fourws"

STATE = f"{NAMESPACE}/state"
DRIVER_INPUT = f"{NAMESPACE}/driver_input"
REAR_STEER_CMD = f"{NAMESPACE}/rear_steer_cmd"
MANEUVER_STATUS = f"{NAMESPACE}/maneuver_status"
SIM_STATUS = f"{NAMESPACE}/sim_status"
ODOM = f"{NAMESPACE}/odom"
IMU = f"{NAMESPACE}/imu"
RUN_CONFIG = f"{NAMESPACE}/run_config"
CLOCK = "/clock"
#: Recorder -> simulator flow control in lockstep (``std_msgs/UInt64``: number of
#: ``/fourws/state`` messages written so far). Not recorded.
RECORDER_PROGRESS = f"{NAMESPACE}/recorder_progress"

#: Services of the simulator (``std_srvs/srv/Trigger`` and ``std_srvs/srv/SetBool``).
SRV_RESET = f"{NAMESPACE}/reset"
SRV_PAUSE = f"{NAMESPACE}/pause"

#: Message type of each topic, in rosbags/rosbag2 spelling ``package/msg/Name``.
TOPIC_TYPES: dict[str, str] = {
    STATE: "fourws_msgs/msg/VehicleState",
    DRIVER_INPUT: "fourws_msgs/msg/DriverInput",
    REAR_STEER_CMD: "fourws_msgs/msg/RearSteerCommand",
    MANEUVER_STATUS: "fourws_msgs/msg/ManeuverStatus",
    SIM_STATUS: "fourws_msgs/msg/SimulatorStatus",
    ODOM: "nav_msgs/msg/Odometry",
    IMU: "sensor_msgs/msg/Imu",
    RUN_CONFIG: "std_msgs/msg/String",
    CLOCK: "rosgraph_msgs/msg/Clock",
    RECORDER_PROGRESS: "std_msgs/msg/UInt64",
}

#: Frames (REP-105): earth-fixed ``odom``, body ``base_link`` (x forward, y left, z up).
FRAME_ODOM = "odom"
FRAME_BODY = "base_link"

#: History depth of the message streams (messages). 2000 is 2 s of a 1 kHz stream, or 1 s of
#: a 20x lockstep run at 100 Hz: the longest stall of the recorder that loses nothing.
STREAM_DEPTH = 2000
STATUS_DEPTH = 100

STREAM_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=STREAM_DEPTH,
                        reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.VOLATILE)
STATUS_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=STATUS_DEPTH,
                        reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.VOLATILE)
LATCHED_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
CLOCK_QOS = STREAM_QOS

#: QoS of every topic (publishers and subscribers use the same profile).
TOPIC_QOS: dict[str, QoSProfile] = {
    STATE: STREAM_QOS,
    DRIVER_INPUT: STREAM_QOS,
    REAR_STEER_CMD: STREAM_QOS,
    MANEUVER_STATUS: STATUS_QOS,
    SIM_STATUS: STATUS_QOS,
    ODOM: STREAM_QOS,
    IMU: STREAM_QOS,
    RUN_CONFIG: LATCHED_QOS,
    CLOCK: CLOCK_QOS,
    RECORDER_PROGRESS: STATUS_QOS,
}


def message_class(topic: str) -> type:
    """The rclpy message class of a graph topic (imports the generated module lazily).

    Parameters
    ----------
    topic : str
        One of the topic names above.

    Raises
    ------
    KeyError
        If ``topic`` is not a graph topic.
    """
    import importlib

    package, _, name = TOPIC_TYPES[topic].split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)
