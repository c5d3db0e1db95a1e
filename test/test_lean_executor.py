# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The lean executor against rclpy's single-threaded executor: one scenario (messages with
and without message info, raw, timers with and without TimerInfo, a guard condition, a
parameter service called by another node) spun by each; the callbacks' trace must be the
same, and the lean executor must have taken its own path (or rclpy's, where a node has a
waitable or a coroutine callback)."""

from __future__ import annotations

import time

import pytest

pytestmark = pytest.mark.usefixtures("ros_domain")


def _spin_until(executors, predicate, timeout_s: float = 20.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        for ex in executors:
            ex.spin_once(timeout_sec=0.005)
    return predicate()


def _scenario(ctx, executor_class, waitable: bool = False, coroutine: bool = False,
              peer_lean: bool = True):
    """Run the scenario with ``executor_class`` spinning the probe node (and the peer, its
    parameter client, unless not ``peer_lean``); the trace and both executors."""
    from rcl_interfaces.msg import Parameter as ParameterMsg
    from rcl_interfaces.msg import ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters
    from rclpy.event_handler import SubscriptionEventCallbacks
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.serialization import deserialize_message
    from rclpy.timer import TimerInfo
    from std_msgs.msg import String

    from fourws_ros.node_base import FourwsNode

    trace: list[tuple] = []
    probe = FourwsNode("lean_probe", context=ctx)
    probe.declare_parameter("gain", 1.0)

    def only(msg):
        trace.append(("only", msg.data))

    def with_info(msg, info):
        trace.append(("info", msg.data, isinstance(info, dict) and "publisher_gid" in info,
                      info["publication_sequence_number"] if isinstance(info, dict) else None))

    def raw(data, info):
        trace.append(("raw", deserialize_message(data, String).data, type(data).__name__))

    if coroutine:
        async def only_async(msg):
            trace.append(("only", msg.data))
        probe.create_subscription(String, "lean_a", only_async, 10)
    else:
        probe.create_subscription(String, "lean_a", only, 10)
    probe.create_subscription(String, "lean_b", with_info, 10)
    # a QoS event handler is a waitable
    events = {"event_callbacks": SubscriptionEventCallbacks(deadline=lambda event: None)
              } if waitable else {}
    probe.create_subscription(String, "lean_c", raw, 10, raw=True, **events)
    ticks = {"plain": 0, "info": 0}

    def plain_tick():
        ticks["plain"] += 1

    def info_tick(timer_info: TimerInfo):
        if ticks["info"] == 0:
            trace.append(("timer_info", type(timer_info).__name__))
        ticks["info"] += 1

    # the class itself, as rclpy compares it (this module's annotations are strings)
    info_tick.__annotations__["timer_info"] = TimerInfo
    probe.create_timer(0.01, plain_tick)
    probe.create_timer(0.01, info_tick)
    guard = probe.create_guard_condition(lambda: trace.append(("guard",)))

    peer = FourwsNode("lean_peer", context=ctx)
    peer_ex = (executor_class if peer_lean else SingleThreadedExecutor)(context=ctx)
    peer_ex.add_node(peer)
    pubs = {t: peer.create_publisher(String, t, 10) for t in ("lean_a", "lean_b", "lean_c")}
    client = peer.create_client(SetParameters, "/lean_probe/set_parameters")

    executor = executor_class(context=ctx)
    executor.add_node(probe)
    try:
        assert _spin_until([executor, peer_ex], lambda: all(
            p.get_subscription_count() == 1 for p in pubs.values())
            and client.service_is_ready())
        for k in range(3):
            for topic, pub in pubs.items():
                pub.publish(String(data=f"{topic}-{k}"))
        assert _spin_until([executor, peer_ex], lambda: len(trace) >= 9)
        guard.trigger()
        assert _spin_until([executor, peer_ex], lambda: ("guard",) in trace)
        request = SetParameters.Request(parameters=[ParameterMsg(
            name="gain", value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE,
                                              double_value=2.5))])
        future = client.call_async(request)
        assert _spin_until([executor, peer_ex], future.done)
        trace.append(("set", future.result().results[0].successful,
                      probe.get_parameter("gain").value))
        assert _spin_until([executor, peer_ex], lambda: ticks["plain"] >= 3 and
                           ticks["info"] >= 3)
    finally:
        executor.shutdown(timeout_sec=1.0)
        peer_ex.shutdown(timeout_sec=1.0)
        probe.destroy_node()
        peer.destroy_node()
    # order across topics depends on delivery; within a topic it is the publish order
    return sorted(trace, key=repr), executor, peer_ex


def test_lean_executor_calls_what_rclpy_calls_with_the_same_arguments(rclpy_context):
    from rclpy.executors import SingleThreadedExecutor

    from fourws_ros.lean_executor import LeanExecutor

    expected, _, _ = _scenario(rclpy_context, SingleThreadedExecutor)
    got, lean, peer = _scenario(rclpy_context, LeanExecutor)
    assert got == expected
    # 3 messages each of three topics, the guard, the parameter set, the TimerInfo timer
    assert len(got) == 12
    assert ("set", True, 2.5) in got
    assert ("raw", "lean_c-2", "bytes") in got
    assert [t for t in got if t[0] == "info"] == [
        ("info", f"lean_b-{k}", True, k + 1) for k in range(3)]
    assert lean.lean_wakeups > 0 and lean.rclpy_wakeups == 0
    # the peer's parameter client took its response on the lean path
    assert peer.lean_wakeups > 0 and peer.rclpy_wakeups == 0


@pytest.mark.parametrize("case", ["waitable", "coroutine"])
def test_lean_executor_leaves_what_it_does_not_handle_to_rclpy(rclpy_context, case):
    from rclpy.executors import SingleThreadedExecutor

    from fourws_ros.lean_executor import LeanExecutor

    kwargs = {case: True}
    expected, _, _ = _scenario(rclpy_context, SingleThreadedExecutor, **kwargs)
    got, lean, _ = _scenario(rclpy_context, LeanExecutor, peer_lean=False, **kwargs)
    assert got == expected and len(got) == 12
    assert lean.rclpy_wakeups > 0 and lean.lean_wakeups == 0


def test_lean_executor_returns_on_shutdown_and_on_a_context_shut_down(rclpy_context):
    import threading

    import rclpy
    from rclpy.context import Context
    from rclpy.executors import ExternalShutdownException
    from rclpy.task import Future

    from fourws_ros.lean_executor import LeanExecutor
    from fourws_ros.node_base import FourwsNode

    node = FourwsNode("lean_idle", context=rclpy_context)
    executor = LeanExecutor(context=rclpy_context)
    executor.add_node(node)
    threading.Timer(0.3, executor.shutdown).start()
    start = time.monotonic()
    executor.spin_until_future_complete(Future(), timeout_sec=30.0)
    assert time.monotonic() - start < 20.0  # woken by its guard condition, not the timeout
    node.destroy_node()

    other = Context()
    rclpy.init(args=[], context=other)
    node = FourwsNode("lean_idle2", context=other)
    executor = LeanExecutor(context=other)
    executor.add_node(node)
    threading.Timer(0.3, other.try_shutdown).start()
    with pytest.raises(ExternalShutdownException):
        for _ in range(600):  # 30 s at most
            executor.spin_once(timeout_sec=0.05)


def test_lean_executor_keeps_its_entities_until_a_node_changes_them(rclpy_context):
    """The entities are gathered once, not per wake-up; a subscription created while the
    executor spins is served, a destroyed one never called again, a timer added is run."""
    from std_msgs.msg import String

    from fourws_ros.lean_executor import LeanExecutor
    from fourws_ros.node_base import FourwsNode

    node = FourwsNode("lean_cache", context=rclpy_context)
    executor = LeanExecutor(context=rclpy_context)
    executor.add_node(node)
    got: list[tuple[str, str]] = []
    pub = node.create_publisher(String, "lean_cache_a", 10)
    first = node.create_subscription(String, "lean_cache_a",
                                     lambda m: got.append(("first", m.data)), 10)
    try:
        assert _spin_until([executor], lambda: pub.get_subscription_count() == 1)
        executor.spin_once(timeout_sec=0.0)
        scans = executor.entity_scans
        assert scans == 1
        for k in range(20):
            pub.publish(String(data=f"m{k}"))
            assert _spin_until([executor], lambda k=k: ("first", f"m{k}") in got)
        # 20 messages, at least 20 wake-ups, and not one gathering of the entities
        assert executor.lean_wakeups >= 20 and executor.entity_scans == scans
        node.create_subscription(String, "lean_cache_a",
                                 lambda m: got.append(("second", m.data)), 10)
        assert _spin_until([executor], lambda: pub.get_subscription_count() == 2)
        pub.publish(String(data="both"))
        assert _spin_until([executor], lambda: {("first", "both"), ("second", "both")}
                           <= set(got))
        assert executor.entity_scans > scans
        node.destroy_subscription(first)
        ticks: list[int] = []
        node.create_timer(0.01, lambda: ticks.append(1))
        pub.publish(String(data="after"))
        assert _spin_until([executor], lambda: ("second", "after") in got and ticks)
        assert ("first", "after") not in got
        assert executor.rclpy_wakeups == 0
    finally:
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()


def test_an_entity_created_while_the_executor_gathers_is_not_missed(rclpy_context, monkeypatch):
    """A subscription created (by another thread) while the executor is gathering the
    entities, after it has read the node's list: the next wake-up gathers them again and
    serves the new subscription (the lists gathered before the change are not kept)."""
    from std_msgs.msg import String

    from fourws_ros.lean_executor import LeanExecutor
    from fourws_ros.node_base import FourwsNode

    node = FourwsNode("lean_race", context=rclpy_context)
    executor = LeanExecutor(context=rclpy_context)
    executor.add_node(node)
    got: list[str] = []
    pub = node.create_publisher(String, "lean_race_a", 10)
    gather = executor._gather
    created: list = []

    def gather_then_create():
        found = gather()  # the lists as they were
        if not created:  # the other thread's creation lands here, once
            created.append(node.create_subscription(String, "lean_race_a",
                                                    lambda m: got.append(m.data), 10))
        return found

    monkeypatch.setattr(executor, "_gather", gather_then_create)
    try:
        assert _spin_until([executor], lambda: pub.get_subscription_count() == 1)
        pub.publish(String(data="seen"))
        assert _spin_until([executor], lambda: "seen" in got)
        assert executor.entity_scans >= 2
    finally:
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
