# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""QoS profiles of the fourws graph, on the names of :mod:`fourws_run.interface`.

Topic names, message types, frames and roles are defined once in :mod:`fourws_run.interface`
(no rclpy there, so the bag tools read the same names); this module adds what only the ROS
side needs: QoS profiles and the rclpy message classes. It re-exports the names so node code
reads ``topics.STATE``.

QoS choice (why):

* ``STREAM_QOS`` (state, driver input, rear-steer command, odometry, IMU): reliable,
  **transient local**, keep last :data:`STREAM_DEPTH`. Lockstep runs must not lose a single
  message: the simulator waits for the answers to each state, and it never runs more than the
  flow-control window (:data:`fourws_ros.node_params.RECORDER_WINDOW`, well below this depth)
  ahead of what the recorder has stored, so no message can be pushed out of a queue before it
  is recorded. Durability makes delivery independent of discovery order: a volatile writer
  sends a message only to the readers it has matched when it writes, and never again to one it
  matches later, while a transient-local writer hands a late-matched transient-local reader its
  history. The graph lists a subscription before its writers have matched it (under load for
  seconds), so with volatile streams a first state, driver input or command could leave before
  the recorder's or the controller's reader was matched, and never arrive (a lockstep run then
  stalls at t = 0). Every fourws reader of these topics is transient local, so no node -- a
  user's controller or driver written from the contracts included -- needs to know who else is
  on the graph before its first message. A user's *reader* may stay volatile (compatible); the
  built-in writers also hold their first message until their subscribers have matched
  (:class:`fourws_ros.reporting.MatchWait`), which covers such readers. A user's *writer* must be
  transient local: a volatile one cannot match the transient-local readers (the simulator says
  so, naming the topic and the node).
* ``CLOCK_QOS`` (``/clock``): reliable, volatile: a late ``use_sim_time`` node must start at the
  current time, not replay the past.
* ``EVENT_QOS`` (simulator and maneuver status, which the recorder stores and counts): reliable,
  **transient local**, keep last :data:`STATUS_DEPTH` -- the events (``done``, final counts)
  must arrive, and the recorder must hold every one: in a graph started by hand nobody tells
  the writers to wait for the recorder, and a volatile maneuver status published before the
  recorder's reader had matched was never sent again (the recorder then waited for good for
  the 6 statuses of the run's first 0.6 s, seen in 2 of 8 hand-started runs). Their other
  readers (simulator, controller, launcher) stay volatile (``STATUS_QOS``): they need what
  comes from now on, which a transient-local writer serves too.
* ``STATUS_QOS`` (the recorder's status, and the volatile readers of the two above): reliable,
  keep last :data:`STATUS_DEPTH`.
* ``LATCHED_QOS`` (run and node configuration, ``/tf_static``, ``/robot_description``):
  reliable, transient local, depth 1 per publisher -- a recorder, RViz or Foxglove that joins
  late still gets them (what tf2's static listener and robot_state_publisher use).
* ``/tf`` and ``/fourws/markers`` are streams of the simulator like the state (``STREAM_QOS``):
  the recorder must not miss the first transforms either. tf2's listeners and RViz subscribe
  reliable and volatile, which a transient-local writer serves too.
* **What fourws' own nodes read with** (``READ_QOS``, ``STREAM_READ_QOS``, ``STATUS_READ_QOS``,
  ``LATCHED_RECORD_QOS``): the topic's reliability and durability, but **keep all**. A
  keep-last reader holds the last N messages of all its writers together (ROS topics have no
  keys: one instance), so a foreign node flooding a topic of the run's domain pushes the run's
  own messages out of a reader that is starved for a moment: a launcher beside two CPU hogs
  lost the maneuver's one final status among 1000 foreign 'done' statuses and failed a good
  run ("the simulation ended without the maneuver's end"). A keep-all reader never drops what
  it received; when its resource limit is reached it refuses new samples, and a reliable
  writer sends them again later, so the flood is slowed, not the run's message lost. Writers
  stay keep last (a keep-all writer would block on a stopped reader).
* ``DRIVE_QOS`` (``/drive``, ``/joy``: inputs from another stack or a gamepad, read by the
  fourws driver nodes): reliable, volatile, keep last 10 -- what an F1TENTH stack, the
  ``joy`` node and ``ros2 topic pub`` publish with (a reliable reader does not match a
  best-effort writer: a driver that publishes best effort is told so by its own graph tools).
"""

from __future__ import annotations

import importlib

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from fourws_run.interface import (CLOCK, DRIVE, DRIVER_INPUT, EXTERNAL_TOPIC_TYPES, FRAME_BODY,
                                  FRAME_ODOM, IMU, JOY, LATCHED_TOPICS, MANEUVER_STATUS,
                                  MARKERS, NAMESPACE, NODE_CONFIG, NODE_NAMES, ODOM,
                                  REAR_STEER_CMD, RECORDED_TOPICS, RECORDER_STATUS,
                                  ROBOT_DESCRIPTION, RUN_CONFIG, SIM_STATUS, SRV_PAUSE,
                                  SRV_RESET, STATE, TF, TF_STATIC, TOPIC_TYPES, WRITER_ROLES,
                                  Role)

#: History depth of the message streams (messages): 2 s of a 1 kHz stream.
STREAM_DEPTH = 2000
#: History depth of the status topics (messages).
STATUS_DEPTH = 1000

STREAM_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=STREAM_DEPTH,
                        reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.TRANSIENT_LOCAL)
STATUS_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=STATUS_DEPTH,
                        reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.VOLATILE)
EVENT_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=STATUS_DEPTH,
                       reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
LATCHED_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
CLOCK_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=STREAM_DEPTH,
                       reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.VOLATILE)
DRIVE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                       reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.VOLATILE)


def keep_all(profile: QoSProfile) -> QoSProfile:
    """``profile``'s reliability and durability with a keep-all history: what fourws' nodes
    read the run's topics with (module docstring)."""
    return QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=profile.reliability,
                      durability=profile.durability)


STREAM_READ_QOS = keep_all(STREAM_QOS)
STATUS_READ_QOS = keep_all(STATUS_QOS)
#: What a recorder subscribes latched topics with: transient local like the publishers, but
#: keep all, since several nodes publish on one latched topic (``/fourws/node_config``) and a
#: depth-1 reader would keep only the last of them.
LATCHED_RECORD_QOS = keep_all(LATCHED_QOS)

#: QoS of every topic (publishers and subscribers use the same profile).
TOPIC_QOS: dict[str, QoSProfile] = {
    STATE: STREAM_QOS,
    DRIVER_INPUT: STREAM_QOS,
    REAR_STEER_CMD: STREAM_QOS,
    MANEUVER_STATUS: EVENT_QOS,
    SIM_STATUS: EVENT_QOS,
    ODOM: STREAM_QOS,
    IMU: STREAM_QOS,
    RUN_CONFIG: LATCHED_QOS,
    NODE_CONFIG: LATCHED_QOS,
    CLOCK: CLOCK_QOS,
    RECORDER_STATUS: STATUS_QOS,
    TF: STREAM_QOS,
    TF_STATIC: LATCHED_QOS,
    ROBOT_DESCRIPTION: LATCHED_QOS,
    MARKERS: STREAM_QOS,
    DRIVE: DRIVE_QOS,
    JOY: DRIVE_QOS,
}
#: What fourws' nodes read each topic of the run with (module docstring); the external
#: drivers' topics keep their usual keep-last 10.
READ_QOS: dict[str, QoSProfile] = {
    topic: (LATCHED_RECORD_QOS if qos is LATCHED_QOS else qos if qos is DRIVE_QOS
            else keep_all(qos)) for topic, qos in TOPIC_QOS.items()}
assert set(TOPIC_QOS) == set(TOPIC_TYPES) | set(EXTERNAL_TOPIC_TYPES)
assert all(TOPIC_QOS[t] is LATCHED_QOS for t in LATCHED_TOPICS)


def message_class(topic: str) -> type:
    """The rclpy message class of a graph topic (imports the generated module lazily, so a
    missing interface package is reported by the node that needs it).

    Parameters
    ----------
    topic : str
        One of the topic names of :mod:`fourws_run.interface`.

    Raises
    ------
    KeyError
        If ``topic`` is not a graph topic.
    """
    package, _, name = {**TOPIC_TYPES, **EXTERNAL_TOPIC_TYPES}[topic].split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


__all__ = ["CLOCK", "CLOCK_QOS", "DRIVE", "DRIVER_INPUT", "DRIVE_QOS", "EVENT_QOS", "FRAME_BODY",
           "FRAME_ODOM", "IMU", "JOY", "LATCHED_QOS", "LATCHED_RECORD_QOS", "MANEUVER_STATUS",
           "MARKERS", "NAMESPACE", "NODE_CONFIG", "NODE_NAMES", "ODOM", "READ_QOS",
           "REAR_STEER_CMD", "RECORDED_TOPICS", "RECORDER_STATUS", "ROBOT_DESCRIPTION",
           "RUN_CONFIG", "Role", "SIM_STATUS", "SRV_PAUSE", "SRV_RESET", "STATE", "STATUS_DEPTH",
           "STATUS_QOS", "STATUS_READ_QOS", "STREAM_DEPTH", "STREAM_QOS", "STREAM_READ_QOS", "TF",
           "TF_STATIC", "TOPIC_QOS", "TOPIC_TYPES", "WRITER_ROLES", "keep_all", "message_class"]
