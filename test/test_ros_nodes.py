# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Tests of single fourws nodes: recorder durability, parameter validation, simulator safety.

In-process tests create the node in the test process (on a reserved ROS domain, discovery on
this machine only); the recorder durability tests run it as its own process, to kill it.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from fourws_analysis.bag import BagError, load_bag
from fourws_ros import conversions, topics
from fourws_run.bagfile import read_bag

pytestmark = pytest.mark.usefixtures("ros_domain")


# ----------------------------------------------------------------------------- helpers
def _spin_until(executor, predicate, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        executor.spin_once(timeout_sec=0.02)
    return predicate()


def _start_recorder(bag: Path, *extra: str) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "fourws_cli.main", "node", "recorder", "--ros-args",
           "-p", f"bag_path:={bag}", *extra]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            start_new_session=True)


def _publish_states(n: int, rate_hz: float, ctx, name: str = "state_source",
                    final: bool = False, keep: bool = False, claimed: int | None = None):
    """Publish ``n`` VehicleState messages (step k, yaw rate k*1e-3, stamp k ms) at rate_hz
    from a node called ``name``; with ``final``, then a final SimulatorStatus with the counts
    (what the simulator sends when a run ends; ``claimed`` states instead of ``n``: some were
    lost). The node is destroyed (it leaves the graph) unless ``keep``: then it is returned,
    still publishing."""
    import rclpy
    from rclpy.duration import Duration

    node = rclpy.create_node(name, context=ctx)
    pub = node.create_publisher(topics.message_class(topics.STATE), topics.STATE,
                                topics.STREAM_QOS)
    status_pub = node.create_publisher(topics.message_class(topics.SIM_STATUS),
                                       topics.SIM_STATUS, topics.TOPIC_QOS[topics.SIM_STATUS])
    deadline = time.monotonic() + 30.0
    while (pub.get_subscription_count() < 1 or final and status_pub.get_subscription_count() < 1
           ) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert pub.get_subscription_count() >= 1, "recorder did not subscribe"
    msg = topics.message_class(topics.STATE)()
    t0 = time.perf_counter()
    for k in range(n):
        conversions.set_stamp(msg.header.stamp, k * 1e-3)
        msg.step = k
        msg.yaw_rate_radps = k * 1e-3
        pub.publish(msg)
        while time.perf_counter() - t0 < (k + 1) / rate_hz:
            time.sleep(1e-4)
    if final:
        status = topics.message_class(topics.SIM_STATUS)()
        status.published_topics = [topics.SIM_STATUS, topics.STATE]
        status.published_counts = [1, n if claimed is None else claimed]
        status.final = True
        status.end_reason = "test"
        status_pub.publish(status)
        status_pub.wait_for_all_acked(Duration(seconds=10))
    pub.wait_for_all_acked(Duration(seconds=10))
    if keep:
        return node
    node.destroy_node()
    return None


_AS_SIMULATOR = ("-p", "simulator_node:=state_source",
                 "-p", f"topics:=[{topics.STATE},{topics.SIM_STATUS}]")


# ----------------------------------------------------------------------------- recorder
def test_recorder_closes_a_bag_that_cannot_complete_after_the_final_counts(
        tmp_path, rclpy_context):
    """The final status claims 2005 states, 2000 came: once nothing more arrives for
    INCOMPLETE_AFTER_END_S the recorder closes the bag incomplete by itself, exit 4, saying
    what is missing (it waited for good before: a hand-started graph never ended)."""
    bag = tmp_path / "bag"
    proc = _start_recorder(bag, *_AS_SIMULATOR)
    try:
        _publish_states(2000, 2000.0, rclpy_context, final=True, claimed=2005)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 4, out
    assert b"every writer reported its final counts" in out, out
    assert topics.STATE.encode() in out
    run = load_bag(bag, allow_incomplete=True)
    assert run.complete is False
    assert len(run.topics[topics.STATE]) == 2000


def test_a_status_reader_matched_late_still_hears_the_recorder(tmp_path, rclpy_context):
    """A reader of /fourws/recorder_status created after the recorder's first status (the
    topic is volatile), with nothing for the recorder to store: it still gets statuses, at
    least every STATUS_HEARTBEAT_S. Before, the recorder spoke only after storing something,
    and a simulator whose start waits for a first status waited for good (a run stalled at
    t = 0 in CI)."""
    import rclpy
    from fourws_ros.recorder_node import STATUS_HEARTBEAT_S

    proc = _start_recorder(tmp_path / "bag", *_AS_SIMULATOR)
    node = rclpy.create_node("late_reader", context=rclpy_context)
    executor = rclpy.executors.SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    try:
        # the recorder is up (its status publisher is in the graph, its first status sent)
        assert _spin_until(executor, lambda: any(
            i.node_name == "fourws_recorder"
            for i in node.get_publishers_info_by_topic(topics.RECORDER_STATUS)), 60.0)
        heard = []
        node.create_subscription(topics.message_class(topics.RECORDER_STATUS),
                                 topics.RECORDER_STATUS, heard.append, topics.STATUS_QOS)
        assert _spin_until(executor, lambda: len(heard) >= 3, 40 * STATUS_HEARTBEAT_S), (
            f"{len(heard)} statuses")
        assert not heard[-1].closed and list(heard[-1].stored) == [0, 0]  # nothing stored
    finally:
        executor.shutdown()
        node.destroy_node()
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


def test_recorder_closes_complete_bag_when_the_run_ends(tmp_path, rclpy_context):
    """States, then the simulator's final status with its counts: the recorder holds all 2001
    messages, closes the bag by itself as complete and exits 0 (no signal needed)."""
    bag = tmp_path / "bag"
    proc = _start_recorder(bag, *_AS_SIMULATOR)
    try:
        _publish_states(2000, 2000.0, rclpy_context, final=True)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 0, out
    assert b"complete" in out
    run = load_bag(bag)
    assert run.complete is True and not run.warnings
    state = run.topics[topics.STATE]
    assert len(state) == 2000
    np.testing.assert_allclose(state.fields["yaw_rate_radps"], np.arange(2000) * 1e-3)
    # bag times are the simulation stamps
    np.testing.assert_allclose(state.time_s, np.arange(2000) * 1e-3, atol=1e-12)


def test_recorder_sigint_drains_and_closes_incomplete(tmp_path, rclpy_context):
    """SIGINT before the run ended: the recorder drains its queue, closes the bag with its
    accounting (the publisher's final count never came) and exits 4; all 2000 states are
    in the bag."""
    bag = tmp_path / "bag"
    proc = _start_recorder(bag, *_AS_SIMULATOR)
    try:
        _publish_states(2000, 2000.0, rclpy_context)
        proc.send_signal(signal.SIGINT)  # at once: the recorder must drain its queue first
        out, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 4, out
    assert (bag / "metadata.yaml").is_file()
    with pytest.raises(BagError, match="final count is unknown"):
        load_bag(bag)
    run = load_bag(bag, allow_incomplete=True)
    assert run.complete is False
    assert len(run.topics[topics.STATE]) == 2000


def test_recorder_stores_nothing_from_a_foreign_publisher(tmp_path, rclpy_context):
    """States from a node that is not the run's simulator are counted as foreign, not
    stored."""
    bag = tmp_path / "bag"
    proc = _start_recorder(bag, *_AS_SIMULATOR)
    try:
        _publish_states(300, 2000.0, rclpy_context, name="rogue")
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert b"300 foreign messages not stored" in out
    messages, check = read_bag(bag)
    assert messages == []
    meta = check.accounting
    assert meta["topics"][topics.STATE]["stored"] == 0
    assert meta["topics"][topics.STATE]["foreign"] == 300
    # named after the publishing node (or, if the ROS graph never named it before it left,
    # as an unidentified publisher: foreign either way)
    (who,) = meta["foreign_publishers"]
    assert who in (f"{topics.STATE} from rogue",
                   f"{topics.STATE} from (unidentified publisher)")


def test_recorder_sigkill_leaves_repairable_bag(tmp_path, rclpy_context):
    """SIGKILL: everything published a flush period before the kill is in complete chunks;
    `fourws bag repair` rebuilds summary and metadata so rosbags opens it."""
    from rosbags.rosbag2 import Reader

    bag = tmp_path / "bag"
    flush_s = 0.2
    proc = _start_recorder(bag, "-p", f"flush_period_s:={flush_s}", *_AS_SIMULATOR)
    source = None
    try:
        # the state source stays (a source that leaves ends the recording by itself)
        source = _publish_states(500, 1000.0, rclpy_context, keep=True)
        time.sleep(5 * flush_s)  # several flushes after the last message
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        if source is not None:
            source.destroy_node()
    assert proc.returncode == -signal.SIGKILL
    assert not (bag / "metadata.yaml").exists()  # it really died before closing
    run = load_bag(bag, allow_incomplete=True)
    state = run.topics[topics.STATE]
    assert len(state) == 500  # everything published a flush period before the kill
    np.testing.assert_allclose(state.fields["yaw_rate_radps"], np.arange(500) * 1e-3)
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "bag", "repair", str(bag)],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 1, res.stderr  # repaired, and says it is still incomplete
    assert "500" in res.stdout and "final" in res.stdout
    with Reader(bag) as reader:
        assert sum(1 for c, _, _ in reader.messages() if c.topic == topics.STATE) == 500
    assert (bag / (next(bag.glob("*.mcap")).name + ".damaged")).is_file()


def test_stamp_parsing_matches_messages():
    from rclpy.serialization import serialize_message

    from fourws_run.cdr import stamp_ns

    msg = topics.message_class(topics.STATE)()
    conversions.set_stamp(msg.header.stamp, 12.345678901)
    msg.model = "8dof"
    assert stamp_ns(serialize_message(msg), topics.TOPIC_TYPES[topics.STATE]) == 12_345_678_901
    clock = conversions.clock_msg(3.5)
    assert stamp_ns(serialize_message(clock), topics.TOPIC_TYPES[topics.CLOCK]) == 3_500_000_000
    # status messages hold sequences after the header: the stamp still sits at a fixed place
    status = topics.message_class(topics.SIM_STATUS)()
    conversions.set_stamp(status.header.stamp, 2.25)
    status.published_topics = ["a", "bb"]
    assert stamp_ns(serialize_message(status),
                    topics.TOPIC_TYPES[topics.SIM_STATUS]) == 2_250_000_000
    # a message without a stamp has none (not its first bytes read as one)
    text = topics.message_class(topics.NODE_CONFIG)(data="{}")
    assert stamp_ns(serialize_message(text), topics.TOPIC_TYPES[topics.NODE_CONFIG]) is None


# ----------------------------------------------------------------------------- controller
def test_controller_live_law_switch_is_validated(rclpy_context):
    from rclpy.parameter import Parameter

    from fourws_ros.controller_node import ControllerNode

    node = _make_node(ControllerNode, rclpy_context)
    try:
        assert node.law_name == "fws"
        bad = node.set_parameters([Parameter("law", value="no_such_law")])[0]
        assert not bad.successful and "unknown law 'no_such_law'" in bad.reason
        assert node.get_parameter("law").value == "fws" and node.law_name == "fws"
        # out of the descriptor's range: rejected, running value kept
        limit = node.get_parameter("angle_limit_rad").value
        res = node.set_parameters([Parameter("angle_limit_rad", value=2.0)])[0]
        assert not res.successful
        assert node.get_parameter("angle_limit_rad").value == limit
        res = node.set_parameters([Parameter("law_options_json", value="{not json")])[0]
        assert not res.successful and "law_options_json" in res.reason
        ok = node.set_parameters([Parameter("law", value="sol1")])[0]
        assert ok.successful and node.law_name == "sol1"
        # the new law is sol1 of the simulated car: same gains as the core builds
        from fourws_control import make_law
        np.testing.assert_array_equal(node.law.gains(23.6),
                                      make_law("sol1", node.vehicle).gains(23.6))
    finally:
        node.destroy_node()


def _make_node(cls, ctx, **params):
    """Build a fourws node class in context ``ctx`` with parameter overrides."""
    import rclpy
    from rclpy.parameter import Parameter

    original = rclpy.node.Node.__init__

    def init(self, name, **kwargs):
        kwargs.setdefault("context", ctx)
        kwargs["parameter_overrides"] = [Parameter(k, value=v) for k, v in params.items()]
        original(self, name, **kwargs)

    rclpy.node.Node.__init__ = init
    try:
        return cls()
    finally:
        rclpy.node.Node.__init__ = original


# ----------------------------------------------------------------------------- simulator
class _Peer:
    """A test node that answers the simulator like maneuver + controller would."""

    def __init__(self, ctx):
        import rclpy

        self.node = rclpy.create_node("peer", context=ctx)
        msg = topics.message_class
        self.driver_pub = self.node.create_publisher(msg(topics.DRIVER_INPUT),
                                                     topics.DRIVER_INPUT, topics.STREAM_QOS)
        self.cmd_pub = self.node.create_publisher(msg(topics.REAR_STEER_CMD),
                                                  topics.REAR_STEER_CMD, topics.STREAM_QOS)
        self.states = []
        self.status = []
        self.node.create_subscription(msg(topics.STATE), topics.STATE, self.states.append,
                                      topics.STREAM_QOS)
        self.node.create_subscription(msg(topics.SIM_STATUS), topics.SIM_STATUS,
                                      self.status.append, topics.STATUS_QOS)

    def answer(self, state, rear_rad: float, front_rad: float = 0.01) -> None:
        from fourws_sim.drivers import DriverCommand

        self.driver_pub.publish(conversions.driver_msg(DriverCommand(front_rad * 16, front_rad),
                                                       state.sim_time_s))
        cmd = topics.message_class(topics.REAR_STEER_CMD)()
        cmd.angle_rad = rear_rad
        cmd.state_step = state.step
        cmd.state_stamp = state.header.stamp
        self.cmd_pub.publish(cmd)


@pytest.fixture
def lockstep_sim(rclpy_context):
    from rclpy.executors import SingleThreadedExecutor

    from fourws_ros.simulator_node import SimulatorNode

    sim = _make_node(SimulatorNode, rclpy_context, answer_timeout_s=0.3,
                     expected_state_subscribers=1)
    peer = _Peer(rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(sim)
    executor.add_node(peer.node)
    try:
        yield sim, peer, executor
    finally:
        executor.shutdown()
        sim.destroy_node()
        peer.node.destroy_node()


def test_simulator_refuses_bad_commands_and_never_substitutes_one(lockstep_sim):
    """Lockstep: a non-finite and an out-of-limit command are refused and counted; the tick
    waits for a valid answer and runs on it; an answer that never comes stops the run after
    answer_timeout_s (0.3 s here) naming the controller -- no tick ever runs on an input the
    nodes did not send (zero rear steer would make the numbers depend on the machine's
    load)."""
    sim, peer, executor = lockstep_sim
    assert _spin_until(executor, lambda: len(peer.states) == 1, 20.0)
    s0 = peer.states[0]
    assert s0.step == 0 and s0.sim_time_s == 0.0
    peer.answer(s0, math.nan)
    peer.answer(s0, 10 * sim.limits.rear_angle_limit_rad)
    assert _spin_until(executor, lambda: sim.clock.rejections.total == 3, 10.0)
    # (each answer() also sends a driver input: the second one for the same state is refused)
    assert sim.clock.rejections.counts == {
        f"{topics.REAR_STEER_CMD}: impossible values": 2,
        f"{topics.DRIVER_INPUT}: second answer to one state": 1}
    assert len(peer.states) == 1
    cmd = topics.message_class(topics.REAR_STEER_CMD)()
    cmd.angle_rad = 0.01
    cmd.state_step = s0.step
    cmd.state_stamp = s0.header.stamp
    peer.cmd_pub.publish(cmd)
    assert _spin_until(executor, lambda: len(peer.states) == 2, 10.0)
    s1 = peer.states[1]
    assert s1.step == sim.engine.n_control and sim.clock.stale_commands == 0
    # the valid command was applied (8-DOF applied rear angle = command + roll steer; roll is
    # ~0 after 10 ms of a small steer)
    assert s1.rear_wheel_angle_rad == pytest.approx(0.01, abs=1e-4)
    # no answer to the next state: the run stops, naming the controller, no third state
    from fourws_sim.drivers import DriverCommand
    peer.driver_pub.publish(conversions.driver_msg(DriverCommand(0.16, 0.01), s1.sim_time_s))
    assert _spin_until(executor, lambda: bool(sim.ended), 10.0)
    assert "no rear-steer command for the state at t = 0.01 s" in sim.stop_reason
    assert "controller node (fourws_controller) did not answer" in sim.stop_reason
    assert len(peer.states) == 2
    for s in peer.states:
        assert math.isfinite(s.yaw_rate_radps) and math.isfinite(s.speed_mps)


def test_simulator_stops_on_non_finite_state(lockstep_sim):
    from fourws_sim.errors import DivergedError

    sim, peer, executor = lockstep_sim
    assert _spin_until(executor, lambda: len(peer.states) == 1, 20.0)

    def diverge(*_args, **_kwargs):
        raise DivergedError("state component R is not finite (test)", 0.0)

    sim.engine.sim.step = diverge
    peer.answer(peer.states[0], 0.0)
    assert _spin_until(executor, lambda: sim.finished, 10.0)
    assert "diverged at t = 0.0000 s" in sim.stop_reason
    assert "R is not finite" in sim.stop_reason
    assert _spin_until(executor, lambda: any(not s.running for s in peer.status), 5.0)
    final = [s for s in peer.status if not s.running][-1]
    assert final.stop_reason == sim.stop_reason
    assert len(peer.states) == 1  # nothing after the failure


def test_simulator_refuses_bad_configuration(rclpy_context):
    from rclpy.exceptions import ParameterException

    from fourws_ros.simulator_node import SimulatorNode
    from fourws_sim.errors import ParameterError, UnknownNameError

    with pytest.raises(UnknownNameError, match="unknown model 'warp'.*8dof"):
        _make_node(SimulatorNode, rclpy_context, model="warp")
    with pytest.raises(UnknownNameError, match="unknown tire 'slick'"):
        _make_node(SimulatorNode, rclpy_context, tire="slick")
    with pytest.raises(ParameterError, match="control_period_s.*whole multiple"):
        _make_node(SimulatorNode, rclpy_context, control_period_s=0.0105)
    with pytest.raises(ParameterException, match="integration_step_s"):
        _make_node(SimulatorNode, rclpy_context, integration_step_s=5.0)


# ----------------------------------------------------------------------------- replay
def test_replay_timed_plays_every_message_at_rate(tmp_path, rclpy_context):
    from rclpy.executors import SingleThreadedExecutor

    from fourws_analysis.bag import BagWriter
    from fourws_ros.replay_node import ReplayNode
    from rclpy.serialization import serialize_message

    bag = tmp_path / "bag"
    n = 200  # 2 s of bag time at 100 Hz
    with BagWriter(bag) as writer:
        writer.write_run_config({"law": "fws"})
        for k in range(n):
            msg = conversions.state_msg({"yaw_rate_radps": k * 1e-3}, time_s=k * 0.01, step=k,
                                        model="8dof")
            writer.write_raw(topics.STATE, serialize_message(msg), k * 10_000_000)
    rate = 4.0
    replay = _make_node(ReplayNode, rclpy_context, bag_path=str(bag), rate=rate)
    import rclpy

    sink = rclpy.create_node("sink", context=rclpy_context)
    got, clocks = [], []
    sink.create_subscription(topics.message_class(topics.STATE), topics.STATE,
                             lambda m: got.append((time.monotonic(), m)), topics.STREAM_QOS)
    sink.create_subscription(topics.message_class(topics.CLOCK), topics.CLOCK, clocks.append,
                             topics.CLOCK_QOS)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(replay)
    executor.add_node(sink)
    try:
        assert _spin_until(executor, lambda: len(got) == n and len(clocks) == n, 20.0)
    finally:
        executor.shutdown()
        replay.destroy_node()
        sink.destroy_node()
    yaw = [m.yaw_rate_radps for _, m in got]
    np.testing.assert_allclose(yaw, np.arange(n) * 1e-3)  # all, in order
    wall = got[-1][0] - got[0][0]
    bag_span = (n - 1) * 0.01
    # paced at 4x: never ahead of the bag's time scaled by the rate (a loaded machine may make
    # it late, which says nothing about the replay, so there is no upper bound)
    assert wall >= 0.98 * bag_span / rate
    # one /clock per message, carrying the bag time
    assert conversions.stamp_to_s(clocks[-1].clock) == pytest.approx(bag_span, abs=1e-9)


def test_shipped_parameter_files_are_accepted(rclpy_context, tmp_path):
    import yaml

    from fourws_ros.controller_node import ControllerNode
    from fourws_ros.maneuver_node import ManeuverNode
    from fourws_ros.simulator_node import SimulatorNode
    from fourws_sim.params import CONFIG_DIR

    classes = {"fourws_simulator": SimulatorNode, "fourws_maneuver": ManeuverNode,
               "fourws_controller": ControllerNode}
    for path in sorted((CONFIG_DIR / "params").glob("*.yaml")):
        data = yaml.safe_load(path.read_text())
        for name, cls in classes.items():
            params = dict(data[name]["ros__parameters"])
            params["autostart"] = False if cls is SimulatorNode else params.get("autostart")
            params = {k: v for k, v in params.items() if v is not None}
            node = _make_node(cls, rclpy_context, **params)
            try:
                for key, value in params.items():
                    assert node.get_parameter(key).value == value, (path.name, name, key)
            finally:
                node.destroy_node()


def test_simulator_pause_and_reset_services(lockstep_sim):
    from std_srvs.srv import SetBool, Trigger

    sim, peer, executor = lockstep_sim
    pause = peer.node.create_client(SetBool, topics.SRV_PAUSE)
    reset = peer.node.create_client(Trigger, topics.SRV_RESET)

    def call(client, request):
        assert _spin_until(executor, client.service_is_ready, 10.0)
        future = client.call_async(request)
        assert _spin_until(executor, future.done, 10.0)
        return future.result()

    assert _spin_until(executor, lambda: len(peer.states) == 1, 20.0)
    assert call(pause, SetBool.Request(data=True)).success
    peer.answer(peer.states[0], 0.02)
    _spin_until(executor, lambda: len(peer.states) > 1, 0.5)
    assert len(peer.states) == 1  # paused: the answered tick does not advance
    assert call(pause, SetBool.Request(data=False)).success
    assert _spin_until(executor, lambda: len(peer.states) == 2, 10.0)
    # the tick ran on the answers given while paused (not on a timeout's zero rear steer)
    assert sim.clock.stale_commands == 0
    assert peer.states[1].rear_wheel_angle_rad == pytest.approx(0.02, abs=1e-3)
    assert peer.states[1].sim_time_s == pytest.approx(sim.control_period_s, abs=1e-12)
    res = call(reset, Trigger.Request())
    assert res.success
    assert _spin_until(executor, lambda: len(peer.states) == 3, 10.0)
    back = peer.states[2]
    assert back.step == 0 and back.sim_time_s == 0.0
    assert back.speed_mps == pytest.approx(sim._cfg["initial_speed_mps"], abs=1e-12)


def test_maneuver_node_refuses_bad_maneuver(rclpy_context, tmp_path):
    from fourws_ros.maneuver_node import ManeuverNode
    from fourws_sim.errors import ParameterError, UnknownNameError

    with pytest.raises(UnknownNameError, match="no_such_maneuver"):
        _make_node(ManeuverNode, rclpy_context, maneuver="no_such_maneuver")
    bad = tmp_path / "bad.yaml"
    bad.write_text("type: step_steer\ninitial_speed_mps: 20.0\nduration_s: -1.0\n"
                   "amplitude_rad: 0.01\n")
    with pytest.raises(ParameterError, match="duration_s"):
        _make_node(ManeuverNode, rclpy_context, maneuver=str(bad))
    with pytest.raises(ParameterError, match="maneuver_json"):
        _make_node(ManeuverNode, rclpy_context, maneuver_json="{type: oops")


def test_realtime_command_timeout_falls_back_to_zero_and_recovers(rclpy_context):
    from rclpy.executors import SingleThreadedExecutor

    from fourws_ros.simulator_node import SimulatorNode

    timeout = 0.05  # s of simulation time = 5 control periods
    sim = _make_node(SimulatorNode, rclpy_context, clock_mode="realtime",
                     command_stale_periods=5, realtime_priority=0, status_period_s=0.02,
                     controller_node="peer", maneuver_node="peer")
    peer = _Peer(rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(sim)
    executor.add_node(peer.node)
    try:
        # the wall clock starts once the first state is answered (driver input and command)
        assert _spin_until(executor, lambda: len(peer.states) == 1, 20.0)
        time.sleep(0.2)
        executor.spin_once(timeout_sec=0.05)
        assert len(peer.states) == 1  # nothing runs before the first answers
        peer.answer(peer.states[0], 0.0)
        # then no controller: after the timeout the simulator reports zero rear steer
        assert _spin_until(executor, lambda: any(s.command_timed_out for s in peer.status),
                           5.0)
        flagged = next(s for s in peer.status if s.command_timed_out)
        assert flagged.sim_time_s > timeout - 0.01 and flagged.stale_commands >= 1
        # a controller appears: its commands are used again, the flag clears

        def answering() -> bool:
            if peer.states:
                peer.answer(peer.states[-1], 0.01)
            return bool(peer.status) and not peer.status[-1].command_timed_out
        assert _spin_until(executor, answering, 5.0)
        assert _spin_until(executor, lambda: peer.states[-1].rear_wheel_angle_rad > 0.005, 5.0)
    finally:
        sim.on_shutdown(executor)
        executor.shutdown()
        sim.destroy_node()
        peer.node.destroy_node()


def test_message_conversions_round_trip():
    from rclpy.serialization import deserialize_message, serialize_message

    from fourws_run import codecs
    from fourws_sim.drivers import DriverCommand

    rng = np.random.default_rng(3)
    outputs = {k: float(rng.normal()) for k in conversions.STATE_SCALARS}
    outputs.update({k: rng.normal(size=4) for k in conversions.STATE_WHEELS})
    msg = conversions.state_msg(outputs, time_s=0.123456789, step=123, model="3dof")
    back = conversions.state_to_outputs(deserialize_message(
        serialize_message(msg), topics.message_class(topics.STATE)))
    fast = codecs.parse_state(serialize_message(msg))
    for key in conversions.STATE_SCALARS:
        assert back[key] == outputs[key] == fast[key]
    assert back["sim_time_s"] == 0.123456789
    cmd = DriverCommand(0.1, 0.00625, 0.0, (10.0, 10.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0))
    assert conversions.driver_command(conversions.driver_msg(cmd, 1.0)) == cmd
    with pytest.raises(conversions.NonFiniteError, match="front_wheel_angle_rad"):
        conversions.driver_msg(DriverCommand(0.0, math.inf), 1.0)
    with pytest.raises(conversions.NonFiniteError, match="yaw_rate_radps"):
        conversions.state_msg({**outputs, "yaw_rate_radps": math.nan}, time_s=1.0, step=1,
                              model="8dof")
    # odometry orientation: heading psi about z gives q = (0, 0, sin(psi/2), cos(psi/2))
    msg.heading_rad, msg.roll_rad = 0.5, 0.0
    q = conversions.odometry_msg(msg).pose.pose.orientation
    assert (q.x, q.y) == (0.0, 0.0)
    assert q.z == pytest.approx(math.sin(0.25)) and q.w == pytest.approx(math.cos(0.25))


# ----------------------------------------------------------------------------- matching
def test_expected_subscribers_of_the_default_run():
    """Each topic's subscriber count is that of the run's node set (expected endpoints): the
    state has the maneuver, the controller and the recorder; the command the simulator and
    the recorder; the driver input the simulator, the built-in controller and the
    recorder."""
    from fourws_ros.node_params import expected_subscribers
    from fourws_run.config import RunConfig
    from fourws_run.scenario import load_scenario

    config = RunConfig.from_scenario(load_scenario("default"), "sol1")
    counts = expected_subscribers(config, recorded=True)
    assert counts[topics.STATE] == 3
    assert counts[topics.REAR_STEER_CMD] == 2
    assert counts[topics.DRIVER_INPUT] == 3
    assert all(counts[t] >= 1 for t in config.recorded_topics)
    # the volatile statuses: every reader (a count of 1 could be met by the wrong one) -- the
    # simulator's: maneuver, controller, launcher, recorder; the maneuver's: simulator,
    # launcher, recorder
    assert counts[topics.SIM_STATUS] == 4 and counts[topics.MANEUVER_STATUS] == 3
    unrecorded = expected_subscribers(config, recorded=False)
    assert unrecorded[topics.STATE] == 2 and topics.ODOM not in unrecorded


@pytest.mark.parametrize("text", ["{not json", "[1, 2]", '{"/fourws/state": -1}',
                                  '{"/fourws/state": 2.5}', '{"/fourws/state": 65}',
                                  '{"/fourws/state": true}'])
def test_expected_subscribers_parameter_is_validated(text):
    from fourws_ros.reporting import EXPECTED_SUBSCRIBERS_PARAM, parse_expected_subscribers
    from fourws_sim.errors import ParameterError

    with pytest.raises(ParameterError, match=EXPECTED_SUBSCRIBERS_PARAM):
        parse_expected_subscribers(text)
    assert parse_expected_subscribers("") == {}
    assert parse_expected_subscribers('{"/fourws/state": 3}') == {topics.STATE: 3}


def test_simulator_publishes_nothing_before_its_subscribers_matched(rclpy_context):
    """A volatile publisher never resends what it published before a subscriber matched it,
    so a subscriber that is in the graph but not yet matched (the recorder, under load)
    would miss the run's first states. The simulator expecting two state subscribers sends
    no state while one is matched; once the second matches, both receive the run from its
    first state (step 0)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from fourws_ros.simulator_node import SimulatorNode

    sim = _make_node(SimulatorNode, rclpy_context, answer_timeout_s=30.0,
                     expected_state_subscribers=1,
                     expected_subscribers_json=json.dumps({topics.STATE: 2}))
    peer = _Peer(rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(sim)
    executor.add_node(peer.node)
    late = rclpy.create_node("late_subscriber", context=rclpy_context)
    try:
        # the peer matches (the simulator's own state-subscriber condition holds) ...
        assert _spin_until(executor, lambda: sim.state_pub.get_subscription_count() >= 1, 20.0)
        _spin_until(executor, lambda: bool(peer.states), 1.0)
        # ... but the second expected subscriber is missing: nothing is published
        assert peer.states == [] and sim.matched.unmatched() == [topics.STATE]
        got = []
        late.create_subscription(topics.message_class(topics.STATE), topics.STATE, got.append,
                                 topics.STREAM_QOS)
        executor.add_node(late)
        assert _spin_until(executor, lambda: bool(peer.states) and bool(got), 20.0)
        assert peer.states[0].step == 0 and got[0].step == 0
    finally:
        executor.shutdown()
        sim.destroy_node()
        peer.node.destroy_node()
        late.destroy_node()


def test_nodes_refuse_a_malformed_expected_subscribers_parameter(rclpy_context):
    from fourws_ros.controller_node import ControllerNode
    from fourws_sim.errors import ParameterError

    with pytest.raises(ParameterError, match="expected_subscribers_json"):
        _make_node(ControllerNode, rclpy_context, expected_subscribers_json='{"a": "b"}')


def _maneuver_beside_a_state_source(ctx, **params):
    """A maneuver node and a node ``state_source`` that publishes states to it and collects
    its driver inputs, both on one executor, once the two have matched each other: returns
    ``(maneuver, source, state publisher, driver inputs received, executor)``."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from fourws_ros.maneuver_node import ManeuverNode

    man = _make_node(ManeuverNode, ctx, simulator_node="state_source", **params)
    src = rclpy.create_node("state_source", context=ctx)
    pub = src.create_publisher(topics.message_class(topics.STATE), topics.STATE,
                               topics.STREAM_QOS)
    got: list = []
    src.create_subscription(topics.message_class(topics.DRIVER_INPUT), topics.DRIVER_INPUT,
                            got.append, topics.STREAM_QOS)
    executor = SingleThreadedExecutor(context=ctx)
    for n in (man, src):
        executor.add_node(n)
    assert _spin_until(executor, lambda: pub.get_subscription_count() >= 1
                       and man.driver_pub.get_subscription_count() >= 1, 20.0)
    return man, src, pub, got, executor


def test_maneuver_holds_the_runs_first_state_among_rogue_ones_until_matched(rclpy_context):
    """The maneuver node gets the run's first state (step 0) and then a flood of foreign
    states before its driver-input publisher has matched the run's subscribers: once the
    second subscriber matches it answers exactly the run's state -- one driver input stamped
    t = 0 -- and none of the foreign ones (they are refused by the gate, not held)."""
    import rclpy

    man, src, pub, got, executor = _maneuver_beside_a_state_source(
        rclpy_context, expected_subscribers_json=json.dumps({topics.DRIVER_INPUT: 2}))
    late = rclpy.create_node("late_subscriber", context=rclpy_context)
    try:
        msg = topics.message_class(topics.STATE)()
        msg.speed_mps = 23.6
        msg.step = 0
        pub.publish(msg)  # the run's first state: t = 0, step 0
        for k in range(1, 40):  # foreign: off the run's clock, or not continuing it
            conversions.set_stamp(msg.header.stamp, 1e6 + k)
            msg.sim_time_s = 1e6 + k
            msg.step = 10 ** 9 + k
            pub.publish(msg)
        _spin_until(executor, lambda: bool(got), 1.0)
        assert got == [] and len(man._held) == 1
        late.create_subscription(topics.message_class(topics.DRIVER_INPUT),
                                 topics.DRIVER_INPUT, lambda m: None, topics.STREAM_QOS)
        executor.add_node(late)
        assert _spin_until(executor, lambda: bool(got), 20.0)
        _spin_until(executor, lambda: len(got) > 1, 0.5)
        assert len(got) == 1
        assert (got[0].header.stamp.sec, got[0].header.stamp.nanosec) == (0, 0)
        assert man.gate.rejections.total == 39
    finally:
        executor.shutdown()
        for n in (man, src, late):
            n.destroy_node()


def test_maneuver_refuses_a_non_finite_state_on_the_runs_clock(rclpy_context):
    """A NaN state with the run's step 0 and stamp comes first: it is refused for its content
    (not admitted), so the run's own state 0 that follows is answered -- one driver input,
    stamped t = 0 -- and nothing is counted as a state that does not continue the run."""
    man, src, pub, got, executor = _maneuver_beside_a_state_source(rclpy_context)
    try:
        msg = topics.message_class(topics.STATE)()
        msg.speed_mps = 23.6
        msg.yaw_rate_radps = math.nan
        pub.publish(msg)  # step 0, t = 0, NaN yaw rate
        msg.yaw_rate_radps = 0.0
        pub.publish(msg)  # the run's state 0
        assert _spin_until(executor, lambda: bool(got), 20.0)
        _spin_until(executor, lambda: len(got) > 1, 0.5)
        assert len(got) == 1 and got[0].header.stamp.sec == got[0].header.stamp.nanosec == 0
        assert dict(man.gate.rejections.counts) == {
            f"{topics.STATE}: non-finite state": 1}
    finally:
        executor.shutdown()
        for n in (man, src):
            n.destroy_node()


def test_maneuver_takes_states_from_the_runs_simulator_only(rclpy_context):
    """A foreign node publishes a state on the run's clock (step 0, t = 0, finite) and then
    the run's simulator its own state 0. Content cannot tell them apart: before, whichever
    came first was answered and the other refused as not after it (a foreign state one tick
    ahead of the simulator's then stalled a lockstep run). The foreign one is refused for
    its publisher; the simulator's is answered, once."""
    import rclpy

    man, src, pub, got, executor = _maneuver_beside_a_state_source(rclpy_context)
    rogue = rclpy.create_node("rogue", context=rclpy_context)
    rogue_pub = rogue.create_publisher(topics.message_class(topics.STATE), topics.STATE,
                                       topics.STREAM_QOS)
    executor.add_node(rogue)
    try:
        assert _spin_until(executor, lambda: rogue_pub.get_subscription_count() >= 1, 20.0)
        msg = topics.message_class(topics.STATE)()
        msg.speed_mps = 23.6
        rogue_pub.publish(msg)
        assert _spin_until(executor, lambda: man.gate.rejections.total == 1, 20.0)
        pub.publish(msg)
        assert _spin_until(executor, lambda: bool(got), 20.0)
        _spin_until(executor, lambda: len(got) > 1, 0.5)
        assert len(got) == 1 and got[0].header.stamp.sec == got[0].header.stamp.nanosec == 0
        assert dict(man.gate.rejections.counts) == {
            f"{topics.STATE}: not from the run's node": 1}
        assert man.gate.last_step == 0
    finally:
        executor.shutdown()
        for n in (man, src, rogue):
            n.destroy_node()


# ----------------------------------------------------------------------------- live parameters
def test_controller_live_belief_changes_take_effect_or_are_refused(rclpy_context, tmp_path):
    """The controller's belief while it runs (``ros2 param set``): a scale change takes
    effect on the belief it is given -- also the JSON belief fourws run gives it: the law's
    belief then has 0.6 x the front cornering stiffness of that belief, exactly; a
    ``belief_vehicle`` change while ``belief_vehicle_json`` is set is refused, saying so
    (it would have no effect); with no JSON belief, a missing, UTF-16 or ``chassis: null``
    file is refused naming the problem and leaves the running belief untouched."""
    from rclpy.parameter import Parameter

    from fourws_ros.controller_node import ControllerNode
    from fourws_sim.params import load_vehicle

    given = load_vehicle("table_8_1").with_axle_tires(0.8, 1.0)  # the scenario's belief
    node = _make_node(ControllerNode, rclpy_context, law="sol1",
                      belief_vehicle_json=json.dumps(given.to_dict()))
    try:
        cf = given.axle_tires.cornering_stiffness_front_n_per_rad
        assert node.law.vehicle.axle_tires.cornering_stiffness_front_n_per_rad == cf
        (res,) = node.set_parameters([Parameter("belief_scale_front", value=0.6)])
        assert res.successful, res.reason
        assert node.law.vehicle.axle_tires.cornering_stiffness_front_n_per_rad == 0.6 * cf
        (res,) = node.set_parameters([Parameter("belief_vehicle", value="table_4_4")])
        assert not res.successful and "belief_vehicle_json is set" in res.reason
        assert node.law.vehicle.axle_tires.cornering_stiffness_front_n_per_rad == 0.6 * cf
    finally:
        node.destroy_node()
    node = _make_node(ControllerNode, rclpy_context, law="sol1")
    try:
        before = node.law.vehicle
        utf16 = tmp_path / "utf16.yaml"
        utf16.write_text("chassis: {}\n", encoding="utf-16")
        import yaml

        null = tmp_path / "null.yaml"
        data = yaml.safe_load((Path(__file__).parent.parent / "config/vehicles/table_8_1.yaml")
                              .read_text())
        data["chassis"] = None
        null.write_text(yaml.safe_dump(data))
        for bad, said in ((tmp_path / "missing.yaml", "missing.yaml"), (utf16, "UTF-8"),
                          (null, "chassis")):
            (res,) = node.set_parameters([Parameter("belief_vehicle", value=str(bad))])
            assert not res.successful and said in res.reason, res.reason
            assert node.law.vehicle is before
        (res,) = node.set_parameters([Parameter("belief_vehicle", value="table_4_4")])
        assert res.successful, res.reason
        assert node.law.vehicle.name == "table_4_4"
    finally:
        node.destroy_node()


def test_fourws_nodes_have_no_qos_event_handlers(rclpy_context):
    """rclpy gives each endpoint default QoS event handlers that the single-threaded executor
    visits on every wake-up (fourws_ros/node_base.py): a plain Node carries at least one per
    endpoint created, a FourwsNode none, and handlers asked for are still made (one each)."""
    from rclpy.event_handler import SubscriptionEventCallbacks
    from rclpy.node import Node

    from fourws_ros.node_base import FourwsNode

    msg = topics.message_class(topics.SIM_STATUS)
    qos = topics.TOPIC_QOS[topics.SIM_STATUS]
    counts = {}
    for cls in (Node, FourwsNode):
        node = cls(f"qos_events_{cls.__name__.lower()}", context=rclpy_context)
        try:
            before = len(list(node.waitables))
            node.create_publisher(msg, topics.SIM_STATUS, qos)
            node.create_subscription(msg, topics.SIM_STATUS, lambda m: None, qos)
            counts[cls.__name__] = (before, len(list(node.waitables)))
            if cls is FourwsNode:
                node.create_subscription(msg, topics.SIM_STATUS, lambda m: None, qos,
                                         event_callbacks=SubscriptionEventCallbacks(
                                             message_lost=lambda e: None,
                                             use_default_callbacks=False))
                assert len(list(node.waitables)) == 1
        finally:
            node.destroy_node()
    plain_before, plain_after = counts["Node"]
    assert plain_after - plain_before >= 2
    assert counts["FourwsNode"] == (0, 0)
