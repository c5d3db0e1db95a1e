# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""One study run three ways, for the tests that hold the compiled loop to the offline twin:
the compiled point alone, the same point in a block, and the interpreted twin."""

from __future__ import annotations

from typing import Any

from fourws_run.closed_loop import run_closed_loop
from fourws_study.kernel import build_law, prepare_compiled, run_compiled, run_compiled_block


def compiled_and_twin(config: Any, law: Any = None) -> tuple[Any, Any, Any, Any]:
    """``(single, block, twin, prep)`` of a study run ``config`` (``law``: its built law)."""
    law = build_law(config) if law is None else law
    single = run_compiled(config, law)
    prep = prepare_compiled(config, law)
    assert not isinstance(single, str) and not isinstance(prep, str), (single, prep)
    (block,) = run_compiled_block([prep])
    twin = run_closed_loop(config.vehicle, config.maneuver, config.law, model=config.model,
                           dt_s=config.integration_step_s,
                           control_period_s=config.control_period_s,
                           belief_vehicle=config.belief, integrator=config.integrator,
                           law_options=config.law_options, tire=config.tire)
    return single, block, twin, prep
