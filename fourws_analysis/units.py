# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Names and units of the quantities the analysis reports: the one table behind every report
table, plot label and ``metrics.json`` key.

Gains are per rad of one of two steering inputs (ISO 7401 reports both):

* ``front_wheel_angle_rad`` -- the front road-wheel angle δf. The analysis takes the angle the
  driver *commands* (``/fourws/driver_input``) whenever the bag has it: that is the input of
  the linear models, and the same for every law. The angle *applied* at the wheels
  (``VehicleState.front_wheel_angle_rad``) adds roll steer, which depends on the law's roll
  response; a run recorded without the driver input can only give gains per applied angle.
* ``steering_wheel_angle_rad`` -- the steering-wheel angle δH = N δf (N the steering ratio),
  the input ISO 7401 and ISO 4138 quote gains against. A gain per δH is the gain per δf
  divided by N (20 log10 N dB lower).

In ``metrics.json`` a gain's key names the output's unit and the input,
``steady_state_gain_<output unit>_per_rad_<input>`` (e.g.
``steady_state_gain_radps_per_rad_steering_wheel``: rad/s of yaw rate per rad of
steering-wheel angle).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Output:
    """A response channel.

    Attributes
    ----------
    channel : str
        Run channel name (``VehicleState`` field).
    label : str
        Words for tables and plots.
    symbol : str
        Symbol (ISO 8855 where it has one).
    unit : str
        Unit of the channel as displayed.
    gain_unit : str
        Unit of a gain of this output per rad of steering input.
    key_unit : str
        The unit as it appears in ``metrics.json`` key names.
    """

    channel: str
    label: str
    symbol: str
    unit: str
    gain_unit: str
    key_unit: str


@dataclass(frozen=True)
class Input:
    """A steering input a gain is per.

    Attributes
    ----------
    channel : str
        Run channel name.
    key : str
        Its name in ``metrics.json`` gain keys.
    label : str
        Words for tables and plots.
    symbol : str
        Symbol (ISO 8855: δH steering-wheel angle; δf front road-wheel angle).
    """

    channel: str
    key: str
    label: str
    symbol: str


#: Responses the analysis reports gains of, in report order.
OUTPUTS: dict[str, Output] = {o.channel: o for o in (
    Output("yaw_rate_radps", "yaw rate", "r", "rad/s", "(1/s)/rad", "radps"),
    Output("lateral_accel_mps2", "lateral acceleration", "a_y", "m/s²", "(m/s²)/rad", "mps2"),
    Output("sideslip_rad", "sideslip", "β", "rad", "rad/rad", "rad"),
    Output("roll_rad", "roll", "φ", "rad", "rad/rad", "rad"),
)}
ROAD_WHEEL = Input("front_wheel_angle_rad", "road_wheel", "front road-wheel angle", "δf")
STEERING_WHEEL = Input("steering_wheel_angle_rad", "steering_wheel", "steering-wheel angle",
                       "δH")
#: Steering inputs gains are per, in report order.
INPUTS: dict[str, Input] = {i.channel: i for i in (ROAD_WHEEL, STEERING_WHEEL)}


def gain_key(output: str, input_channel: str) -> str:
    """``metrics.json`` key of the steady-state gain of ``output`` per ``input_channel``
    (``steady_state_gain`` alone for a channel this table does not know)."""
    out, inp = OUTPUTS.get(output), INPUTS.get(input_channel)
    if out is None or inp is None:
        return "steady_state_gain"
    return f"steady_state_gain_{out.key_unit}_per_rad_{inp.key}"


def steady_key(output: str) -> str:
    """``metrics.json`` key of the steady-state value of ``output`` (with its unit)."""
    out = OUTPUTS.get(output)
    return f"steady_state_{out.key_unit}" if out is not None else "steady_state"


__all__ = ["INPUTS", "Input", "OUTPUTS", "Output", "ROAD_WHEEL", "STEERING_WHEEL", "gain_key",
           "steady_key"]
