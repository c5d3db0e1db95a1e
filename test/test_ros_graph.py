# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""End-to-end tests of the fourws node graph: real nodes, separate processes, isolated domain.

Every run goes through :func:`fourws_ros.graph_run.run_graph` (what ``fourws run`` does), which
reserves its own ROS domain and limits discovery to this machine.
"""

from __future__ import annotations

import dataclasses
import json
import math
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.exceptions import McapError
from mcap.records import Channel, Message
from mcap.stream_reader import StreamReader

from fourws_analysis.bag import load_bag
from fourws_ros import graph_run, topics
from fourws_run.closed_loop import run_closed_loop
from fourws_run.config import ControllerSpec, RunConfig
from fourws_sim.maneuvers import maneuver_spec_from_mapping
from fourws_run.scenario import load_scenario


def run_graph(sc, law, out, controller=None, **kw):
    """One graph run of scenario ``sc`` with ``law`` (or ``controller``)."""
    return graph_run.run_graph(RunConfig.from_scenario(sc, law, controller), out, **kw)


def _scenario(duration_s: float | None = None, **changes):
    sc = load_scenario("default")
    if duration_s is not None:
        spec = sc.maneuver.to_dict()
        spec["duration_s"] = duration_s
        changes["maneuver"] = maneuver_spec_from_mapping(spec)
    return dataclasses.replace(sc, **changes)


@pytest.fixture(scope="module")
def sol1_run(tmp_path_factory):
    """The default scenario (ISO 7401 step steer, 85 km/h, table_8_1, 8-DOF) with sol1,
    lockstep, through the real graph."""
    sc = _scenario()
    run = run_graph(sc, "sol1", tmp_path_factory.mktemp("graph"), run_name="sol1")
    return sc, run


def test_lockstep_sol1_counts(sol1_run):
    sc, run = sol1_run
    assert run.ok, run.reason
    ticks = int(round(sc.maneuver.duration_s / sc.control_period_s))  # 5 s / 10 ms = 500
    viz_every = int(round(0.02 / sc.control_period_s))  # odom/imu at the 20 ms default
    counts = run.message_counts
    # one state per tick plus the final state (at t = duration the maneuver is done)
    assert counts[topics.STATE] == ticks + 1
    # every tick but the final one is answered by the maneuver and the controller
    assert counts[topics.DRIVER_INPUT] == ticks
    assert counts[topics.REAR_STEER_CMD] == ticks
    assert counts[topics.ODOM] == counts[topics.IMU] == ticks // viz_every + 1
    assert counts[topics.RUN_CONFIG] == 1
    assert counts[topics.MANEUVER_STATUS] >= 1 and counts[topics.SIM_STATUS] >= 1
    assert run.stale_commands == 0
    assert math.isclose(run.sim_time_s, sc.maneuver.duration_s, abs_tol=sc.control_period_s)


def test_lockstep_sol1_equals_offline_closed_loop(sol1_run):
    sc, run = sol1_run
    vehicle = sc.build_vehicle()
    ref = run_closed_loop(vehicle, sc.maneuver, "sol1", model=sc.model,
                          dt_s=sc.integration_step_s, control_period_s=sc.control_period_s,
                          belief_vehicle=sc.build_belief(vehicle), integrator=sc.integrator)
    bag = load_bag(run.bag_path)
    state = bag.topics[topics.STATE]
    n = ref.time_s.size
    np.testing.assert_allclose(state.fields["sim_time_s"][:n], ref.time_s, rtol=0, atol=1e-12)
    np.testing.assert_allclose(state.fields["yaw_rate_radps"][:n], ref["yaw_rate_radps"],
                               rtol=0, atol=1e-9)
    assert abs(state.fields["yaw_rate_radps"][n] - ref.final_outputs["yaw_rate_radps"]) < 1e-9
    np.testing.assert_allclose(bag.topics[topics.REAR_STEER_CMD].fields["angle_rad"],
                               ref.rear_angle_rad, rtol=0, atol=1e-12)
    np.testing.assert_allclose(bag.topics[topics.DRIVER_INPUT].fields["front_wheel_angle_rad"],
                               ref.driver["front_wheel_angle_rad"], rtol=0, atol=1e-15)
    # the step steer really turned the car (yaw rate of ~0.1 rad/s, not a trivial zero run)
    assert np.max(np.abs(ref["yaw_rate_radps"])) > 0.05
    # the bag describes itself
    assert bag.config["law"] == "sol1" and bag.maneuver == "step_steer"
    assert bag.config["clock_mode"] == "lockstep"


def test_realtime_run_records_at_configured_rate(tmp_path):
    period = 0.005  # 200 Hz state
    sc = _scenario(duration_s=3.0, clock_mode="realtime", state_period_s=period)
    run = run_graph(sc, "sol1", tmp_path, run_name="rt")
    assert run.ok, run.reason
    state = load_bag(run.bag_path).topics[topics.STATE]
    span = state.time_s[-1] - state.time_s[0]
    rate_hz = (len(state) - 1) / span
    assert abs(rate_hz - 1.0 / period) <= 0.02 / period
    # every state from the first published one (step = one state period) to the end
    np.testing.assert_allclose(np.diff(state.time_s), period, atol=1e-9)
    assert run.complete
    # (how closely simulated time follows the wall clock, the step lateness and the overruns
    # depend on the machine's load: `fourws bench-graph` reports them; a test asserting them
    # would fail on a loaded machine for no fault of fourws)


def test_example_controller_replaces_builtin(tmp_path):
    ratio = -0.2
    sc = _scenario(duration_s=1.5)
    example = (sys.executable, "-m", "fourws_cli.main", "node", "example_controller")
    run = run_graph(sc, "fws", tmp_path, run_name="example",
                    controller=ControllerSpec(example),
                    node_overrides={"fourws_controller": {"rear_ratio": ratio}})
    assert run.ok, run.reason
    bag = load_bag(run.bag_path)
    cmd = bag.topics[topics.REAR_STEER_CMD]
    drv = bag.topics[topics.DRIVER_INPUT]
    assert len(cmd) == len(drv) == int(round(1.5 / sc.control_period_s))
    assert set(cmd.fields["law"]) == {"example_ratio"}
    np.testing.assert_array_equal(cmd.time_s, drv.time_s)
    np.testing.assert_allclose(cmd.fields["angle_rad"],
                               ratio * drv.fields["front_wheel_angle_rad"], rtol=0, atol=1e-15)
    # counter-phase rear steer was applied: the rear road-wheel angle of the last state
    state = bag.topics[topics.STATE]
    assert state.fields["rear_wheel_angle_rad"][-1] < -0.1 * abs(
        drv.fields["front_wheel_angle_rad"][-1])


def test_unknown_law_fails_with_reason(tmp_path):
    run = run_graph(_scenario(duration_s=1.0), "no_such_law", tmp_path, run_name="bad")
    assert not run.ok
    assert "unknown law 'no_such_law'" in run.reason and "sol1" in run.reason
    assert run.exit_codes["fourws_controller"] == 2


def test_controller_crash_stops_run_and_keeps_bag(tmp_path):
    def kill_controller(group):
        group.child("fourws_controller").proc.send_signal(signal.SIGKILL)

    run = run_graph(_scenario(duration_s=30.0), "sol1", tmp_path, run_name="crash",
                    on_running=kill_controller)
    assert not run.ok
    assert "fourws_controller" in run.reason and "SIGKILL" in run.reason
    # every other process is gone (no orphans) and the recorder closed a bag holding every
    # message the surviving nodes published up to the crash (their final counts say so); a
    # command the killed controller had in flight may have reached the simulator but not the
    # recorder, and then the bag says so
    assert all(code is not None for code in run.exit_codes.values())
    assert run.account is not None
    if run.account.complete:
        assert run.exit_codes["fourws_recorder"] == 0
    else:
        assert run.exit_codes["fourws_recorder"] == 4
        assert all(topics.REAR_STEER_CMD in p for p in run.account.problems())
    bag = load_bag(run.bag_path, allow_incomplete=True)
    assert len(bag.topics[topics.STATE]) >= 1
    assert all(np.isfinite(bag.topics[topics.STATE].fields["yaw_rate_radps"]))


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "fourws_cli.main", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def test_cli_run_rejects_malformed_scenario(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("vehicle: table_8_1\nmaneuver: step_steer_85kmh\nclock_mode: warp\n")
    res = _cli("run", str(bad), "--out", str(tmp_path), cwd=tmp_path)
    assert res.returncode == 2
    assert "clock_mode" in res.stderr and str(bad) in res.stderr
    broken = tmp_path / "broken.yaml"
    broken.write_text("vehicle: [table_8_1\n")
    res = _cli("run", str(broken), cwd=tmp_path)
    assert res.returncode == 2 and "not valid YAML" in res.stderr
    res = _cli("run", "--law", "nope", cwd=tmp_path)
    assert res.returncode == 2 and "unknown law 'nope'" in res.stderr
    assert not any(tmp_path.glob("runs/*"))  # nothing was started


def test_replayed_driver_input_drives_new_run_with_other_law(sol1_run, tmp_path):
    # the sol1 run's recorded driver, replayed tick by tick, drives a run with another law
    sc, first = sol1_run
    run = run_graph(sc, "ff_zero_sideslip", tmp_path, run_name="replayed",
                    replay_driver_from=first.bag_path)
    assert run.ok, run.reason
    old, new = load_bag(first.bag_path), load_bag(run.bag_path)
    drv_old, drv_new = old.topics[topics.DRIVER_INPUT], new.topics[topics.DRIVER_INPUT]
    assert len(drv_new) == len(drv_old)
    np.testing.assert_array_equal(drv_new.fields["front_wheel_angle_rad"],
                                  drv_old.fields["front_wheel_angle_rad"])
    np.testing.assert_array_equal(drv_new.fields["drive_torque_nm"],
                                  drv_old.fields["drive_torque_nm"])
    # and the new law really steered the rear wheels differently
    cmd_old = old.topics[topics.REAR_STEER_CMD].fields["angle_rad"]
    cmd_new = new.topics[topics.REAR_STEER_CMD].fields["angle_rad"]
    assert set(new.topics[topics.REAR_STEER_CMD].fields["law"]) == {"ff_zero_sideslip"}
    assert np.max(np.abs(cmd_new - cmd_old)) > 1e-4


def _node_processes(marker: str) -> list[int]:
    """PIDs of live processes whose command line contains ``marker``."""
    pids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
            status = (entry / "status").read_text()
        except OSError:
            continue
        if marker in cmdline and "params.yaml" in cmdline and "\nState:\tZ" not in status:
            pids.append(int(entry.name))
    return pids


def _states_on_disk(out: Path) -> int:
    """States in the bag files under ``out`` as far as written (a file being recorded)."""
    n = 0
    for path in out.glob("*/bag/*.mcap"):
        channels: dict[int, str] = {}
        with open(path, "rb") as f:
            try:
                for record in StreamReader(f).records:
                    if isinstance(record, Channel):
                        channels[record.id] = record.topic
                    elif isinstance(record, Message) and \
                            channels.get(record.channel_id) == topics.STATE:
                        n += 1
            except McapError:  # the file ends mid-record while it is being written
                pass
    return n


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGKILL, -9)])
def test_launcher_signal_leaves_no_orphans_and_a_bag(tmp_path, sig, code):
    import time

    scenario = tmp_path / "long.yaml"
    scenario.write_text("vehicle: table_8_1\nmaneuver: {type: step_steer, initial_speed_mps: "
                        "20.0, duration_s: 60.0, amplitude_rad: 0.01}\nlaws: [sol1]\n"
                        "clock_mode: realtime\n")
    out = tmp_path / "runs"
    proc = subprocess.Popen([sys.executable, "-m", "fourws_cli.main", "run", str(scenario),
                             "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    marker = f"{out}/"  # the node processes' --params-file lies in the run folder
    deadline = time.monotonic() + 60
    # running: the recorder's periodic flushes (every 0.5 s simulated) have put states on
    # disk (counted in the file, not its size: the robot description alone is ~40 kB)
    while time.monotonic() < deadline and _states_on_disk(out) < 20:
        time.sleep(0.2)
    assert len(_node_processes(marker)) == 4  # simulator, maneuver, controller, recorder
    grown = _states_on_disk(out) >= 20
    proc.send_signal(sig)
    said = proc.communicate(timeout=60)[0]
    assert proc.returncode == code, said
    deadline = time.monotonic() + 20
    while _node_processes(marker) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert _node_processes(marker) == []
    (bag,) = out.glob("*/bag")
    run = load_bag(bag, allow_incomplete=True)
    assert (bag / "metadata.yaml").is_file()  # finalized, even with the launcher killed
    state = run.topics[topics.STATE]
    logs = "".join(f"--- {log.name}:\n" + "\n".join(log.read_text().splitlines()[-6:]) + "\n"
                   for log in sorted(out.glob("*/logs/*.log")))
    assert grown, f"the run did not get going within 60 s:\n{said}\n{logs}"
    assert len(state) > 10, f"{said}\n{logs}"  # the run up to the signal, at 100 Hz from 0
    np.testing.assert_allclose(np.diff(state.time_s), 0.01, atol=1e-9)  # none lost


def test_controller_that_stops_answering_fails_the_run(tmp_path):
    """A controller stopped (SIGSTOP) mid-run: lockstep waits for its answer, never runs a tick
    on anything else, and after answer_timeout_s (2 s here) the run fails naming the
    controller. (A recorder starved beside other load holds a tick up to recorder_timeout_s,
    60 s, not 2 s: the verdict names the missing answer, not a slow recorder.) The bag holds
    the run up to there, each tick with its command (and at most the command the controller
    was sending when it was stopped: a SIGSTOP can land between a write's delivery to the
    recorder and its delivery to the simulator)."""
    def freeze_controller(group):
        group.child("fourws_controller").proc.send_signal(signal.SIGSTOP)

    sc = _scenario(30.0)
    run = run_graph(sc, "sol1", tmp_path, run_name="frozen", on_running=freeze_controller,
                    node_overrides={"fourws_simulator": {"answer_timeout_s": 2.0}})
    assert not run.ok and "the controller node (fourws_controller) did not answer" in run.reason
    assert run.stale_commands == 0
    bag = load_bag(run.bag_path, allow_incomplete=True)
    state = bag.topics[topics.STATE]
    cmds = bag.topics[topics.REAR_STEER_CMD]
    ticks = run.control_ticks  # the ticks that ran, each on its command
    assert ticks > 0 and len(state) == ticks + 1  # and the state awaiting the answer
    status = bag.topics[topics.SIM_STATUS].fields
    assert status["final"][-1] and status["commands_accepted"][-1] == ticks
    assert ticks <= len(cmds) <= ticks + 1
    # each command answers the state of its tick, in order (10 steps of 1 ms per 10 ms tick)
    np.testing.assert_array_equal(cmds.fields["state_step"], 10 * np.arange(len(cmds)))
    np.testing.assert_array_equal(state.fields["step"][:len(cmds)], cmds.fields["state_step"])
    assert run.exit_codes["fourws_controller"] is not None  # the stopped process was ended


def test_bench_graph_reports_a_realtime_run(tmp_path):
    """`fourws bench-graph` with only a realtime run (the soak command, shortened to 1 s):
    one JSON object whose realtime run is ok and complete, every recorded topic stored as
    published, states every 5 ms (200 Hz) with no gap, and the overrun times read from the
    bag (a list); two start-up runs and two `fourws run` commands, each ok, whose start-up
    (launch to simulation start) is part of its whole run. Timings are reported, not asserted."""
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "bench-graph", "--json",
                          "--lockstep-seconds", "0", "--realtime-seconds", "1",
                          "--startups", "2",
                          "--keep", str(tmp_path / "keep")],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    out = json.loads(res.stdout)
    assert "lockstep_ok" not in out  # skipped
    assert out["realtime_ok"] and out["realtime_recording"]["complete"]
    for topic, n in out["realtime_recording"]["topics"].items():
        assert n["published"] == n["stored"] and n["lost"] == 0, topic
    assert out["realtime_state_rate_hz"] == pytest.approx(200.0, rel=1e-6)
    assert isinstance(out["realtime_overrun_times_s"], list)
    assert out["startup_runs"] == 2 and out["startup_runs_ok"]
    assert 0 < out["startup_s_min"] <= out["startup_s_median"] <= out["startup_s_max"]
    # each run's start-up is part of it, so every order statistic is
    for stat in ("min", "median", "max"):
        assert out[f"startup_s_{stat}"] < out[f"startup_run_wall_s_{stat}"], stat
        # and so is a command's: its graph came up before it exited
        assert 0 < out[f"command_startup_s_{stat}"] < out[f"command_wall_s_{stat}"], stat
    assert out["command_runs_ok"]
