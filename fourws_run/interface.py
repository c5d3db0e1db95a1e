# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The interface of the fourws graph, named once: topics, message types, frames, roles.

Everything that crosses a process boundary is spelled here and nowhere else: the ROS layer
(:mod:`fourws_ros.topics` adds QoS profiles to these names), the recorder, the bag reader and
writer, the codecs and the run accounting all import it. It imports no rclpy, so the offline
tools and the tests read the same names.

Roles
-----
A run has one node per :class:`Role`. Each topic has the roles that may publish it
(:data:`WRITER_ROLES`); a message on a topic from any other publisher does not belong to the
run (the recorder does not store it, it is counted as foreign).
"""

from __future__ import annotations

import enum
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.typesys import get_types_from_msg

from fourws_sim.errors import FourwsError
from fourws_sim.params import N_WHEELS, find_resource_dir

NAMESPACE = "/fourws"

STATE = f"{NAMESPACE}/state"
DRIVER_INPUT = f"{NAMESPACE}/driver_input"
REAR_STEER_CMD = f"{NAMESPACE}/rear_steer_cmd"
MANEUVER_STATUS = f"{NAMESPACE}/maneuver_status"
SIM_STATUS = f"{NAMESPACE}/sim_status"
ODOM = f"{NAMESPACE}/odom"
IMU = f"{NAMESPACE}/imu"
#: The whole run description (``std_msgs/String``, JSON of :class:`fourws_run.config.RunConfig`),
#: latched, published by the launcher of ``fourws run``.
RUN_CONFIG = f"{NAMESPACE}/run_config"
#: What each node runs with (``std_msgs/String``, JSON ``{"node", "role", "config"}``), latched,
#: one message per node: a graph started by hand is self-describing too.
NODE_CONFIG = f"{NAMESPACE}/node_config"
CLOCK = "/clock"
#: Recorder progress and accounting (``fourws/msg/RecorderStatus``); lockstep flow control.
#: Not recorded.
RECORDER_STATUS = f"{NAMESPACE}/recorder_status"
#: The car in 3D (REP-105 names): the frames of :data:`FRAMES` at the state rate, the fixed
#: offsets latched, the URDF of the simulated vehicle (``std_msgs/String``, latched), the
#: tire forces, velocity, sideslip, path and course as markers.
TF = "/tf"
TF_STATIC = "/tf_static"
ROBOT_DESCRIPTION = "/robot_description"
MARKERS = f"{NAMESPACE}/markers"

#: Services of the simulator (``std_srvs/srv/Trigger`` and ``std_srvs/srv/SetBool``).
SRV_RESET = f"{NAMESPACE}/reset"
SRV_PAUSE = f"{NAMESPACE}/pause"

#: ROS package of the fourws message definitions (``msg/*.msg``): the ``fourws`` package itself
#: generates them (one ament_cmake package, see docs/architecture.md).
MSG_PACKAGE = "fourws"
#: Earlier name of the message package (a separate ``fourws_msgs`` interface package); bags
#: recorded with it still decode (the bag tools register the definitions under both names).
LEGACY_MSG_PACKAGES: tuple[str, ...] = ("fourws_msgs",)
#: Folder with the fourws ``.msg`` definitions (``share/fourws/msg`` once installed).
MSG_DIR = find_resource_dir(Path(__file__).resolve().parent.parent / "msg", MSG_PACKAGE, "msg",
                            "*.msg")

#: Message type of each topic, in rosbag2 spelling ``package/msg/Name``.
TOPIC_TYPES: dict[str, str] = {
    STATE: f"{MSG_PACKAGE}/msg/VehicleState",
    DRIVER_INPUT: f"{MSG_PACKAGE}/msg/DriverInput",
    REAR_STEER_CMD: f"{MSG_PACKAGE}/msg/RearSteerCommand",
    MANEUVER_STATUS: f"{MSG_PACKAGE}/msg/ManeuverStatus",
    SIM_STATUS: f"{MSG_PACKAGE}/msg/SimulatorStatus",
    ODOM: "nav_msgs/msg/Odometry",
    IMU: "sensor_msgs/msg/Imu",
    RUN_CONFIG: "std_msgs/msg/String",
    NODE_CONFIG: "std_msgs/msg/String",
    CLOCK: "rosgraph_msgs/msg/Clock",
    RECORDER_STATUS: f"{MSG_PACKAGE}/msg/RecorderStatus",
    TF: "tf2_msgs/msg/TFMessage",
    TF_STATIC: "tf2_msgs/msg/TFMessage",
    ROBOT_DESCRIPTION: "std_msgs/msg/String",
    MARKERS: "visualization_msgs/msg/MarkerArray",
}
#: Topics of other stacks that fourws's driver nodes read (not the run's own, so not recorded
#: and not in :data:`TOPIC_TYPES`; the driver input they become is): an Ackermann command as
#: F1TENTH stacks and f1tenth_gym_ros publish it, and a gamepad's ``joy`` node.
DRIVE = "/drive"
JOY = "/joy"
EXTERNAL_TOPIC_TYPES: dict[str, str] = {
    DRIVE: "ackermann_msgs/msg/AckermannDriveStamped",
    JOY: "sensor_msgs/msg/Joy",
}
#: Topics whose messages are latched (transient local): a late subscriber still gets them.
LATCHED_TOPICS = (RUN_CONFIG, NODE_CONFIG, TF_STATIC, ROBOT_DESCRIPTION)
#: Topics recorded by default: every graph topic but ``/clock`` (it repeats the state stamps)
#: and the recorder's own status.
RECORDED_TOPICS: tuple[str, ...] = tuple(t for t in TOPIC_TYPES
                                         if t not in (CLOCK, RECORDER_STATUS))

#: Frames (REP-105): earth-fixed ``odom``, body ``base_link`` (x forward, y left, z up).
FRAME_ODOM = "odom"
FRAME_BODY = "base_link"

#: Wheel count and order of every per-wheel field (FL, FR, RL, RR).
WHEELS = ("FL", "FR", "RL", "RR")
assert len(WHEELS) == N_WHEELS

#: The car's frames on ``/tf`` and ``/tf_static`` and the links of its URDF
#: (:mod:`fourws_run.scene`, :mod:`fourws_run.urdf`). ``base_link`` stays parallel to the
#: road (REP-105 for a ground vehicle: the frame the wheels, which do not roll with the body,
#: hang off); ``body`` is the sprung mass, rolled about the roll axis.
FRAME_SPRUNG = "body"
#: Per wheel (in :data:`WHEELS` order): the fixed wheel-centre mount on ``base_link``
#: (``/tf_static``), the steer frame turned by the applied road-wheel angle (the tire frame of
#: the forces) and the wheel turned by its spin angle.
FRAME_MOUNT = tuple(f"{w.lower()}_mount" for w in WHEELS)
FRAME_STEER = tuple(f"{w.lower()}_steer" for w in WHEELS)
FRAME_WHEEL = tuple(f"{w.lower()}_wheel" for w in WHEELS)
#: Every frame the simulator publishes, parents before children.
FRAMES = (FRAME_ODOM, FRAME_BODY, FRAME_SPRUNG, *FRAME_MOUNT, *FRAME_STEER, *FRAME_WHEEL)

#: Fields of ``VehicleState`` that describe the message rather than the vehicle (the
#: simulator fills them from its clock and model name); every other field is a model output.
STATE_ENVELOPE = ("header", "step", "sim_time_s", "model")


class MessageDefinitionError(FourwsError):
    """A ``.msg`` definition fourws cannot map onto its data."""


def state_output_fields(path: Path | None = None) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The model outputs a ``VehicleState`` definition carries: (float64 fields,
    float64[N_WHEELS] fields), each in message order.

    Parameters
    ----------
    path : Path, optional
        The definition; default ``msg/VehicleState.msg``.

    Raises
    ------
    MessageDefinitionError
        A field outside :data:`STATE_ENVELOPE` of another type (the simulator's outputs are
        floats and per-wheel float arrays).
    """
    path = MSG_DIR / "VehicleState.msg" if path is None else path
    msgtype = TOPIC_TYPES[STATE]
    _, fields = get_types_from_msg(path.read_text(), msgtype)[msgtype]
    scalars: list[str] = []
    wheels: list[str] = []
    for name, (kind, detail) in fields:
        if name in STATE_ENVELOPE:
            continue
        if kind == Nodetype.BASE and detail[0] == "float64":
            scalars.append(name)
        elif (kind == Nodetype.ARRAY and detail[0] == (Nodetype.BASE, ("float64", 0))
              and detail[1] == N_WHEELS):
            wheels.append(name)
        else:
            raise MessageDefinitionError(
                f"{path}: field {name!r} is neither float64 nor float64[{N_WHEELS}] (the "
                "simulator's outputs are floats and per-wheel float arrays)")
    return tuple(scalars), tuple(wheels)


_STATE_FIELDS = state_output_fields()
#: Scalar float fields of ``VehicleState`` taken from ``Simulator.outputs()``, message order
#: (read from ``msg/VehicleState.msg``).
STATE_SCALARS = _STATE_FIELDS[0]
#: Per-wheel (``float64[4]``) fields of ``VehicleState``, message order (same source).
STATE_WHEELS = _STATE_FIELDS[1]


class Role(str, enum.Enum):
    """The nodes of a run."""

    SIMULATOR = "simulator"
    MANEUVER = "maneuver"
    CONTROLLER = "controller"
    RECORDER = "recorder"
    LAUNCHER = "launcher"


#: Default ROS node name of each role (a user controller may take another name).
NODE_NAMES: dict[Role, str] = {
    Role.SIMULATOR: "fourws_simulator",
    Role.MANEUVER: "fourws_maneuver",
    Role.CONTROLLER: "fourws_controller",
    Role.RECORDER: "fourws_recorder",
    Role.LAUNCHER: "fourws_launcher",
}

#: The roles that publish each topic; anything else on the topic is foreign to the run.
WRITER_ROLES: dict[str, tuple[Role, ...]] = {
    STATE: (Role.SIMULATOR,),
    ODOM: (Role.SIMULATOR,),
    IMU: (Role.SIMULATOR,),
    SIM_STATUS: (Role.SIMULATOR,),
    CLOCK: (Role.SIMULATOR,),
    DRIVER_INPUT: (Role.MANEUVER,),
    MANEUVER_STATUS: (Role.MANEUVER,),
    REAR_STEER_CMD: (Role.CONTROLLER,),
    RUN_CONFIG: (Role.LAUNCHER,),
    NODE_CONFIG: (Role.SIMULATOR, Role.MANEUVER, Role.CONTROLLER),
    RECORDER_STATUS: (Role.RECORDER,),
    TF: (Role.SIMULATOR,),
    TF_STATIC: (Role.SIMULATOR,),
    ROBOT_DESCRIPTION: (Role.SIMULATOR,),
    MARKERS: (Role.SIMULATOR,),
}
assert set(WRITER_ROLES) == set(TOPIC_TYPES)

#: Topics whose publishers report their published counts in their status messages (the
#: simulator's ``SimulatorStatus`` and the maneuver's ``ManeuverStatus``); the controller's
#: count is its publisher's sequence number (:mod:`fourws_run.accounting`).
SIMULATOR_COUNTED = (STATE, ODOM, IMU, SIM_STATUS, NODE_CONFIG, TF, TF_STATIC,
                     ROBOT_DESCRIPTION, MARKERS)
MANEUVER_COUNTED = (DRIVER_INPUT, MANEUVER_STATUS, NODE_CONFIG)

NS_PER_S = 1_000_000_000


def time_to_ns(time_s: float) -> int:
    """Simulation time in s -> integer ns (rounded): the ``header.stamp`` of a message."""
    return int(round(float(time_s) * NS_PER_S))


def times_to_ns(time_s: Any) -> Any:
    """:func:`time_to_ns` of every element of an array (int64 array; the same rounding:
    half to even of the float64 product)."""
    product = np.asarray(time_s, dtype=np.float64) * NS_PER_S
    return np.rint(product).astype(np.int64)


__all__ = [
    "CLOCK", "DRIVE", "DRIVER_INPUT", "EXTERNAL_TOPIC_TYPES", "FRAMES", "FRAME_BODY",
    "FRAME_MOUNT", "FRAME_ODOM",
    "FRAME_SPRUNG", "FRAME_STEER", "FRAME_WHEEL", "IMU", "JOY", "LATCHED_TOPICS", "MARKERS",
    "LEGACY_MSG_PACKAGES", "MANEUVER_COUNTED", "MANEUVER_STATUS", "MSG_DIR", "MSG_PACKAGE",
    "MessageDefinitionError", "NAMESPACE", "NODE_CONFIG", "NODE_NAMES", "NS_PER_S", "N_WHEELS",
    "ODOM", "REAR_STEER_CMD", "RECORDED_TOPICS", "RECORDER_STATUS", "ROBOT_DESCRIPTION",
    "RUN_CONFIG", "Role",
    "SIMULATOR_COUNTED", "SIM_STATUS", "SRV_PAUSE", "SRV_RESET", "STATE", "STATE_ENVELOPE",
    "STATE_SCALARS", "STATE_WHEELS", "TF", "TF_STATIC", "TOPIC_TYPES", "WHEELS",
    "WRITER_ROLES",
    "state_output_fields", "time_to_ns", "times_to_ns",
]
