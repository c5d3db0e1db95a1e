# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The start-up of a run's graph: wait until every node is ready and every endpoint is in
the graph, with time limits that follow what the nodes say they are doing.

Each fourws node reports its start-up phase to the launcher on a pipe
(:func:`fourws_ros.runtime.report_phase`): nothing while Python imports, ``configuring``
(parameters, the core objects), ``compiling`` (the simulator's numba kernels: seconds from the
disk cache ``make setup`` fills, up to minutes cold on a busy machine), ``ready``, or
``failed: <why>``. The launcher waits

* for a node that has said nothing yet: :data:`IMPORT_TIMEOUT_S`;
* for a node in a phase: :data:`PHASE_TIMEOUT_S` from its last report, but
  :data:`COMPILE_TIMEOUT_S` while it compiles;
* once every fourws node is ready, for the ROS graph to list every endpoint the run needs:
  :data:`DISCOVERY_TIMEOUT_S`; a user's controller (it reports no phases) must have its
  endpoints within :data:`USER_NODE_TIMEOUT_S` of the start;

and stops at once when a node fails or exits. Every timeout names the node and what it was
doing or which endpoint is missing.
"""

from __future__ import annotations

import time
from typing import Any, Callable

from fourws_ros import node_params, topics
from fourws_ros.processes import ProcessGroup, describe_exit
from fourws_run.config import RunConfig

#: A node that has reported no phase yet (Python still importing) gets this long, s.
IMPORT_TIMEOUT_S = 60.0
#: A node in a phase other than compiling gets this long from its last report, s.
PHASE_TIMEOUT_S = 60.0
#: A node compiling its kernels gets this long, s.
COMPILE_TIMEOUT_S = 600.0
#: Once every fourws node is ready: time for the graph to list every endpoint, s.
DISCOVERY_TIMEOUT_S = 30.0
#: A user's controller (no phases): time from the start for its endpoints to appear, s.
USER_NODE_TIMEOUT_S = 60.0
READY = "ready"


def _late_node(group: ProcessGroup, reporting: set[str], now: float) -> str:
    """A fourws node past the limit of its phase ('' if none)."""
    for child in group.children:
        if child.name not in reporting or child.phase == READY:
            continue
        if child.phase.startswith("failed"):
            return f"node {child.name} {child.phase}"
        limit = (IMPORT_TIMEOUT_S if not child.phase
                 else COMPILE_TIMEOUT_S if child.phase == "compiling" else PHASE_TIMEOUT_S)
        if now - child.phase_at > limit:
            doing = child.phase or "starting (importing Python modules)"
            return (f"node {child.name} did not get past '{doing}' within {limit:.0f} s "
                    f"(log {child.log_path})")
    return ""


def wait_for_graph(config: RunConfig, group: ProcessGroup, ros: Any,
                   interrupted: Callable[[], bool], recorded: bool, replay: bool = False) -> str:
    """Wait until the graph of ``config`` is complete and the simulator's pause service is
    there; '' or why not (module docstring)."""
    expected = node_params.expected_endpoints(config, recorded, replay)
    if recorded:
        expected.append((topics.RUN_CONFIG, "sub", topics.NODE_NAMES[topics.Role.RECORDER]))
    user = set() if config.controller.builtin else {config.controller.node_name}
    if not config.driver_node:  # a user's driver in the maneuver's role reports no phases
        user.add(topics.NODE_NAMES[topics.Role.MANEUVER])
    reporting = {c.name for c in group.children} - user
    ready_at = 0.0
    while True:
        ros.spin(0.05)
        group.read_phases()
        now = time.monotonic()
        if interrupted():
            return "interrupted (Ctrl-C / SIGTERM)"
        dead = group.failed()
        if dead is not None:
            return describe_exit(dead)
        late = _late_node(group, reporting, now)
        if late:
            return late
        if not all(group.child(n).phase == READY for n in reporting):
            continue
        ready_at = ready_at or now
        missing = [e for e in expected if not ros.has_endpoint(*e)]
        if not missing and ros.pause.service_is_ready():
            return ""
        user_missing = [e for e in missing if e[2] in user]
        if user_missing and now - group.started_at > USER_NODE_TIMEOUT_S:
            node = user_missing[0][2]
            who = (f"the controller {node} ({' '.join(config.controller.command)})"
                   if node == config.controller.node_name and not config.controller.builtin
                   else f"the driver {node} ({' '.join(config.driver)})")
            return (f"{who} is not in the graph after {USER_NODE_TIMEOUT_S:.0f} s; missing: "
                    + _endpoints(user_missing))
        if now - ready_at > DISCOVERY_TIMEOUT_S and (missing != user_missing or not missing):
            if not missing:
                return "the simulator's /fourws/pause service did not appear"
            return (f"graph incomplete {DISCOVERY_TIMEOUT_S:.0f} s after every node was "
                    f"ready; missing: " + _endpoints(missing))


def _endpoints(entries: list[tuple[str, str, str]]) -> str:
    return ", ".join(f"{n} {'publishing' if k == 'pub' else 'subscribing to'} {t}"
                     for t, k, n in entries)


__all__ = ["COMPILE_TIMEOUT_S", "DISCOVERY_TIMEOUT_S", "IMPORT_TIMEOUT_S", "PHASE_TIMEOUT_S",
           "USER_NODE_TIMEOUT_S", "wait_for_graph"]
