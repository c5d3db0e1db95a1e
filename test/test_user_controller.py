# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The user's own controller through `fourws run --controller`: a node written from
docs/controller-contract.md alone (test/contract_controller.py) runs in place of fourws's,
and its commands, recomputed from the bag with the law it documents, match to 1e-12."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np

from fourws_analysis.bag import load_bag
from fourws_ros import topics

CONTROLLER = Path(__file__).with_name("contract_controller.py")


def _contract_module():
    spec = importlib.util.spec_from_file_location("contract_controller", CONTROLLER)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_contract_controller_runs_through_fourws_run(tmp_path):
    scenario = tmp_path / "s.yaml"
    scenario.write_text("vehicle: table_8_1\nmaneuver: step_steer_85kmh\nlaws: [fws]\n")
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "run", str(scenario),
                          "--controller", f"python {CONTROLLER}", "--out", str(tmp_path / "o"),
                          "--name", "mine"], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "recording: complete" in res.stdout
    bag = load_bag(tmp_path / "o" / "mine" / "bag")
    # the run records which controller ran and the law its commands name
    assert bag.config["controller"]["command"] == ["python", str(CONTROLLER)]
    cmd = bag.topics[topics.REAR_STEER_CMD]
    assert set(cmd.fields["law"]) == {"contract_zero_sideslip"}
    # every tick answered: 500 commands for the 5 s step at 100 Hz
    drv = bag.topics[topics.DRIVER_INPUT]
    state = bag.topics[topics.STATE]
    assert len(cmd) == len(drv) == 500
    # recompute: the state and driver input of each tick, the documented law
    module = _contract_module()
    belief = bag.config["belief_vehicle"]
    limit = belief["actuators"]["rear_angle_limit_rad"]
    speed = state.fields["speed_mps"][:500]
    expected = np.clip([-module.ratio(belief, u) * f for u, f in
                        zip(speed, drv.fields["front_wheel_angle_rad"])], -limit, limit)
    np.testing.assert_allclose(cmd.fields["angle_rad"], expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(cmd.fields["state_step"], state.fields["step"][:500])
    # and the rear steer was applied: the simulator used every command
    assert abs(expected[-1]) > 1e-4
    # fourws analyze labels the run with the law the commands name (never a guess)
    res = subprocess.run([sys.executable, "-m", "fourws_cli.main", "analyze",
                          str(tmp_path / "o" / "mine" / "bag"), "--json", "--quiet",
                          "--no-sweep"], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    import json
    (entry,) = json.loads(res.stdout)["runs"].values()
    assert entry["law"] == "contract_zero_sideslip"
    assert entry["recording"] == "complete"
