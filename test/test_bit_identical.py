# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""What the restructuring of the run layer must not change: the recorded numbers.

Pinned before the change, at commit fd6e3f7 (the graph of the previous structure): the SHA-256
of every message (its log time and CDR bytes, in time order) of the default scenario's three
bags on the topics whose layout did not change. The status topics gained accounting fields
(published and refused counts) and ``/fourws/run_config`` is the typed run description now,
so those differ by design. A bag recorded by fd6e3f7 is kept as a fixture: it still loads, its
run description still parses, and its run replays bit for bit.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from fourws_analysis.bag import load_bag
from fourws_ros import graph_run, topics
from fourws_run.bagfile import read_bag
from fourws_run.closed_loop import run_twin
from fourws_run.config import RunConfig
from fourws_run.scenario import load_scenario

DATA = Path(__file__).with_name("data")

#: Digests of the default scenario's bags recorded at commit fd6e3f7 (sha256 of the log time
#: as 8 little-endian bytes followed by the CDR bytes, every message of the topic in order).
PINNED_FD6E3F7 = {
    "fws": {
        topics.DRIVER_INPUT: "b3dcd427c10fded25cb06fca18530c29365a43869225f770015c33354005d876",
        topics.IMU: "35546f81bb3947302bad94bba8d5ec0ba48fc0227959ffca12d6c793eab1d03f",
        topics.ODOM: "20ea6bb2b04d124f147aed4a13f74040f4c95c6e3d3bb2486aa8ca739d4cb86c",
        topics.REAR_STEER_CMD: "551b50fd2e7160f22d850f7dee22912f4853fe8166dc682e123e7ba674593df9",
        topics.STATE: "8d0451a67aab7b5bf776a887d506112fbf89f48369df1dd4b5af1532a91ed413",
    },
    "sol1": {
        topics.DRIVER_INPUT: "e02072ae16807ac02c41ac5cc844d5c5925dd4874eb0c0d3b413195ffc002cb5",
        topics.IMU: "c33dcbb037b37fa3aed0b6d5c7ab0a991384991b094aebd791fd4fca0a2a8823",
        topics.ODOM: "4071031c062d8d1b263e490d2b14ed9b046ab74de3f5e78401bdff27a183f428",
        topics.REAR_STEER_CMD: "2b9b346018909939be42937cd99ddcfe946147f87cb36248278b69b7710cfaeb",
        topics.STATE: "387d514c42a14d6c9a16e682e040026f771a8280ecd4e449fbf2013bf5906b09",
    },
    "rwc2_3dof": {
        topics.DRIVER_INPUT: "e0ba2fa0f2d553dc253d1941deaaaf803877762e74f7c118e1f29afcf3242efa",
        topics.IMU: "2da7262cf86b0290c422871c078a1465e54140b58729ad4c5cf5047ddf49a957",
        topics.ODOM: "4723ed1e6ba263ce12f4da8a991a5e190962e33ceae4faf0510663600ae8d55c",
        topics.REAR_STEER_CMD: "b6ea0bf5b6c929b7b7cc10efa42b75fed39beca54458fff9d25f801158043004",
        topics.STATE: "dd24d9c93ec077922a455e9f4233734ac1351c01072a06c4ff77003e0c0d7287",
    },
}


def _digests(bag: Path) -> dict[str, str]:
    messages, check = read_bag(bag)
    assert check.complete, check.problems
    out = {}
    for topic in PINNED_FD6E3F7["fws"]:
        h = hashlib.sha256()
        for m in sorted((m for m in messages if m.topic == topic),
                        key=lambda m: m.log_time_ns):
            h.update(m.log_time_ns.to_bytes(8, "little"))
            h.update(m.data)
        out[topic] = h.hexdigest()
    return out


def test_default_scenario_bags_equal_those_of_fd6e3f7(tmp_path):
    scenario = load_scenario("default")
    for law in scenario.laws:
        run = graph_run.run_graph(RunConfig.from_scenario(scenario, law), tmp_path,
                                  run_name=law)
        assert run.ok, run.reason
        assert _digests(run.bag_path) == PINNED_FD6E3F7[law], law


def test_a_bag_recorded_by_fd6e3f7_loads_and_replays_bit_for_bit():
    """The fixture: the run of test/data/bag_fd6e3f7_short_sol1.yaml recorded by fd6e3f7's
    graph. It carries no recording accounting (older bags did not), so it loads with a
    warning; its version-1 run description becomes a RunConfig whose offline twin gives the
    recorded states exactly."""
    run = load_bag(DATA / "bag_fd6e3f7_short_sol1")
    assert run.complete is None and "not verified" in run.warnings[0]
    config = RunConfig.from_dict(run.config)
    assert config.law == "sol1" and config.maneuver.duration_s == 0.3
    assert config.belief == config.vehicle
    twin = run_twin(config)
    state = run.topics[topics.STATE]
    n = twin.time_s.size
    assert len(state) == n + 1
    np.testing.assert_array_equal(state.fields["sim_time_s"][:n], twin.time_s)
    for name in ("yaw_rate_radps", "lateral_velocity_mps", "roll_rad", "speed_mps"):
        np.testing.assert_array_equal(state.fields[name][:n], twin[name])
