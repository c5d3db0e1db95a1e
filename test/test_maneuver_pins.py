# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Regression pin of every shipped maneuver: the offline twin's driver commands and outputs.

Source of the pinned numbers: the code of commit ae11d23 (before the maneuvers became one class
per type) for the ten maneuvers it shipped; the maneuvers added since are pinned with the code
of the commit that added them (torque-input maneuvers on ``8dof-free``, the sine with dwell
resolved for ``fws`` on the default scenario's settings). All were pinned again when the 8-DOF
kernels and the STI tire took their sin, cos and atan from ``fourws_sim.trig`` instead of the C
library (each within 1 ulp of it): every output moved in its last bits only (largest change
9e-14 of the channel's peak over the fifteen runs, compared side by side with the commit
before; end reasons and phases unchanged). Each shipped maneuver file runs on
the offline twin
(:func:`fourws_run.closed_loop.run_closed_loop`) on table_8_1 with ``fws``, its duration cut
to :data:`PIN_DURATION_S` (the run costs a fraction of a second and still covers the settle,
the steer and, for ``constant_radius``, one speed step). The SHA-256 of the recorded driver
commands (every ``DriverInput`` field, float64 bytes in tick order) and of the outputs (every
numeric ``VehicleState`` field) must be unchanged: a restructuring of the maneuver code that is
meant to keep behaviour keeps every bit. The end reason and the phase names are compared as
text. The digests are of IEEE float64 results on x86_64 (numba's LLVM; the 8-DOF's
trigonometry is fourws's own, the Magic Formula tire's and the drivers' the C library's:
another platform's ``sin`` may differ in the last bit, and then these pins must be
regenerated there; :func:`digests` gives them).
"""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np
import pytest

from fourws_run.closed_loop import run_closed_loop
from fourws_run.step_target import resolve_maneuver_for_law
from fourws_run.scenario import load_scenario
from fourws_sim.maneuvers import available_maneuvers, load_maneuver_spec, maneuver_class
from fourws_sim.params import load_vehicle

#: Longest simulated time of a pinned run, s.
PIN_DURATION_S = 10.0
#: Longer for the maneuvers whose event comes later (the release at 10 s).
PIN_DURATIONS = {"steering_release": 12.0}

#: maneuver file -> (driver digest, outputs digest, end reason, phases joined by ",").
PINS: dict[str, tuple[str, str, str, str]] = {
    'brake_in_turn': (
        '3a479602f39934ec34ee4c132c08f411e0f5683bd94f329b5a99e20ff1ef76ba',
        '84f33b1a65ef63345a08e7e5f57d5a8ce2d2b9ec7054ffa71c86c3ba13c371fb',
        'duration',
        'settle,steer,brake,hold',
    ),
    'constant_radius': (
        'cc26ec4fcb1a13d690f1fe3361ebc6d4bd7e234818a14149d0f5734adda79882',
        '8f4e5f89e1443762ac7327131c61d14eb5b7e14b055762564af6111d7e14c40a',
        'duration',
        'speed_6.00_mps,speed_7.00_mps',
    ),
    'double_lane_change': (
        '5babbe23327018811ec2d2a09fe45a481ca0c5dfb1e5b682a62d7a5f29547e55',
        '4ca4c417ad865b9b7413585c1fac93977ddc02ca397fa37108a23792643a34a7',
        'duration',
        'approach,course,exit',
    ),
    'pulse': (
        'af7de9aaf52cd5507ba3d3784edffb00b9a7e00a2506b5af3b0fd2aa230c35c6',
        '5fd6d1636c6bdce1cc5435eb65c1cdc90db39e2670b04e372058f35477d84bc8',
        'duration',
        'settle,pulse,recover',
    ),
    'ramp_steer': (
        '9061413db85e3b49810402aafaced1a651bc3131d1eed853820776a4c956309f',
        '5836c049b8536804c0c91e01090c95b2f57fc867085f55ed37f23cd0d4e3a7a8',
        'duration',
        'settle,steer,hold',
    ),
    'random_steer': (
        '8b1d8dd3f338cc48399aea909cafca9558daaada4b19bd6f809f379e775b0379',
        'd288842901b378625272ace6e6e21dee68423b39e44b060996be96a4d111af76',
        'duration',
        'settle,random',
    ),
    'sine': (
        '1ddb2725da7dd0f67c7a2a830404811730f131b71173bbe400b4dbe945198384',
        '1421a6a2ec262763d68d799dfbb07da9d66ea05d9de5dac454780d9d7a82aab5',
        'duration',
        'settle,steer,recover',
    ),
    'sine_with_dwell': (
        '9ab9d521fbc4b2135f5ae981a067e8ec18b186c460eb7ae925d57b3e36b4aa49',
        '2e152b0faaedea7facf02cf9105a550580ebb1b66c75698da5cb7bb4b58ee312',
        'duration',
        'settle,sine,dwell,return,coast',
    ),
    'slow_ramp_steer': (
        '227d7f9c991158e164b6a6c120879d3b4154f0087673d37c48819dcc6f96981a',
        '637e5b3f2548ef7bfdc0439be42c233ffd1493f3e3fc5832c9993be672994853',
        'lateral acceleration limit reached',
        'settle,steer',
    ),
    'slowly_increasing_steer': (
        '43bc906c965a4f8cd201e031fb3b99b89f57b3d002fc222913812dd627ec3256',
        'e5f457aa8ab207b67c1c5bc2cdcf05203864b0439c9ce5bedf15e229b826fb57',
        'lateral acceleration limit reached',
        'settle,steer',
    ),
    'steering_pulse': (
        '98543433cca02fe7511856bb6ee60b371cebd3ef523984f5365baca61911a842',
        'db8642863203d733d25fe801913331bc47cef02cd6832df6b6d18398d7f20b75',
        'duration',
        'settle,pulse,free',
    ),
    'steering_release': (
        'c5c0e0e9b6ac0135ded6af7ad754c7e80325eed684e6966e48f4e23335e9e551',
        'b63fe340a9b02ab8a953e89406633d3a429c293e47557c69a7688fa1a9961a46',
        'duration',
        'settle,turn_in,hold,released',
    ),
    'steering_torque_step': (
        'd2e82e394557e44a7d7d2b8b0fb7ab5b004382b56ce08dc6e7a6821c9a715cde',
        'b7836258e6a9635426390b8bbbe415c44aaa1e30dac3e3f56257d3e91190131d',
        'duration',
        'settle,steer,hold',
    ),
    'step_steer_85kmh': (
        '16be81e03f056fb9782f598e415b2a9455c437b056f0d1e6c171e2bbc6784eaf',
        '81c613fbf4f0c90f6b578d7e32eb2ca58c2c1252822229ae3843831da2ff113b',
        'duration',
        'settle,steer,hold',
    ),
    'swept_sine': (
        '3ed22ada9686b7e4921e024f9842aaeb741e55a2aee0f095c786c26a21f55a97',
        '2c4a967643f4592c57401ec2e3db447765dc2d1c3e0367f46575e544fb1cca0d',
        'duration',
        'settle,sweep',
    ),
}


def _array_digest(arrays: dict[str, np.ndarray]) -> str:
    sha = hashlib.sha256()
    for key in sorted(arrays):
        sha.update(key.encode())
        sha.update(np.ascontiguousarray(arrays[key], dtype="<f8").tobytes())
    return sha.hexdigest()


def digests(name: str) -> tuple[str, str, str, str]:
    """The pinned quantities of maneuver file ``name`` (see the module docstring)."""
    spec = load_maneuver_spec(name)
    spec = dataclasses.replace(spec, duration_s=min(spec.duration_s,
                                                    PIN_DURATIONS.get(name, PIN_DURATION_S)))
    torque = maneuver_class(spec.type).steering_control == "torque"
    model = "8dof-free" if torque else "8dof"
    spec = resolve_maneuver_for_law(
        dataclasses.replace(load_scenario("default"), maneuver=spec, model=model), "fws")
    res = run_closed_loop(load_vehicle("table_8_1"), spec, "fws", model=model)
    phases = []
    for phase in res.phase:  # run-length encoded: the phase sequence, not every tick
        if not phases or phases[-1] != phase:
            phases.append(phase)
    return (_array_digest(res.driver),
            _array_digest({**res.outputs, "time_s": res.time_s,
                           "rear_angle_rad": res.rear_angle_rad}),
            res.end_reason, ",".join(phases))


def test_every_shipped_maneuver_is_pinned() -> None:
    """A new maneuver file gets its pin (the list is the shipped files' list)."""
    assert sorted(PINS) == sorted(available_maneuvers())


@pytest.mark.parametrize("name", sorted(PINS))
def test_driver_commands_and_outputs_are_bit_identical(name: str) -> None:
    """The twin's driver commands and outputs equal the pinned ones bit for bit."""
    driver, outputs, end, phases = digests(name)
    pin = PINS[name]
    assert (end, phases) == (pin[2], pin[3])
    assert driver == pin[0], "driver commands changed"
    assert outputs == pin[1], "outputs changed"


if __name__ == "__main__":  # print the pins of the current code
    for maneuver in available_maneuvers():
        print(f"    {maneuver!r}: {digests(maneuver)!r},")
