# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""`fourws run` of a scenario series through the real node graph, on the 8-DOF with its free
steering system: one recorded run per member, each equal to its offline twin.

Source: the offline twin (fourws_run.series.run_series), which the lockstep graph reproduces
bit for bit (yaw rate to 1e-9 rad/s, driver torque and angles exactly).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from fourws_analysis.bag import load_bag
from fourws_cli.main import main
from fourws_ros import topics
from fourws_run.scenario import load_scenario
from fourws_run.series import run_series, scenario_runs


def test_free_steering_series_runs_through_the_graph_as_its_twin(tmp_path: Path,
                                                                 capsys) -> None:
    """Two steering pulses (left, right) with sol1 on 8dof-free: two complete bags named after
    the members, each the twin's run; the controller's law saw the free front angle (the
    driver input's angle, the rear command follows it), the torque pulse is in the bag."""
    scenario = {
        "name": "pulses", "vehicle": "table_8_1", "model": "8dof-free", "laws": ["sol1"],
        "maneuver": {"name": "pulse", "type": "steering_pulse", "initial_speed_mps": 25.0,
                     "duration_s": 2.0, "torque_nm": 5.0, "width_s": 0.3, "start_s": 0.3},
        "series": [{"name": "left"}, {"name": "right", "torque_nm": -5.0}],
        "recording": {"output_dir": str(tmp_path / "runs")},
    }
    path = tmp_path / "pulses.yaml"
    path.write_text(yaml.safe_dump(scenario))
    rc = main(["run", str(path), "--name", "p"])
    out = capsys.readouterr().out
    assert rc == 0, out
    # called in this process, not as its own program: the launcher participants were closed,
    # not kept (a kept one makes the caller's process leave with os._exit at its next command)
    from fourws_ros import launcher_node
    assert launcher_node.KEEP_PARTICIPANTS is False
    sc = load_scenario(path)
    members = scenario_runs(sc, "sol1")
    twins = run_series(sc, "sol1", members)
    for member, twin in zip(members, twins):
        bag = load_bag(tmp_path / "runs" / f"p-{member.name}" / "bag")
        assert bag.config["model"] == "8dof-free" and bag.maneuver == "steering_pulse"
        state = bag.topics[topics.STATE]
        n = twin.time_s.size
        np.testing.assert_allclose(state.fields["yaw_rate_radps"][:n], twin["yaw_rate_radps"],
                                   rtol=0, atol=1e-9)
        driver = bag.topics[topics.DRIVER_INPUT]
        for name in ("steering_torque_nm", "front_wheel_angle_rad"):
            np.testing.assert_array_equal(driver.fields[name], twin.driver[name])
        np.testing.assert_allclose(bag.topics[topics.REAR_STEER_CMD].fields["angle_rad"],
                                   twin.rear_angle_rad, rtol=0, atol=1e-12)
        peak = float(np.max(np.abs(driver.fields["steering_torque_nm"])))
        assert peak > 4.0  # the pulse's 5 N m peak, sampled at 10 ms
        assert np.max(np.abs(twin.rear_angle_rad)) > 1e-4  # sol1 steered on the free angle
    left, right = twins
    np.testing.assert_allclose(right["yaw_rate_radps"], -left["yaw_rate_radps"], atol=1e-12)
