"""Regression pin of every shipped maneuver: the offline twin's driver commands and outputs.

Source of the pinned numbers: the code of commit ae11d23 (before the maneuvers became one class
per type) for the ten maneuvers it shipped; the maneuvers added since are pinned with the code
of the commit that added them (torque-input maneuvers on ``8dof-free``, the sine with dwell
resolved for ``fws`` on the default scenario's settings). Each shipped maneuver file runs on
the offline twin
(:func:`fourws_run.closed_loop.run_closed_loop`) on table_8_1 with ``fws``, its duration cut
to :data:`PIN_DURATION_S` (the run costs a fraction of a second and still covers the settle,
the steer and, for ``constant_radius``, one speed step). The SHA-256 of the recorded driver
commands (every ``DriverInput`` field, float64 bytes in tick order) and of the outputs (every
numeric ``VehicleState`` field) must be unchanged: a restructuring of the maneuver code that is
meant to keep behaviour keeps every bit. The end reason and the phase names are compared as
text. The digests are of IEEE float64 results on x86_64 (glibc libm, numba's LLVM); another
platform's ``sin`` may differ in the last bit, and then these pins must be regenerated there
(:func:`digests` prints them).
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
        '85226120c855f7dcba754e38b619a1cd1e2bfcbce44678dcce81a91bc3f5a0b7',
        'duration',
        'settle,steer,brake,hold',
    ),
    'constant_radius': (
        '07fbb955b13c53638a4d64b9e357c6c17f0d910eeb0425e5fe6703ed0364d13e',
        '94dbc487ce15567deb0a51b6c98f1dd1a702dacea54641d563cf4f7d57a84328',
        'duration',
        'speed_6.00_mps,speed_7.00_mps',
    ),
    'double_lane_change': (
        'd589c9cd9728922b962c85a96348be1f83e3aa89e4f81b2d6f24111d7e403819',
        'd1ee700c688e82e8595a8076a153caff0b7d1061677c8965e1a835cc9e05878b',
        'duration',
        'approach,course,exit',
    ),
    'pulse': (
        'af7de9aaf52cd5507ba3d3784edffb00b9a7e00a2506b5af3b0fd2aa230c35c6',
        '8e9241dc39c1761b33b3c0807cc05b17385071c1a4f4679ed85201eb385b4d63',
        'duration',
        'settle,pulse,recover',
    ),
    'ramp_steer': (
        'b3d01034df685d2b933ce5af5a2b58124f6214ac3666d962d484ff6031eee807',
        '9d67587e338c5a436719df5644fb35e6cf9b96b3d3bfa22e584d9d1afb8bde20',
        'duration',
        'settle,steer,hold',
    ),
    'random_steer': (
        '8b1d8dd3f338cc48399aea909cafca9558daaada4b19bd6f809f379e775b0379',
        '5cbd6a3c922775e32fc3a1846895b48b10ed16d1bff2c581962e81e93c2814fc',
        'duration',
        'settle,random',
    ),
    'sine': (
        '1ddb2725da7dd0f67c7a2a830404811730f131b71173bbe400b4dbe945198384',
        '4c272b853f49703dda49cd899ae74def51cb0b21e162d63fa9c85af684779f17',
        'duration',
        'settle,steer,recover',
    ),
    'slow_ramp_steer': (
        '227d7f9c991158e164b6a6c120879d3b4154f0087673d37c48819dcc6f96981a',
        'c7473205ce62673cf0c7d90d2ca51d4e65bb41b602e0a6087d61d77a22b89dfc',
        'lateral acceleration limit reached',
        'settle,steer',
    ),
    'step_steer_85kmh': (
        '16be81e03f056fb9782f598e415b2a9455c437b056f0d1e6c171e2bbc6784eaf',
        'a1a99722a8121f21e7bcba1dc8e32bdf584985172dba426ab775bb654a3d88a2',
        'duration',
        'settle,steer,hold',
    ),
    'swept_sine': (
        '3ed22ada9686b7e4921e024f9842aaeb741e55a2aee0f095c786c26a21f55a97',
        '2dada252af810d0f811d1683cfe6df65cce3092a1e5dc37d7884b5547a3f5fd8',
        'duration',
        'settle,sweep',
    ),
    'sine_with_dwell': (
        '9ab9d521fbc4b2135f5ae981a067e8ec18b186c460eb7ae925d57b3e36b4aa49',
        '0837cd400bfbc3b205d086faa44dce57c8aabc14d86d0daeba4af5a1c6d09764',
        'duration',
        'settle,sine,dwell,return,coast',
    ),
    'slowly_increasing_steer': (
        '43bc906c965a4f8cd201e031fb3b99b89f57b3d002fc222913812dd627ec3256',
        '19aebd20a919e6c9208b39b13af7195aed6c45267419ffbc7b73e6fcd2f014f0',
        'lateral acceleration limit reached',
        'settle,steer',
    ),
    'steering_pulse': (
        '98543433cca02fe7511856bb6ee60b371cebd3ef523984f5365baca61911a842',
        '3f36091005f220e7433065021d0796700463917b8b8b56be3bcd558788af6d82',
        'duration',
        'settle,pulse,free',
    ),
    'steering_release': (
        'e9688f531defe37e82006bb11a9f26adfd73265bfea6c4ce21139c647492f9e1',
        'b49c4e390fb579dc7df9d69fb01c356a88b19e3d850e2afc8af9a5c3ab828a00',
        'duration',
        'settle,turn_in,hold,released',
    ),
    'steering_torque_step': (
        'd2e82e394557e44a7d7d2b8b0fb7ab5b004382b56ce08dc6e7a6821c9a715cde',
        'a4134890b74a19f53d19e542b1783da82eeb2ea651b9108fae6f067fe4596b5f',
        'duration',
        'settle,steer,hold',
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
    """The twin's driver commands and outputs equal those of commit ae11d23 bit for bit."""
    driver, outputs, end, phases = digests(name)
    pin = PINS[name]
    assert (end, phases) == (pin[2], pin[3])
    assert driver == pin[0], "driver commands changed"
    assert outputs == pin[1], "outputs changed"


if __name__ == "__main__":  # print the pins of the current code
    for maneuver in available_maneuvers():
        print(f"    {maneuver!r}: {digests(maneuver)!r},")
