# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The launcher's ROS side of ``fourws run``: the run description, the run nodes' statuses,
their last words on ``/rosout``, the graph's endpoints and the pause service.

The launcher takes status messages only from the run's own nodes (publisher identity from
rclpy message info): a foreign status cannot end a run. What the nodes say on ``/rosout``
(warnings and errors, by node name) is kept, so a run that stops because a node did not
answer can say what that node was waiting for.
"""

from __future__ import annotations

import faulthandler
import os
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import rclpy
from rcl_interfaces.msg import Log
from rclpy.context import Context
from rclpy.qos import qos_profile_rosout_default
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import String
from std_srvs.srv import SetBool

from fourws_ros import topics
from fourws_ros.domains import graph_env
from fourws_ros.identity import PublisherNames, drain
from fourws_ros.node_base import FourwsNode
from fourws_ros.runtime import make_executor
from fourws_run.verdict import ManeuverReport, SimReport

Role = topics.Role
#: Log levels kept from ``/rosout`` (rcl_interfaces/Log: WARN 30, ERROR 40, FATAL 50).
_KEPT_LEVELS = (Log.WARN, Log.ERROR, Log.FATAL)


#: How long the launcher's own participant may take to close, s. Fast DDS 3.2 can deadlock
#: while a participant removes a peer's endpoints on its receive thread and its event thread
#: wants the discovery lock (eProsima/Fast-DDS#6502): destroying a publisher then waits for
#: ever (seen as a run whose recorder was killed ended). The run's outcome is known by
#: then; the teardown is left to its thread.
CLOSE_TIMEOUT_S = 10.0
#: How often the launcher asks the graph for the status topics' publishers while it spins, s.
#: The run's own are named before the start (fourws_ros.startup) and a publisher not named yet
#: is looked up when its first message comes (PublisherNames.name); asked on every spin, the
#: graph queries were a quarter of the launcher's CPU in a lockstep run (a spin per status).
NAMES_REFRESH_S = 0.1
#: How long the simulator may take to answer the start request (or report running), s.
START_TIMEOUT_S = 10.0
#: The closing thread can hold the interpreter while it is stuck (rclpy's destroy calls keep
#: it): then no Python code runs again, the timeout above included, and the process hung for
#: good after a complete run (seen: a ``fourws run`` whose nodes had all exited). This much
#: later faulthandler's own thread, which needs no interpreter, writes every stack to stderr
#: and exits the process with code 1; the run's record is written before the close, s.
CLOSE_BACKSTOP_S = 5.0
#: Launcher nodes not destroyed (their participants stuck in Fast DDS, or kept, see
#: :data:`KEEP_PARTICIPANTS`), each with what it keeps held (the run's domain lease): a
#: process holding one leaves with ``os._exit`` (exiting normally would destroy them).
ABANDONED: list[tuple["LauncherNode", Any]] = []
#: Keep each run's launcher participant instead of destroying it. The command line sets it:
#: its process ends right after its command (``os._exit``), so nothing of it needs to be
#: destroyed, and a destroy that can deadlock is never attempted. A process that runs many
#: runs (the test suite, a user's script through :mod:`fourws_api`) destroys them.
KEEP_PARTICIPANTS = False
#: Arm the backstop of :data:`CLOSE_BACKSTOP_S` (faulthandler has one such timer per process:
#: the test suite, whose own per-test timer covers the same case, switches it off).
CLOSE_BACKSTOP = True
#: What :meth:`LauncherNode.close` did.
CLOSED, KEPT, STUCK = "closed", "kept", "stuck"


@dataclass
class RunState:
    """What the launcher knows of the running graph (from the run's own nodes only)."""

    sim: Any = None
    sim_final: Any = None
    maneuver: Any = None
    maneuver_end: Any = None
    recorder: Any = None
    events: list[str] = field(default_factory=list)
    foreign: int = 0
    last_advance: float = 0.0
    sim_time_s: float = 0.0
    t_start: float = 0.0
    t_end: float = 0.0
    #: The last warning or error each node said on /rosout.
    last_words: dict[str, str] = field(default_factory=dict)
    #: The law the user controller's commands name (from the bag, after the run).
    law_label: str = ""

    def sim_report(self) -> SimReport | None:
        """The simulator's final (or last) status as a :class:`SimReport`."""
        msg = self.sim_final or self.sim
        if msg is None:
            return None
        return SimReport(
            sim_time_s=float(msg.sim_time_s), max_lateness_s=float(msg.max_lateness_s),
            p99_lateness_s=float(msg.p99_lateness_s), overruns=int(msg.overruns),
            stale_commands=int(msg.stale_commands), steps=int(msg.steps),
            wall_time_s=float(getattr(msg, "wall_time_s", 0.0)),
            commands_accepted=int(msg.commands_accepted), end_reason=str(msg.end_reason),
            stop_reason=str(msg.stop_reason), final=bool(msg.final),
            rejections={str(r): int(n)
                        for r, n in zip(msg.rejected_reasons, msg.rejected_counts)})

    def maneuver_report(self) -> ManeuverReport | None:
        """The maneuver's end (or last) status as a :class:`ManeuverReport`."""
        msg = self.maneuver_end or self.maneuver
        if msg is None:
            return None
        return ManeuverReport(end=str(msg.end), event=str(msg.event),
                              done=self.maneuver_end is not None,
                              rejections={str(r): int(n) for r, n in
                                          zip(msg.rejected_reasons, msg.rejected_counts)})


class LauncherNode:
    """The launcher's ROS node on the run's domain (module docstring).

    Parameters
    ----------
    domain_id : int
    config_json : str
        The run description (``/fourws/run_config``, latched).
    writers : dict
        ROS node name of each role.
    state : RunState
        Filled by the callbacks.
    """

    def __init__(self, domain_id: int, config_json: str, writers: dict[Role, str],
                 state: RunState) -> None:
        # the domain goes to rclpy.init; the run's discovery range and DDS profile are in the
        # environment only while the participant is created: the process keeps the user's
        # (a later run in this process, or the caller, must see what the user set, not ours)
        run_env = graph_env(domain_id)
        keys = ("ROS_AUTOMATIC_DISCOVERY_RANGE", "FASTDDS_DEFAULT_PROFILES_FILE",
                "ROS_STATIC_PEERS")
        saved = {key: os.environ.get(key) for key in keys}
        try:
            for key in keys:
                if run_env.get(key):
                    os.environ[key] = run_env[key]
                else:
                    os.environ.pop(key, None)
            self.context = Context()
            rclpy.init(args=[], context=self.context, domain_id=domain_id,
                       signal_handler_options=SignalHandlerOptions.NO)
            # no parameter services: fewer entities to destroy at the close (above)
            self.node = FourwsNode(topics.NODE_NAMES[Role.LAUNCHER], context=self.context,
                                   enable_rosout=False, start_parameter_services=False)
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value
        # message info (publisher identity): rclpy's single-threaded executor or the lean one
        self.executor = make_executor(self.context, message_info=True)
        self.executor.add_node(self.node)
        self.state = state
        self.writers = writers
        self.names = PublisherNames(self.node)
        self._names_refreshed = -float("inf")  # time.monotonic() of the last refresh
        self.config_pub = self.node.create_publisher(String, topics.RUN_CONFIG,
                                                     topics.LATCHED_QOS)
        self.config_pub.publish(String(data=config_json))
        for topic, handler in ((topics.MANEUVER_STATUS, self._on_maneuver),
                               (topics.SIM_STATUS, self._on_sim),
                               (topics.RECORDER_STATUS, self._on_recorder)):
            self._subscribe(topic, handler)
        self.node.create_subscription(Log, "/rosout", self._on_rosout,
                                      qos_profile_rosout_default)
        self.pause = self.node.create_client(SetBool, topics.SRV_PAUSE)

    def _subscribe(self, topic: str, handler: Callable[[Any, Any], None]) -> None:
        """Subscribe ``handler(msg, info)``, taking every queued message per wake-up (a
        foreign node flooding a status topic cannot push the run's own messages out)."""
        msg_type = topics.message_class(topic)
        holder: list[Any] = []

        def callback(msg: Any, info: Any) -> None:
            handler(msg, info)
            drain(holder[0], msg_type, False, handler)

        holder.append(self.node.create_subscription(msg_type, topic, callback,
                                                    topics.STATUS_READ_QOS))

    def spin(self, seconds: float) -> None:
        """Run callbacks for up to ``seconds``."""
        now = time.monotonic()
        if now - self._names_refreshed >= NAMES_REFRESH_S:
            self._names_refreshed = now
            self.names.refresh(topics.MANEUVER_STATUS, topics.SIM_STATUS,
                               topics.RECORDER_STATUS)
        self.executor.spin_once(timeout_sec=seconds)

    def _from(self, topic: str, info: Any, role: Role) -> bool:
        ok = self.names.of(topic, info) == self.writers[role]
        if not ok:
            self.state.foreign += 1
        return ok

    def _on_maneuver(self, msg: Any, info: Any) -> None:
        if not self._from(topics.MANEUVER_STATUS, info, Role.MANEUVER):
            return
        self.state.maneuver = msg
        if msg.event:
            self.state.events.append(msg.event)
        if msg.done:
            self.state.maneuver_end = msg

    def _on_sim(self, msg: Any, info: Any) -> None:
        if not self._from(topics.SIM_STATUS, info, Role.SIMULATOR):
            return
        state = self.state
        if msg.sim_time_s > state.sim_time_s:
            state.last_advance = time.monotonic()
        state.sim_time_s = max(state.sim_time_s, float(msg.sim_time_s))
        state.sim = msg
        if msg.final:
            state.sim_final = msg
            state.t_end = state.t_end or time.monotonic()

    def _on_recorder(self, msg: Any, info: Any) -> None:
        if self._from(topics.RECORDER_STATUS, info, Role.RECORDER):
            self.state.recorder = msg

    def _on_rosout(self, msg: Any) -> None:
        # only the run's nodes: a foreign node cannot put words in a run's mouth
        if msg.level in _KEPT_LEVELS and msg.name in self.writers.values():
            self.state.last_words[str(msg.name)] = str(msg.msg)[:300]

    def has_endpoint(self, topic: str, kind: str, node_name: str) -> bool:
        """Whether ``node_name`` publishes (``kind`` "pub") or subscribes ``topic``."""
        infos = (self.node.get_publishers_info_by_topic(topic) if kind == "pub"
                 else self.node.get_subscriptions_info_by_topic(topic))
        return any(i.node_name == node_name for i in infos)

    def start_simulation(self) -> bool:
        """Un-pause the simulator; False if within :data:`START_TIMEOUT_S` it neither
        answered nor reported that it runs. Its answer can be lost while the request was
        taken (the simulator answered before it had matched this client's reply reader:
        rmw's "failed to send response (timeout)", seen with a foreign node flooding the
        domain); a status of the run's simulator saying it runs then is the answer."""
        future = self.pause.call_async(SetBool.Request(data=False))
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.05)
            sim = self.state.sim
            if future.done() or (sim is not None and (sim.running or sim.final)):
                return True
        return False

    def close(self, keep: Any = None, destroy: bool = False) -> str:
        """Destroy the node and its context (:data:`CLOSED`); with :data:`KEEP_PARTICIPANTS`
        and not ``destroy`` keep it instead (:data:`KEPT`); :data:`STUCK` if the destroy did
        not end within :data:`CLOSE_TIMEOUT_S`. A kept or stuck participant is left as it is,
        in :data:`ABANDONED` with ``keep`` (the run's domain lease: a next run in this process
        must not meet it). ``destroy`` is for a domain the next run must have again (the
        user's ``ROS_DOMAIN_ID``: a kept lease would refuse the second run of a demo). A
        destroy stuck holding the interpreter ends the process (:data:`CLOSE_BACKSTOP_S`)."""
        if KEEP_PARTICIPANTS and not destroy:
            ABANDONED.append((self, keep))
            return KEPT
        done = threading.Event()

        def teardown() -> None:
            self.executor.shutdown(timeout_sec=1.0)
            self.node.destroy_node()
            self.context.try_shutdown()
            done.set()

        backstop = CLOSE_BACKSTOP
        if backstop:
            faulthandler.dump_traceback_later(CLOSE_TIMEOUT_S + CLOSE_BACKSTOP_S, exit=True)
        try:
            thread = threading.Thread(target=teardown, daemon=True, name="fourws-launcher-close")
            thread.start()
            if done.wait(CLOSE_TIMEOUT_S):
                return CLOSED
        finally:
            if backstop:
                faulthandler.cancel_dump_traceback_later()
        ABANDONED.append((self, keep))
        return STUCK


__all__ = ["ABANDONED", "CLOSED", "CLOSE_BACKSTOP", "CLOSE_BACKSTOP_S", "CLOSE_TIMEOUT_S",
           "KEEP_PARTICIPANTS", "KEPT", "LauncherNode", "NAMES_REFRESH_S", "RunState",
           "START_TIMEOUT_S", "STUCK"]
