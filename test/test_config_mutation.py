# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Property-based mutation of the shipped vehicle, maneuver, scenario and parameter files.

Each example changes one thing in a shipped file (see ``test/config_mutation.py``: values
including NaN, infinities, huge, tiny and negative ones, types, deleted, added and duplicated
keys, null subsystems, YAML 1.2 numbers, alias bombs, deep nesting, random bytes, UTF-16,
Latin-1) and feeds it through the loaders, ``fourws linear`` (in this process, through
``fourws_cli.main.main``) and a node's ``--params-file`` (a few examples, one process each).
Every outcome must be a success or a one-line package error naming the file: never another
exception, never a hang, never an absurd value accepted, never a valid YAML 1.2 number
refused or read differently. Examples are derandomized (the same ones every run) and bounded
in number; the whole module takes well under 30 s.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from config_mutation import (LINEAR_VEHICLES, PARAMS_FILE_MUTATORS, Mutation, classify_call,
                             classify_cli, classify_node, config_dirs, linear_case,
                             linear_speeds, maneuver_target, mutations, reference_dict,
                             scenario_target, vehicle_target)

DIRS = config_dirs()
WORK = Path(tempfile.mkdtemp(prefix="fourws-mutation-test-"))
#: Per-example guard against hangs only (an answer takes well under a second).
LIMIT_S = 60.0


def _settings(n: int) -> settings:
    return settings(max_examples=n, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))


def _check(outcome: tuple[str, str], base: Path, mutation: Mutation) -> None:
    kind, detail = outcome
    assert kind in ("ok", "clear"), (f"{kind} for {base.name}, {mutation.kind}: "
                                     f"{mutation.note}: {detail}")


def _loader_case(kind: str, target, pair: tuple[Path, Mutation]) -> None:
    base, mutation = pair
    path = WORK / f"mutated_{kind}.yaml"
    path.write_bytes(mutation.data)
    reference = reference_dict(kind, base) if mutation.expect == "same" else None
    _check(classify_call(lambda: target(path), mutation, path, reference, LIMIT_S), base,
           mutation)


@_settings(150)
@given(mutations(DIRS["vehicle"]))
def test_vehicle_file_mutations(pair):
    _loader_case("vehicle", vehicle_target, pair)


@_settings(90)
@given(mutations(DIRS["maneuver"]))
def test_maneuver_file_mutations(pair):
    _loader_case("maneuver", maneuver_target, pair)


@_settings(60)
@given(mutations(DIRS["scenario"]))
def test_scenario_file_mutations(pair):
    _loader_case("scenario", scenario_target, pair)


@_settings(80)
@given(mutations([p for p in DIRS["vehicle"] if p.stem in LINEAR_VEHICLES]),
       st.sampled_from(["2dof", "3dof"]), linear_speeds())
def test_fourws_linear_mutations(pair, model, speed):
    base, mutation = pair
    path = WORK / "mutated_linear.yaml"
    path.write_bytes(mutation.data)
    _check(classify_cli(*linear_case(path, model, speed, mutation), LIMIT_S), base, mutation)


_LOCKSTEP = next(p for p in DIRS["params"] if p.stem == "lockstep")


@pytest.mark.usefixtures("ros_domain")
@_settings(4)
@given(mutations(DIRS["params"], PARAMS_FILE_MUTATORS, strict_keys=False),
       st.sampled_from(["controller", "maneuver"]))
@example(pair=(_LOCKSTEP, Mutation("none", _LOCKSTEP.read_bytes(), "any", "shipped file")),
         node="controller")
@example(pair=(_LOCKSTEP, Mutation("bytes", b"\x89PNG\r\n\x1a\n" + bytes(range(256)), "any",
                                   "binary")), node="maneuver")
def test_node_params_file_mutations(pair, node):
    """A few examples only: one node process each (started, or refused with exit code 2);
    the shipped file (it starts) and a binary one (refused) always among them."""
    base, mutation = pair
    path = WORK / "mutated_params.yaml"
    path.write_bytes(mutation.data)
    _check(classify_node(node, path, dict(os.environ), LIMIT_S), base, mutation)
