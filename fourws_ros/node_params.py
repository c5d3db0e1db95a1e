# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The ROS parameters of each node of a run, from its :class:`~fourws_run.config.RunConfig`.

:func:`node_parameters` is the only translation from a run description to node parameters;
:func:`write_params_file` writes them as one ROS 2 parameter file (the run's ``params.yaml``),
which is what a graph started by hand uses too (``config/params/lockstep.yaml`` is such a file).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import yaml

from fourws_ros import topics
from fourws_run.config import RunConfig

Role = topics.Role
NODE_NAMES = topics.NODE_NAMES
#: Lockstep flow control: the simulator runs at most this many messages of any recorded topic
#: ahead of what the recorder has stored (0.5 s of simulated time at 100 Hz). Far below the
#: stream history depth, so no message can leave a queue before the recorder takes it; and
#: small enough that all topics together stay within the middleware's shared-memory port
#: queue (512 messages by default), whose overflow would cost a retransmission after the
#: writer's next heartbeat (seconds).
RECORDER_WINDOW = 50


def dumps_config(config: dict[str, Any]) -> str:
    """JSON text of a configuration mapping (numpy values and paths made plain)."""
    def default(obj: Any) -> Any:
        if hasattr(obj, "tolist"):
            return obj.tolist()
        if isinstance(obj, Path):
            return str(obj)
        raise TypeError(f"not JSON serializable: {type(obj).__name__}")
    return json.dumps(config, default=default, sort_keys=True)


def node_parameters(config: RunConfig, bag_path: Path | None,
                    replay: bool = False) -> dict[str, dict[str, Any]]:
    """``ros__parameters`` of every node of the run, keyed by ROS node name (``replay``: a
    replay node answers in the maneuver's place, :func:`expected_endpoints`)."""
    lockstep = config.lockstep
    records = bag_path is not None and bool(config.recorded_topics)
    controller = config.controller.node_name
    gate = {"integration_step_s": config.integration_step_s,
            "state_period_s": config.controller_period_s, "clock_mode": config.clock_mode}
    # the vehicle as a whole mapping (tire override applied): the run's vehicle may be one no
    # file holds (a study's scaled mass, a belief with scaled cornering stiffness)
    vehicle = {"vehicle": config.vehicle.name,
               "vehicle_json": dumps_config(config.vehicle.to_dict())}
    # every node publishes only once its publishers have matched the run's subscribers
    # (fourws_ros.reporting.MatchWait): the expected count of each topic
    subscribers = dumps_config(expected_subscribers(config, records, replay))
    gate["expected_subscribers_json"] = subscribers
    # the launcher watches the processes and their start-up phases (fourws_ros.graph_run):
    # the nodes' own start-up timeout, for graphs started by hand, is off
    gate["startup_timeout_s"] = 0.0
    params: dict[str, dict[str, Any]] = {
        NODE_NAMES[Role.SIMULATOR]: {
            **vehicle, "model": config.model, "integrator": config.integrator,
            "integration_step_s": config.integration_step_s,
            "control_period_s": config.control_period_s,
            "state_period_s": config.state_period_s,
            "clock_mode": config.clock_mode,
            "initial_speed_mps": config.speed_mps,
            "autostart": False,
            "expected_state_subscribers": (2 + int(records)) if lockstep else 0,
            "recorder_window": RECORDER_WINDOW if lockstep and records else 0,
            "expected_subscribers_json": subscribers,
            "controller_node": controller,
            "maneuver_node": NODE_NAMES[Role.MANEUVER],
            "startup_timeout_s": 0.0,
            # the course markers (cones, target line) of the scene
            "maneuver_json": dumps_config(config.maneuver.to_dict()),
        },
        NODE_NAMES[Role.MANEUVER]: {
            "maneuver_json": dumps_config(config.maneuver.to_dict()),
            **vehicle, **gate,
        },
        controller: {
            "law": config.law,
            "law_options_json": dumps_config(dict(config.law_options)),
            **vehicle, "belief_vehicle_json": dumps_config(config.belief.to_dict()),
            # the controller is called once per published state: in lockstep once per
            # control period, in realtime once per state period -- the interval of its rate
            # limit
            "control_period_s": config.controller_period_s,
            # lockstep: the driver input of every tick comes (the run ends when it does not)
            "driver_wait_s": 0.0 if lockstep else 0.5,
            **gate,
        },
    }
    if not config.driver_node:
        # a user's driver (docs/driver-contract.md) does not report counts or end the run:
        # the simulator ends it at the maneuver's duration, the recorder counts the driver's
        # messages by their sequence numbers (as a user controller's)
        params[NODE_NAMES[Role.SIMULATOR]]["end_time_s"] = float(config.maneuver.duration_s)
    if records:
        params[NODE_NAMES[Role.RECORDER]] = {
            "bag_path": str(bag_path), "topics": list(config.recorded_topics),
            "controller_node": controller, "startup_timeout_s": 0.0,
            "maneuver_reports": bool(config.driver_node)}
    return params


def write_params_file(path: Path, node_params: dict[str, dict[str, Any]]) -> Path:
    """Write a ROS 2 parameter file ``{node: {ros__parameters: {...}}}`` (YAML).

    Raises
    ------
    OSError
        The file cannot be written.
    """
    data = {node: {"ros__parameters": params} for node, params in node_params.items()}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def expected_subscribers(config: RunConfig, recorded: bool,
                         replay: bool = False) -> dict[str, int]:
    """How many of the run's nodes subscribe to each topic (from :func:`expected_endpoints`):
    a publisher of the topic waits for that many matches before it publishes."""
    counts: dict[str, int] = {}
    for topic, kind, _ in expected_endpoints(config, recorded, replay):
        if kind == "sub":
            counts[topic] = counts.get(topic, 0) + 1
    return counts


def expected_endpoints(config: RunConfig, recorded: bool,
                       replay: bool = False) -> list[tuple[str, str, str]]:
    """``(topic, "pub"|"sub", node name)`` that must be in the graph before the run starts
    (``replay``: the driver inputs come from a replay node, which reads no status)."""
    sim, man = NODE_NAMES[Role.SIMULATOR], NODE_NAMES[Role.MANEUVER]
    ctrl = config.controller.node_name
    expected = [
        (topics.STATE, "pub", sim), (topics.STATE, "sub", man), (topics.STATE, "sub", ctrl),
        (topics.DRIVER_INPUT, "pub", man), (topics.DRIVER_INPUT, "sub", sim),
        (topics.REAR_STEER_CMD, "pub", ctrl), (topics.REAR_STEER_CMD, "sub", sim),
        # every node that answers states is counted where it must receive: the controller
        # contract obliges a user's controller to wait for each tick's driver input too
        (topics.DRIVER_INPUT, "sub", ctrl),
    ]
    # the status topics are volatile: every node that reads them must have matched before
    # the first status, or it misses the first ones (counted, a matched count of 1 could be
    # the simulator's or a viewer's reader, not the recorder's: the live view's load delayed
    # the recorder by 1.3 s, and 13 of 301 statuses were lost to it)
    launcher = NODE_NAMES[Role.LAUNCHER]
    expected += [(topics.MANEUVER_STATUS, "sub", sim), (topics.MANEUVER_STATUS, "sub", launcher),
                 (topics.SIM_STATUS, "sub", launcher)]
    if config.driver_node and not replay:  # fourws's maneuver-role nodes read it
        expected.append((topics.SIM_STATUS, "sub", man))
    # the launcher takes a status only from a publisher its graph names as the run's node
    # (fourws_ros.launcher_node): its graph must name them before the first status, or it
    # drops them (beside a CPU hog, a 1.4 s run's every maneuver status was dropped, the done
    # included, and the run was failed for an end its bag holds)
    expected.append((topics.SIM_STATUS, "pub", sim))
    if config.driver_node:  # the maneuver node, or a replay node answering in its place
        expected.append((topics.MANEUVER_STATUS, "pub", man))
    if config.controller.builtin:
        expected.append((topics.SIM_STATUS, "sub", ctrl))
    if recorded:
        rec = NODE_NAMES[Role.RECORDER]
        expected += [(t, "sub", rec) for t in config.recorded_topics]
        expected += [(topics.RECORDER_STATUS, "sub", sim), (topics.RECORDER_STATUS, "pub", rec)]
    return expected


__all__ = ["RECORDER_WINDOW", "dumps_config", "expected_endpoints", "expected_subscribers",
           "node_parameters",
           "write_params_file"]
