# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A foreign node flooding a status topic cannot push the run's own message out of the
launcher's reader while the launcher is starved (``fourws_ros.topics.READ_QOS``: keep all).

Seen before: beside two CPU hogs, a rogue publishing 'done' maneuver statuses at about 500 a
second pushed the maneuver's one final status out of the launcher's keep-last-1000 reader
before the starved launcher took it, and a good run failed with "the simulation ended without
the maneuver's end"."""

from __future__ import annotations

import selectors
import subprocess
import sys
import textwrap
import time

from fourws_ros.domains import graph_env
from fourws_ros.launcher_node import LauncherNode, RunState
from fourws_run.interface import Role

#: Foreign statuses published after the run's own one, each batch acknowledged by the launcher's
#: reader before the next: more than the 1000 a keep-last reader holds.
AFTER = 1500

_PUBLISHERS = textwrap.dedent("""
    import sys, time
    import rclpy
    from rclpy.duration import Duration
    from fourws_ros import topics

    rclpy.init()
    own, rogue = rclpy.create_node("fourws_maneuver"), rclpy.create_node("rogue")
    msg = topics.message_class(topics.MANEUVER_STATUS)
    pubs = [node.create_publisher(msg, topics.MANEUVER_STATUS, topics.EVENT_QOS)
            for node in (own, rogue)]
    deadline = time.monotonic() + 120.0
    while min(p.get_subscription_count() for p in pubs) < 1 and time.monotonic() < deadline:
        time.sleep(0.05)
    print("matched", flush=True)

    def status(event):
        m = msg()
        m.done, m.end, m.event = True, "completed", event
        return m

    def acked(pub):
        # every message in the launcher's reader before the next batch (the rogue writer's
        # own keep-last history must not drop any); bounded against a hang only
        if not pub.wait_for_all_acked(Duration(seconds=120)):
            print("not acknowledged within 120 s", flush=True)
            sys.exit(1)

    def flood(n):
        for k in range(0, n, 250):
            for _ in range(250):
                pubs[1].publish(status("rogue"))
            acked(pubs[1])

    flood(500)
    pubs[0].publish(status("the run's own end"))
    acked(pubs[0])
    flood(int(sys.argv[1]))
    print("sent", flush=True)
    sys.stdin.readline()
""")


def _line(proc: subprocess.Popen, timeout_s: float) -> str:
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    return proc.stdout.readline() if sel.select(timeout=timeout_s) else ""


def test_a_flood_cannot_push_the_runs_final_status_out_of_a_starved_launcher(ros_domain):
    """The launcher takes nothing while a foreign node publishes 500 'done' statuses, the
    run's maneuver its one final status, then the foreign node 1500 more, every one received
    by the launcher's reader (acknowledged). When the launcher spins, it has the run's final
    status and counts the foreign ones. With a keep-last-1000 reader the run's status was gone
    (this test fails on the code before)."""
    state = RunState()
    launcher = LauncherNode(ros_domain, "{}", {Role.MANEUVER: "fourws_maneuver"}, state)
    proc = subprocess.Popen([sys.executable, "-c", _PUBLISHERS, str(AFTER)],
                            env=graph_env(ros_domain), stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    try:
        assert _line(proc, 120.0) == "matched\n"
        assert _line(proc, 600.0) == "sent\n"  # the launcher has not spun yet
        deadline = time.monotonic() + 60.0  # a bound against a hang, not a speed
        while state.maneuver_end is None and time.monotonic() < deadline:
            launcher.executor.spin_once(timeout_sec=0.05)
        for _ in range(20):  # what else is queued
            launcher.executor.spin_once(timeout_sec=0.01)
    finally:
        proc.stdin.close()
        proc.wait(timeout=60)
        launcher.close(destroy=True)
    assert state.maneuver_end is not None, f"{state.foreign} foreign statuses taken"
    assert state.maneuver_end.event == "the run's own end"
    assert state.foreign >= AFTER
