# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The verdict of a run, without ROS: the vehicle-outcome rule (fourws_sim.outcome) and the
outcome rules of a graph run (fourws_run.verdict), each against a hand-made case."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fourws_run.closed_loop import run_closed_loop
from fourws_run.config import RealtimeDemand, RunConfig
from fourws_run.record import Outcome, RunRecord
from fourws_run.scenario import load_scenario, scenario_from_mapping
from fourws_run.verdict import BagCheck, ManeuverReport, SimReport, conclude
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers import load_maneuver_spec, maneuver_spec_from_mapping
from fourws_sim.outcome import (DEFAULT_LIMITS, DIVERGED, NO_BREACH, REVERSING_BREACH,
                                ROLL_BREACH, SIDESLIP_BREACH, SPUN, VehicleLimits, breach_code)
from fourws_sim.params import load_vehicle

DEG = math.pi / 180.0


# ----------------------------------------------------------------------------- the rule
@pytest.mark.parametrize("state, kind", [
    ({"sideslip_rad": 19.9 * DEG, "speed_mps": 20.0, "roll_rad": 0.05}, None),
    ({"sideslip_rad": -20.1 * DEG, "speed_mps": 20.0, "roll_rad": 0.05}, SPUN),
    ({"sideslip_rad": 0.0, "speed_mps": -0.51, "roll_rad": 0.0}, SPUN),
    ({"sideslip_rad": 0.0, "speed_mps": -0.49, "roll_rad": 0.0}, None),
    ({"sideslip_rad": 0.0, "speed_mps": 20.0, "roll_rad": -30.1 * DEG}, DIVERGED),
    ({"speed_mps": 20.0}, None),  # a model without sideslip/roll outputs: not checked
])
def test_the_rule_on_single_states(state, kind):
    """The defaults (20 deg, -0.5 m/s, 30 deg; module docstring) decide, each on its side of
    the limit; roll beyond the model's range is checked first (diverged)."""
    found = DEFAULT_LIMITS.violation(1.25, state)
    assert (found.kind if found else None) == kind
    if found:
        assert found.time_s == 1.25 and "t = 1.25 s" in found.reason


def test_breach_code_is_one_rule_for_numbers_arrays_and_compiled_code():
    """The predicate of VehicleLimits (breach_code) gives each hand-made state the code of the
    module docstring's order (roll first, then sideslip, then reversing), as a number, element
    by element on arrays (the time-history form) and compiled by numba as the study's loop
    compiles it: states on both sides of each default limit, NaN (not checked) and states
    past two limits."""
    import numba  # the compiled form only

    cases = [((19.9 * DEG, 20.0, 0.05), NO_BREACH), ((-20.1 * DEG, 20.0, 0.0), SIDESLIP_BREACH),
             ((0.0, -0.51, 0.0), REVERSING_BREACH), ((0.0, -0.49, 0.0), NO_BREACH),
             ((0.0, 20.0, -30.1 * DEG), ROLL_BREACH), ((math.nan,) * 3, NO_BREACH),
             ((25 * DEG, -1.0, 31 * DEG), ROLL_BREACH), ((25 * DEG, -1.0, 0.0), SIDESLIP_BREACH)]
    limits = (DEFAULT_LIMITS.max_sideslip_rad, DEFAULT_LIMITS.min_forward_speed_mps,
              DEFAULT_LIMITS.max_roll_rad)
    assert limits == (20 * DEG, -0.5, 30 * DEG)
    compiled = numba.njit(breach_code)
    for state, code in cases:
        assert breach_code(*state, *limits) == compiled(*state, *limits) == code, state
    arrays = [np.array(column) for column in zip(*(state for state, _ in cases))]
    assert breach_code(*arrays, *limits).tolist() == [code for _, code in cases]


def test_first_violation_is_the_per_state_rule_sample_by_sample():
    """The time-history form finds the first sample the per-state form refuses, with the
    same reason (the study's and the analysis' form of the one rule)."""
    t = np.arange(100) * 0.01
    beta = np.linspace(0.0, 0.5, 100)  # crosses 20 deg = 0.349 rad at sample 70
    speed = np.full(100, 20.0)
    roll = np.zeros(100)
    found = DEFAULT_LIMITS.first_violation(t, beta, speed, roll)
    k = int(np.argmax(np.abs(beta) > 20 * DEG))
    assert k == 70 and found is not None and found.time_s == t[k]
    single = DEFAULT_LIMITS.violation(t[k], {"sideslip_rad": beta[k], "speed_mps": speed[k],
                                             "roll_rad": roll[k]})
    assert found == single
    assert DEFAULT_LIMITS.first_violation(t[:60], beta[:60], speed[:60], roll[:60]) is None


def test_limits_from_files_and_scenarios():
    """A maneuver file's and a scenario's ``vehicle_limits``: validated (unknown key, a value
    out of its plausible range refused naming the field), the scenario's replaces the
    maneuver's, and a default maneuver's mapping has no such key (older run records stay
    as they were)."""
    base = load_maneuver_spec("step_steer_85kmh").to_dict()
    assert "vehicle_limits" not in base
    spec = maneuver_spec_from_mapping({**base, "vehicle_limits": {"max_sideslip_rad": 0.5}})
    assert spec.vehicle_limits == VehicleLimits(max_sideslip_rad=0.5)
    assert spec.to_dict()["vehicle_limits"]["max_sideslip_rad"] == 0.5
    with pytest.raises(ParameterError, match="vehicle_limits.max_spin"):
        maneuver_spec_from_mapping({**base, "vehicle_limits": {"max_spin": 0.5}})
    with pytest.raises(ParameterError, match="vehicle_limits.max_roll_rad"):
        maneuver_spec_from_mapping({**base, "vehicle_limits": {"max_roll_rad": 10.0}})
    sc = scenario_from_mapping({"vehicle": "table_8_1", "maneuver": "step_steer_85kmh",
                                "vehicle_limits": {"max_sideslip_rad": 0.2}})
    config = RunConfig.from_scenario(sc, "fws")
    assert config.maneuver.vehicle_limits.max_sideslip_rad == 0.2
    assert RunConfig.from_dict(config.to_dict()).maneuver.vehicle_limits == \
        config.maneuver.vehicle_limits


def test_a_step_steer_at_85_mps_ends_spun_in_the_twin():
    """A step steer with initial_speed_mps 85 (km/h meant): the car spins. The twin ends at
    the first state beyond 20 deg of sideslip, as spun, with every state before it within
    the limit -- the same state the maneuver node ends the graph run at."""
    spec = load_maneuver_spec("step_steer_85kmh").to_dict()
    res = run_closed_loop(load_vehicle("table_8_1"), {**spec, "initial_speed_mps": 85.0},
                          "fws")
    assert res.end_kind == SPUN and "the car spun" in res.end_reason
    beta = np.abs(res["sideslip_rad"])
    assert beta.max() <= 20 * DEG  # the recorded ticks are the ones before the spin
    assert abs(res.final_outputs["sideslip_rad"]) > 20 * DEG
    # its time is the tick after the last recorded one
    assert f"t = {res.time_s[-1] + 0.01:.2f} s" in res.end_reason


# ----------------------------------------------------------------------------- graph verdict
def _record(tmp_path: Path) -> RunRecord:
    return RunRecord(Outcome.FAILED, "", "sol1", tmp_path, None)


def _sim(**kw) -> SimReport:
    base = dict(sim_time_s=5.0, steps=5000, final=True, end_reason="maneuver done",
                commands_accepted=500)
    return SimReport(**{**base, **kw})


def _config(clock: str = "lockstep", **realtime) -> RunConfig:
    sc = load_scenario("default")
    return RunConfig.from_scenario(sc, "sol1").replace(
        clock_mode=clock, realtime=RealtimeDemand(**realtime), recorded_topics=())


def test_a_spun_maneuver_is_never_ok(tmp_path):
    """The maneuver ended 'spun': outcome spun (exit 3) with the rule's sentence; 'diverged'
    (roll beyond the model): diverged."""
    rec = _record(tmp_path)
    conclude(rec, _config(), _sim(), ManeuverReport(
        "spun", "spun: the car spun: |sideslip| 20.3 deg at t = 1.68 s is beyond 20 deg",
        True), False, "", None)
    assert rec.outcome == Outcome.SPUN and rec.exit_code == 3 and not rec.ok
    assert rec.reason.startswith("the car spun: |sideslip| 20.3 deg")
    rec = _record(tmp_path)
    conclude(rec, _config(), _sim(), ManeuverReport("diverged", "diverged: roll ...", True),
             False, "", None)
    assert rec.outcome == Outcome.DIVERGED and rec.exit_code == 3


def test_realtime_stale_and_refused_commands_beyond_the_share_fail(tmp_path):
    """Realtime, 500 control ticks (5000 steps at 1 kHz, 100 Hz control): 5 stale ticks are
    1 % (allowed by the default 1 %), 6 are 1.2 % (fail, naming the controller); 480 of 500
    commands refused as impossible values fail the run too."""
    done = ManeuverReport("completed", "completed", True)
    rec = _record(tmp_path)
    conclude(rec, _config("realtime"), _sim(stale_commands=5), done, False, "", None)
    assert rec.ok and rec.control_ticks == 500
    rec = _record(tmp_path)
    conclude(rec, _config("realtime"), _sim(stale_commands=6), done, False, "", None)
    assert rec.outcome == Outcome.FAILED
    assert "6 of 500 control ticks (1.2%)" in rec.reason and "fourws_controller" in rec.reason
    rec = _record(tmp_path)
    conclude(rec, _config("realtime"), _sim(commands_accepted=20, rejections={
        "/fourws/rear_steer_cmd: impossible values": 480}), done, False, "", None)
    assert rec.outcome == Outcome.FAILED and "480 of 500 commands (96.0%)" in rec.reason


def test_a_controller_that_fell_behind_beside_a_foreign_flood_is_failed_naming_both(tmp_path):
    """Realtime, 41 of 500 ticks without a fresh command while the recorder counted 9000
    foreign states and 4000 foreign driver inputs: the reason names the controller and the
    flooding publisher (seen: a realtime run beside a rogue failed naming only the
    controller). Without foreign messages the reason is the controller's alone."""
    from fourws_run.accounting import RunAccount

    done = ManeuverReport("completed", "completed", True)
    rec = _record(tmp_path)
    rec.account = RunAccount({}, foreign_publishers={"/fourws/state from rogue": 9000,
                                                     "/fourws/driver_input from rogue": 4000})
    conclude(rec, _config("realtime"), _sim(stale_commands=41), done, False, "", None)
    assert rec.outcome == Outcome.FAILED
    assert rec.reason == ("the controller node (fourws_controller): 41 of 500 control ticks "
                          "(8.2%) ran without a fresh command (zero rear steer), beyond the "
                          "allowed 1.0% (realtime.max_stale_share); foreign messages: 9000 on "
                          "/fourws/state from rogue, 4000 on /fourws/driver_input from rogue")
    rec = _record(tmp_path)
    conclude(rec, _config("realtime"), _sim(stale_commands=41), done, False, "", None)
    assert rec.reason.endswith("(realtime.max_stale_share)")


def test_a_realtime_run_behind_real_time_says_so_and_fails_below_the_demand(tmp_path):
    """Simulated 5 s in 6.25 s of wall time: 0.80x. Without a demand the run is ok and its
    summary line says it fell behind; with min_realtime_factor 0.95 it fails saying both
    numbers."""
    done = ManeuverReport("completed", "completed", True)
    rec = _record(tmp_path)
    rec.wall_time_s = 6.25
    conclude(rec, _config("realtime"), _sim(overruns=6), done, False, "", None)
    assert rec.ok and rec.behind_real_time
    assert "behind real time: 0.80x, 6 overruns" in rec.summary_lines()[0]
    rec = _record(tmp_path)
    rec.wall_time_s = 6.25
    conclude(rec, _config("realtime", min_realtime_factor=0.95), _sim(overruns=6), done,
             False, "", None)
    assert rec.outcome == Outcome.FAILED and "0.80x real time, below" in rec.reason
    assert "0.95" in rec.reason


def test_a_failed_run_never_says_recording_complete(tmp_path):
    """A run that failed at start-up while its recorder held the five messages sent: the
    summary says the bag holds what was published, never 'recording: complete'."""
    from fourws_run.accounting import RunAccount, TopicAccount

    rec = _record(tmp_path)
    rec.bag_path = tmp_path / "bag"
    rec.account = RunAccount({"/fourws/node_config": TopicAccount("/fourws/node_config", 5, 5)})
    conclude(rec, _config(), None, None, False, "graph incomplete", None)
    text = "\n".join(rec.summary_lines())
    assert rec.outcome == Outcome.FAILED and "recording: complete" not in text
    assert "holds every message the nodes published before the run stopped" in text


def test_a_recorder_that_never_completes_for_a_second_publisher_names_the_publisher(tmp_path):
    """A foreign command the simulator applied (lockstep cannot tell publishers apart) counts
    as applied, but the recorder, which stores the run's nodes' messages only, never holds it:
    the launcher fails on the recorder after its grace; the reason names the cause, the second
    publisher, first (seen: '4000 stored but the simulator applied 4001' was all it said)."""
    done = ManeuverReport("completed", "completed", True)
    late = ("the recorder did not hold every message 90 s after the simulation ended "
            "(/fourws/rear_steer_cmd: 4000 stored but the simulator applied 4001)")
    rec = _record(tmp_path)
    conclude(rec, _config(), _sim(rejections={
        "/fourws/rear_steer_cmd: second answer to one state": 12}), done, False, late, None)
    assert rec.outcome == Outcome.FAILED
    assert rec.reason == ("a second publisher answered states of this run (12x "
                          "fourws_simulator: /fourws/rear_steer_cmd: second answer to one "
                          "state): the inputs applied are not certain; then: " + late)
    rec = _record(tmp_path)  # without second answers the recorder's failure stands alone
    conclude(rec, _config(), _sim(), done, False, late, None)
    assert rec.outcome == Outcome.FAILED and rec.reason == late


def test_a_bag_incomplete_for_a_second_publisher_names_the_publisher_first(tmp_path):
    """The same, when the recorder closed in time and the bag check finds the gap (the
    launcher has no failure of its own): seen in a clean clone, 'recording incomplete:
    /fourws/rear_steer_cmd: 4000 stored but the simulator applied 4001' alone."""
    done = ManeuverReport("completed", "completed", True)
    gap = "/fourws/rear_steer_cmd: 4000 stored but the simulator applied 4001"
    second = {"/fourws/rear_steer_cmd: second answer to one state": 12}
    rec = _record(tmp_path)
    conclude(rec, _config(), _sim(rejections=second), done, False, "",
             BagCheck(problems=[gap]))
    assert rec.outcome == Outcome.FAILED
    assert rec.reason.startswith("a second publisher answered states of this run (12x ")
    assert rec.reason.endswith("; then: recording incomplete: " + gap)
    rec = _record(tmp_path)
    conclude(rec, _config(), _sim(), done, False, "", BagCheck(problems=[gap]))
    assert rec.outcome == Outcome.FAILED and rec.reason == "recording incomplete: " + gap


def test_a_bag_incomplete_beside_a_silent_realtime_controller_names_the_controller_first(
        tmp_path):
    """Realtime, the controller stopped (SIGSTOP) just after the start: 400 of 500 ticks ran
    without a fresh command, and the recorder, which had matched the controller's writer only
    after it stopped, holds none of its 27 commands. The cause is the controller, named
    first (seen beside the test suite: 'recording incomplete: /fourws/rear_steer_cmd: 0
    stored but the simulator applied 27' alone)."""
    done = ManeuverReport("completed", "completed", True)
    gap = "/fourws/rear_steer_cmd: 0 stored but the simulator applied 27"
    rec = _record(tmp_path)
    conclude(rec, _config("realtime"), _sim(stale_commands=400, commands_accepted=27), done,
             False, "", BagCheck(problems=[gap]))
    assert rec.outcome == Outcome.FAILED
    assert rec.reason.startswith("the controller node (fourws_controller): 400 of 500 "
                                 "control ticks (80.0%) ran without a fresh command")
    assert rec.reason.endswith("; then: recording incomplete: " + gap)
    rec = _record(tmp_path)  # a controller within its share: the gap alone
    conclude(rec, _config("realtime"), _sim(stale_commands=5), done, False, "",
             BagCheck(problems=[gap]))
    assert rec.reason == "recording incomplete: " + gap


def test_a_run_stopped_for_a_missing_answer_names_the_second_publisher_of_states(tmp_path):
    """The maneuver answered a foreign copy of a state and refused the run's own as not after
    the previous one; the simulator stopped the run for the driver input that never came (the
    launcher's failure). The reason names the copies first, then the stop (seen beside a CPU
    hog: the simulator's stop alone, which blamed the maneuver node)."""
    from fourws_run.ticks import NOT_AFTER_PREVIOUS

    stopped = ("node fourws_simulator stopped the run: no driver input for the state at "
               "t = 9.09 s within 60 s (wall time)")
    refused = {f"/fourws/state: {NOT_AFTER_PREVIOUS}": 1}
    man = ManeuverReport("", "", False, rejections=refused)
    rec = _record(tmp_path)
    conclude(rec, _config(), _sim(), man, False, stopped, None)
    assert rec.outcome == Outcome.FAILED
    assert rec.reason == ("a second publisher sent states on this run's clock (1x "
                          f"fourws_maneuver: /fourws/state: {NOT_AFTER_PREVIOUS}): the answers "
                          "applied may be to its states; then: " + stopped)
    rec = _record(tmp_path)  # without refused states the stop stands alone
    conclude(rec, _config(), _sim(), ManeuverReport("", "", False), False, stopped, None)
    assert rec.outcome == Outcome.FAILED and rec.reason == stopped
