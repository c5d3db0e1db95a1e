"""The regulation and standard tests of a recorded run: which the maneuver asks for, computed
from its arrays and its run configuration.

==============================  ==========================================================
maneuver                        metrics
==============================  ==========================================================
``sine_with_dwell``             FMVSS No. 126 yaw-rate ratios, lateral displacement,
                                pass/fail (:mod:`fourws_analysis.fmvss126`)
``slowly_increasing_steer``     the steering-wheel angle of 0.3 g (A of the run)
``steering_release``            ISO 17288-1 return (:mod:`fourws_analysis.iso17288`)
``steering_pulse``              ISO 17288-2 free oscillation
==============================  ==========================================================

The keys of :func:`standard_metrics`' result name the test; the values have ``to_dict``.
"""

from __future__ import annotations

from typing import Any, Callable, Mapping

import numpy as np

from fourws_analysis import fmvss126, iso17288
from fourws_analysis.bag import MetricUnavailableError, UniformRun
from fourws_sim.errors import FourwsError

#: Maneuver type -> the key of its metrics.
STANDARD_KEYS = {"sine_with_dwell": "fmvss126_sine_with_dwell",
                 "slowly_increasing_steer": "fmvss126_slowly_increasing_steer",
                 "steering_release": "iso17288_1_steering_release",
                 "steering_pulse": "iso17288_2_steering_pulse"}


def _number(man: Mapping[str, Any], key: str) -> float | None:
    value = man.get(key)
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) \
        else None


def _channel(ch: Mapping[str, np.ndarray], name: str) -> np.ndarray:
    if name not in ch:
        raise MetricUnavailableError(f"no {name} recorded")
    return ch[name]


def _sine_with_dwell(run: UniformRun, ch: Mapping[str, np.ndarray], man: Mapping[str, Any],
                     vehicle: Any) -> Any:
    return fmvss126.sine_with_dwell_metrics(
        run.time_s, _channel(ch, "steering_wheel_angle_rad"), _channel(ch, "yaw_rate_radps"),
        _channel(ch, "lateral_accel_mps2"), zero_before_s=_number(man, "start_s"),
        amplitude_factor=_number(man, "amplitude_factor"),
        reference_amplitude_rad=_number(man, "reference_amplitude_rad"),
        vehicle_mass_kg=None if vehicle is None else vehicle.chassis.mass_kg,
        x_m=ch.get("x_m"), y_m=ch.get("y_m"), heading_rad=ch.get("heading_rad"))


def _slowly_increasing(run: UniformRun, ch: Mapping[str, np.ndarray], man: Mapping[str, Any],
                       vehicle: Any) -> Any:
    start = _number(man, "start_s")
    return fmvss126.reference_amplitude_metrics(
        run.time_s, _channel(ch, "steering_wheel_angle_rad"), _channel(ch, "lateral_accel_mps2"),
        run.time_s[0] if start is None else start)


def _release(run: UniformRun, ch: Mapping[str, np.ndarray], man: Mapping[str, Any],
             vehicle: Any) -> Any:
    release = _number(man, "release_s")
    if release is None:
        raise MetricUnavailableError("run_config has no maneuver.release_s")
    return iso17288.release_metrics(run.time_s, _channel(ch, "yaw_rate_radps"),
                                    _channel(ch, "steering_wheel_angle_rad"), release,
                                    ch.get("lateral_accel_mps2"))


def _pulse(run: UniformRun, ch: Mapping[str, np.ndarray], man: Mapping[str, Any],
           vehicle: Any) -> Any:
    start, width = _number(man, "start_s"), _number(man, "width_s")
    if start is None or width is None:
        raise MetricUnavailableError("run_config has no maneuver.start_s and width_s")
    return iso17288.pulse_metrics(run.time_s, _channel(ch, "yaw_rate_radps"),
                                  _channel(ch, "steering_wheel_angle_rad"), start, start + width)


_COMPUTE: dict[str, Callable[..., Any]] = {
    "sine_with_dwell": _sine_with_dwell, "slowly_increasing_steer": _slowly_increasing,
    "steering_release": _release, "steering_pulse": _pulse}


def standard_metrics(run: UniformRun, channels: Mapping[str, np.ndarray],
                     vehicle: Any = None) -> tuple[dict[str, Any], dict[str, str]]:
    """The standard test of ``run``'s maneuver (module docstring).

    Returns
    -------
    results : dict
        ``{key: result}`` (empty for other maneuvers).
    unavailable : dict
        ``{key: why}`` when the maneuver asks for a test that cannot be computed.
    """
    kind = run.maneuver
    if kind not in _COMPUTE:
        return {}, {}
    man = run.config.get("maneuver")
    man = man if isinstance(man, Mapping) else {}
    key = STANDARD_KEYS[kind]
    try:
        return {key: _COMPUTE[kind](run, channels, man, vehicle)}, {}
    except FourwsError as exc:  # MetricUnavailableError and friends
        return {}, {key: str(exc)}


__all__ = ["STANDARD_KEYS", "standard_metrics"]
