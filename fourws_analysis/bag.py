# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Recorded runs as arrays: the one bag-to-arrays loader of the analysis, and resampling.

A recorded run is a rosbag2 bag (MCAP storage) holding the topics of
:mod:`fourws_run.interface`; ``/fourws/run_config`` (``std_msgs/String``, JSON of
:class:`fourws_run.config.RunConfig`) describes the run, or, for a graph started by hand, the
nodes' own ``/fourws/node_config`` messages do. Writing, checksums, accounting and repair are
:mod:`fourws_run.bagfile`; this module reads.

* :func:`load_bag` -- a bag turned into per-topic arrays (:class:`RunData`). Only complete,
  checksum-verified bags load; an incomplete or damaged one is an error naming what is
  missing, unless ``allow_incomplete`` (then :attr:`RunData.complete` is False and
  :attr:`RunData.warnings` says why, and every metric computed from it is flagged).
* :func:`resample` -- one uniform time grid for every channel the analysis uses
  (:class:`UniformRun`), since ROS stamps are not evenly spaced.
* :func:`write_run` -- arrays of an offline simulation written as a bag.

Messages with fixed layout (every ``VehicleState`` of a run has the same ``frame_id`` and
``model`` strings) are decoded in bulk with numpy structured arrays at the offsets their
definitions give (:func:`fourws_run.cdr.decode_many`); this is what lets a 60 s bag at 1 kHz
load in a fraction of a second. Any message the fast path cannot prove identical in layout is
decoded with the rosbags deserializer.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.serde import SerdeError

from fourws_run import interface
from fourws_run.accounting import RunAccount, TopicAccount
from fourws_run.bagfile import BagError, BagWriter, bag_typestore, read_bag, typestore
from fourws_run.cdr import decode_many
from fourws_run.config import USER_LAW, RunConfig
from fourws_run.interface import DRIVER_INPUT as TOPIC_DRIVER
from fourws_run.interface import NODE_CONFIG as TOPIC_NODE_CONFIG
from fourws_run.interface import REAR_STEER_CMD as TOPIC_REAR_CMD
from fourws_run.interface import RUN_CONFIG as TOPIC_RUN_CONFIG
from fourws_run.interface import STATE as TOPIC_STATE
from fourws_run.interface import TOPIC_TYPES
from fourws_sim.errors import FourwsError, ParameterError
from fourws_sim.outcome import DEFAULT_LIMITS, VehicleLimits, Violation, vehicle_limits_from

_NS_PER_S = interface.NS_PER_S
#: Bounds of the resampling step of :func:`resample`: at most this many samples per recorded
#: state period (finer interpolation adds nothing but memory: a 1 ns step on a 20 s run asks
#: for 149 GiB) ...
MAX_UPSAMPLING = 100.0
#: ... and at least this many samples over the run (a step as long as the run leaves one
#: sample, which no metric can use).
MIN_RESAMPLED_POINTS = 16


class MetricUnavailableError(FourwsError):
    """A metric cannot be computed from the given run (wrong maneuver, no excitation, ...)."""


def make_message(msgtype: str, **values: Any) -> Any:
    """Build a message object of ``msgtype`` with every field defaulted (zeros, empty strings).

    Parameters
    ----------
    msgtype : str
        rosbags type name, e.g. ``"fourws/msg/VehicleState"``.
    **values
        Field values to set; nested messages may be given as mappings.
    """
    store = typestore()
    return _default(store, msgtype, values)


def _default(store: Any, msgtype: str, values: Mapping[str, Any]) -> Any:
    cls = store.types[msgtype]
    _, fields = store.fielddefs[msgtype]
    kwargs: dict[str, Any] = {}
    for name, (kind, detail) in fields:
        given = values.get(name)
        if kind == Nodetype.NAME:
            if given is None or isinstance(given, Mapping):
                kwargs[name] = _default(store, detail, given or {})
            else:
                kwargs[name] = given
            continue
        if given is not None:
            if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE) and not isinstance(given, np.ndarray):
                sub = detail[0][1][0]
                given = np.asarray(given, dtype=_NUMPY_TYPES.get(sub, object))
            kwargs[name] = given
        elif kind == Nodetype.BASE:
            kwargs[name] = ("" if detail[0] == "string" else False if detail[0] == "bool"
                            else 0.0 if detail[0].startswith("float") else 0)
        elif kind == Nodetype.ARRAY:
            (sub_kind, sub_detail), length = detail
            if sub_kind == Nodetype.BASE and sub_detail[0] in _NUMPY_TYPES:
                kwargs[name] = np.zeros(length, dtype=_NUMPY_TYPES[sub_detail[0]])
            else:
                kwargs[name] = [_default(store, sub_detail, {}) for _ in range(length)]
        else:
            (sub_kind, sub_detail), _ = detail
            if sub_kind == Nodetype.BASE and sub_detail[0] in _NUMPY_TYPES:
                kwargs[name] = np.zeros(0, dtype=_NUMPY_TYPES[sub_detail[0]])
            else:
                kwargs[name] = []
    return cls(**kwargs)


def stamp(time_s: float) -> dict[str, int]:
    """``builtin_interfaces/Time`` mapping of a time in s (for :func:`make_message`)."""
    ns = int(round(time_s * _NS_PER_S))
    return {"sec": ns // _NS_PER_S, "nanosec": ns % _NS_PER_S}


def stamp_seconds(sec: np.ndarray, nanosec: np.ndarray) -> np.ndarray:
    """Message times in s of ``builtin_interfaces/Time`` fields (:attr:`TopicArrays.time_s`
    of a stamped topic)."""
    return (np.asarray(sec).astype(np.float64)
            + np.asarray(nanosec).astype(np.float64) * 1e-9)


# --------------------------------------------------------------------------------------------
# reader

_NUMPY_TYPES = {
    "bool": np.bool_, "byte": np.uint8, "char": np.uint8, "octet": np.uint8,
    "int8": np.int8, "uint8": np.uint8, "int16": np.int16, "uint16": np.uint16,
    "int32": np.int32, "uint32": np.uint32, "int64": np.int64, "uint64": np.uint64,
    "float32": np.float32, "float64": np.float64,
}


@dataclass
class TopicArrays:
    """All messages of one topic as arrays.

    Attributes
    ----------
    time_s : ndarray
        Message time in s: ``header.stamp`` when the message has one (simulation time),
        else the bag receive time relative to the first message of the bag.
    fields : dict of str to ndarray
        Numeric fields by dotted name (``"header.stamp.sec"``, ``"fy_n"`` with shape (N, 4));
        string fields as object arrays.
    """

    time_s: np.ndarray
    fields: dict[str, np.ndarray]

    def __len__(self) -> int:
        return int(self.time_s.size)


@dataclass
class RunData:
    """A recorded run: its configuration and every decoded topic.

    Attributes
    ----------
    path : str
        The bag.
    config : dict
        The JSON of ``/fourws/run_config`` (empty if the bag has none).
    topics : dict of str to TopicArrays
    warnings : list of str
        Problems that did not stop the reading (e.g. a truncated bag read up to its damage).
    complete : bool or None
        The bag holds every message of its run, checksums verified (None: the bag carries no
        accounting, so completeness is unknown).
    problems : list of str
        What is missing or damaged (empty when complete).
    """

    path: str
    config: dict[str, Any]
    topics: dict[str, TopicArrays] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    complete: bool | None = None
    problems: list[str] = field(default_factory=list)

    @property
    def name(self) -> str:
        """Short label of the run: the bag's folder (or ``.mcap`` file stem); a folder named
        ``bag`` (the launcher's ``<run>/bag`` layout) is labelled by its run folder."""
        path = Path(self.path)
        if path.suffix == ".mcap":
            path = path.with_suffix("")
        if path.name == "bag" and path.parent.name:
            return path.parent.name
        return path.name

    @property
    def maneuver(self) -> str:
        """Maneuver type from the run configuration (``""`` if unknown)."""
        man = self.config.get("maneuver")
        if isinstance(man, Mapping):
            return str(man.get("type", ""))
        return str(man or "")

    @property
    def law(self) -> str:
        """Rear-steer law name from the run configuration (``""`` if unknown)."""
        law = self.config.get("law", "")
        if isinstance(law, Mapping):
            return str(law.get("name", law.get("type", "")))
        return str(law)

    def require(self, topic: str, field_name: str | None = None) -> TopicArrays:
        """Return ``topic``'s arrays, raising :class:`BagError` that names what is missing."""
        arrays = self.topics.get(topic)
        if arrays is None or len(arrays) == 0:
            raise BagError(f"bag {self.path!r} has no messages on {topic}")
        if field_name is not None and field_name not in arrays.fields:
            raise BagError(f"bag {self.path!r}: {topic} has no field {field_name!r}")
        return arrays


def _flatten(store: Any, msg: Any, msgtype: str, prefix: str, out: dict[str, Any]) -> None:
    _, fields = store.fielddefs[msgtype]
    for name, (kind, detail) in fields:
        value = getattr(msg, name)
        full = f"{prefix}{name}"
        if kind == Nodetype.NAME:
            _flatten(store, value, detail, f"{full}.", out)
        elif kind == Nodetype.BASE:
            out[full] = value
        elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE) and isinstance(value, np.ndarray):
            out[full] = value
        elif kind == Nodetype.SEQUENCE and all(isinstance(v, str) for v in value):
            out[full] = list(value)
        # arrays of messages are not used by the analysis


def _decode_generic(msgtype: str, raws: list[bytes], store: Any = None
                    ) -> dict[str, np.ndarray]:
    store = store or typestore()
    rows: list[dict[str, Any]] = []
    for raw in raws:
        flat: dict[str, Any] = {}
        _flatten(store, store.deserialize_cdr(raw, msgtype), msgtype, "", flat)
        rows.append(flat)
    result: dict[str, np.ndarray] = {}
    for key in rows[0]:
        values = [row[key] for row in rows]
        if isinstance(values[0], str):
            result[key] = np.array(values, dtype=object)
        elif isinstance(values[0], (list, np.ndarray)) and (
                isinstance(values[0], list) or len({len(v) for v in values}) > 1):
            # a sequence per message (lengths differ): one object per message
            result[key] = np.empty(len(values), dtype=object)
            result[key][:] = values
        else:
            result[key] = np.asarray(values)
    return result


def _decode(msgtype: str, raws: list[bytes], store: Any) -> dict[str, np.ndarray]:
    fixed = decode_many(msgtype, raws, store)
    return fixed if fixed is not None else _decode_generic(msgtype, raws, store)


#: What the analysis of a run reads of its bag (:func:`resample` and the run description,
#: whose run and node configurations every load decodes): ``fourws analyze`` decodes these
#: only. A graph run's scene (``/tf``, the markers) is about two thirds of its decoding time
#: and no metric reads it.
ANALYSIS_TOPICS = (TOPIC_STATE, TOPIC_DRIVER, TOPIC_REAR_CMD)


def load_bag(path: str | Path, topics: Iterable[str] | None = None, *,
             allow_incomplete: bool = False) -> RunData:
    """Read a rosbag2 bag (directory or ``.mcap`` file) into per-topic arrays.

    Parameters
    ----------
    path : str or Path
        Bag directory (with ``metadata.yaml``) or a single ``.mcap`` file.
    topics : iterable of str, optional
        Topics to decode (default: every topic whose type the typestore knows).
    allow_incomplete : bool
        Load a bag that is damaged or does not hold every message of its run (a killed
        recorder, a failed run): what its checked chunks hold is read, ``complete`` is False
        and ``warnings`` says what is missing. Default: such a bag is an error.

    Returns
    -------
    RunData

    Raises
    ------
    BagError
        If the bag is missing, damaged (a checksum fails, a record is truncated) or incomplete
        (and ``allow_incomplete`` is false), or its run description is not valid JSON.
    """
    path = Path(path)
    messages, check = read_bag(path)
    if check.problems and not allow_incomplete:
        raise BagError(f"bag {str(path)!r} is incomplete or damaged: "
                       + "; ".join(check.problems[:4])
                       + (f" (+{len(check.problems) - 4} more)" if len(check.problems) > 4
                          else "")
                       + "; use --allow-incomplete to analyse what it holds")
    if not messages:
        raise BagError(f"bag {str(path)!r} holds no readable message")
    warnings = [f"incomplete or damaged bag: {p}" for p in check.problems]
    if check.complete is None and not check.problems:
        warnings.append("the bag carries no recording accounting (written by an older fourws "
                        "or another tool): its completeness is not verified")
    wanted = set(topics) if topics is not None else None
    store = bag_typestore(check.schemas)  # the definitions the bag was written with
    raw_by_topic: dict[str, list[bytes]] = {}
    recv_by_topic: dict[str, list[int]] = {}
    types: dict[str, str] = {}
    # file order is chunk order; rosbag2 readers give messages in log-time order
    for m in sorted(messages, key=lambda m: m.log_time_ns):
        if m.msgtype not in store.types or (
                wanted is not None and m.topic not in wanted
                and m.topic not in (TOPIC_RUN_CONFIG, TOPIC_NODE_CONFIG)):
            continue
        raw_by_topic.setdefault(m.topic, []).append(m.data)
        recv_by_topic.setdefault(m.topic, []).append(m.log_time_ns)
        types[m.topic] = m.msgtype
    start = min((t[0] for t in recv_by_topic.values()), default=0)

    config: dict[str, Any] = {}
    result = RunData(path=str(path), config=config, warnings=warnings,
                     complete=check.complete, problems=list(check.problems))
    for topic, raws in raw_by_topic.items():
        msgtype = types[topic]
        try:
            fields = _decode(msgtype, raws, store)
        except (ValueError, IndexError, KeyError, UnicodeDecodeError, SerdeError) as exc:
            raise BagError(f"bag {str(path)!r}: cannot decode {topic} ({msgtype}): {exc}") \
                from None
        if "header.stamp.sec" in fields:
            time_s = stamp_seconds(fields["header.stamp.sec"], fields["header.stamp.nanosec"])
        elif "clock.sec" in fields:
            time_s = stamp_seconds(fields["clock.sec"], fields["clock.nanosec"])
        else:
            time_s = (np.asarray(recv_by_topic[topic], dtype=np.float64) - start) * 1e-9
        result.topics[topic] = TopicArrays(time_s=time_s, fields=fields)
    config.update(_run_description(result))
    return result


def _json_object(run: RunData, topic: str, text: str) -> dict[str, Any]:
    try:
        loaded = json.loads(text)
    except json.JSONDecodeError as exc:
        raise BagError(f"bag {run.path!r}: {topic} is not JSON ({exc})") from None
    if not isinstance(loaded, dict):
        raise BagError(f"bag {run.path!r}: {topic} is not a JSON object")
    return loaded


def _run_description(run: RunData) -> dict[str, Any]:
    """The run configuration mapping: ``/fourws/run_config`` if the bag has one, else put
    together from the nodes' ``/fourws/node_config`` (a graph started by hand); the law of a
    controller that publishes no configuration is the name its commands give."""
    cmd = run.topics.get(TOPIC_REAR_CMD)
    laws = sorted(set(cmd.fields["law"])) if cmd is not None and len(cmd) else []
    if TOPIC_RUN_CONFIG in run.topics:
        config = _json_object(run, TOPIC_RUN_CONFIG,
                              str(run.topics[TOPIC_RUN_CONFIG].fields["data"][-1]))
        if config.get("law") == USER_LAW and laws:
            config["law"] = "+".join(laws)  # a user's controller: the law its commands name
        return config
    if TOPIC_NODE_CONFIG not in run.topics:
        return {}
    parts = [_json_object(run, TOPIC_NODE_CONFIG, str(text))
             for text in run.topics[TOPIC_NODE_CONFIG].fields["data"]]
    try:
        config = RunConfig.from_node_configs(parts, law_label="+".join(laws))
    except (FourwsError, KeyError, TypeError, ValueError) as exc:
        run.warnings.append(f"the nodes' configurations do not describe the run ({exc})")
        return {}
    return config.to_dict()


# --------------------------------------------------------------------------------------------
# uniform resampling

#: Channels of :class:`UniformRun` taken from ``/fourws/state``.
STATE_CHANNELS = ("speed_mps", "lateral_velocity_mps", "yaw_rate_radps", "roll_rad",
                  "roll_rate_radps", "sideslip_rad", "longitudinal_accel_mps2",
                  "lateral_accel_mps2", "front_wheel_angle_rad", "rear_wheel_angle_rad",
                  "x_m", "y_m", "heading_rad")


@dataclass
class UniformRun:
    """A run on one uniform time grid.

    Attributes
    ----------
    name : str
        Label of the run.
    time_s : ndarray
        Uniform grid in s, step ``dt_s``.
    dt_s : float
        Grid step in s.
    channels : dict of str to ndarray
        ``STATE_CHANNELS`` plus ``steering_wheel_angle_rad`` (driver input, or front road-wheel
        angle times the steering ratio when no driver input was recorded) and, when the driver
        input was recorded, ``front_wheel_angle_cmd_rad``: the driver's road-wheel command, and
        ``steering_torque_nm``: the driver's steering-wheel torque (free steering control).
        The state's ``front_wheel_angle_rad`` is the angle actually applied, which in the
        8-DOF includes roll steer; the linear models take the command as their input (roll
        steer is inside the plant), so the analysis uses the command when it exists.
    config : dict
        Run configuration.
    vehicle_breach : Violation or None
        The first recorded state past the run's vehicle limits (:func:`run_limits`; found by
        :func:`resample` on the recorded states, before interpolation): the car spun, drove
        backwards or left the model's range there, and the record after it is no handling
        result. None: no state broke them.
    """

    name: str
    time_s: np.ndarray
    dt_s: float
    channels: dict[str, np.ndarray]
    config: dict[str, Any]
    vehicle_breach: Violation | None = None

    @property
    def maneuver(self) -> str:
        """Maneuver type of the run configuration."""
        man = self.config.get("maneuver")
        return str(man.get("type", "")) if isinstance(man, Mapping) else str(man or "")


def run_limits(config: Mapping[str, Any], source: str | None = None) -> VehicleLimits:
    """The :class:`~fourws_sim.outcome.VehicleLimits` of a run: its maneuver's
    ``vehicle_limits`` in the run configuration (a scenario's are written into it), the
    defaults when it has none.

    Raises
    ------
    ParameterError
        ``maneuver.vehicle_limits`` is malformed.
    """
    man = config.get("maneuver")
    if not isinstance(man, Mapping) or man.get("vehicle_limits") is None:
        return DEFAULT_LIMITS
    return vehicle_limits_from(man["vehicle_limits"], source, prefix="maneuver.vehicle_limits.")


def _monotonic(time_s: np.ndarray, values: np.ndarray,
               order_keep: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Sort by time and drop repeated stamps (keep the last message of a stamp);
    ``order_keep``: :func:`_order_keep` of ``time_s`` (one per topic, shared by its fields)."""
    order, keep = order_keep
    return time_s[order][keep], values[order][keep]


def _order_keep(time_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The stable time order of ``time_s`` and, in that order, which stamps are kept (the
    last of each repeated stamp)."""
    order = np.argsort(time_s, kind="stable")
    t = time_s[order]
    keep = np.ones(t.size, dtype=bool)
    keep[:-1] = np.diff(t) > 0.0
    return order, keep


def resample(run: RunData, dt_s: float | None = None) -> UniformRun:
    """Put the state and driver input of ``run`` on one uniform grid (linear interpolation).

    Parameters
    ----------
    run : RunData
    dt_s : float, optional
        Grid step in s; default the median spacing of the state stamps. At least
        1/:data:`MAX_UPSAMPLING` of that spacing and at most the span of the record over
        ``MIN_RESAMPLED_POINTS - 1``.

    Raises
    ------
    BagError
        If the bag has fewer than two state messages or its stamps do not advance.
    ParameterError
        If ``dt_s`` is outside its bounds (field ``dt_s``, the bag named).
    """
    state = run.require(TOPIC_STATE)
    t_raw = state.time_s
    if t_raw.size < 2:
        raise BagError(f"bag {run.path!r}: {TOPIC_STATE} has {t_raw.size} message(s); "
                       "need at least 2")
    state_order = _order_keep(t_raw)
    order_t, _ = _monotonic(t_raw, t_raw, state_order)
    recorded_dt_s = float(np.median(np.diff(order_t)))
    if not (math.isfinite(recorded_dt_s) and recorded_dt_s > 0.0):
        raise BagError(f"bag {run.path!r}: {TOPIC_STATE} stamps do not advance")
    span_s = float(order_t[-1] - order_t[0])
    if dt_s is None:
        dt_s = recorded_dt_s
    low, high = recorded_dt_s / MAX_UPSAMPLING, span_s / (MIN_RESAMPLED_POINTS - 1)
    if not (isinstance(dt_s, (int, float)) and math.isfinite(dt_s) and low <= dt_s <= high):
        raise ParameterError("dt_s", f"resampling step {dt_s!r} s is outside [{low:.3g}, "
                             f"{high:.3g}] s for this bag (state period {recorded_dt_s:.3g} s "
                             f"over {span_s:.3g} s: at most {MAX_UPSAMPLING:g} samples per "
                             f"recorded state, at least {MIN_RESAMPLED_POINTS} samples)",
                             run.path)
    n = int(math.floor(span_s / dt_s + 1e-9)) + 1
    grid = order_t[0] + dt_s * np.arange(n)
    channels: dict[str, np.ndarray] = {}
    recorded: dict[str, np.ndarray] = {}
    for name in STATE_CHANNELS:
        if name in state.fields:
            t, v = _monotonic(t_raw, state.fields[name].astype(np.float64), state_order)
            channels[name] = np.interp(grid, t, v)
            recorded[name] = v
    breach = run_limits(run.config, f"{run.path}:/fourws/run_config").first_violation(
        order_t, recorded.get("sideslip_rad"), recorded.get("speed_mps"),
        recorded.get("roll_rad"))
    driver = run.topics.get(TOPIC_DRIVER)
    if driver is not None and len(driver) >= 2 and "steering_wheel_angle_rad" in driver.fields:
        # zero-order hold: a driver command holds until the next one
        driver_order = _order_keep(driver.time_s)
        for src, dst in (("steering_wheel_angle_rad", "steering_wheel_angle_rad"),
                         ("front_wheel_angle_rad", "front_wheel_angle_cmd_rad"),
                         ("steering_torque_nm", "steering_torque_nm")):
            if src not in driver.fields:
                continue
            t, v = _monotonic(driver.time_s, driver.fields[src].astype(np.float64),
                              driver_order)
            channels[dst] = hold_sorted(t, v, grid, dt_s)
    else:
        ratio = _steering_ratio(run.config)
        if ratio is not None and "front_wheel_angle_rad" in channels:
            channels["steering_wheel_angle_rad"] = channels["front_wheel_angle_rad"] * ratio
    return UniformRun(name=run.name, time_s=grid, dt_s=float(dt_s), channels=channels,
                      config=run.config, vehicle_breach=breach)


#: A grid point this fraction of a step before a command's stamp counts as at it: the grid
#: t0 + k dt drifts from stamps k dt by k float roundings (with the median step of float
#: stamps 2e-16 s short of 10 ms, by 1e-12 s after 47 s), which a fixed 1e-12 s did not
#: absorb: the command of a 100 Hz record came one sample late from then on.
HOLD_TOLERANCE = 1e-6


def hold_sorted(time_s: np.ndarray, values: np.ndarray, grid: np.ndarray,
                step_s: float) -> np.ndarray:
    """Zero-order hold of ``values`` stamped ``time_s`` (sorted, increasing) on ``grid``: a
    command holds until the next one (before the first: the first); a grid point within
    :data:`HOLD_TOLERANCE` of the grid step ``step_s`` before a stamp takes that stamp's
    command."""
    idx = np.searchsorted(time_s, grid + HOLD_TOLERANCE * step_s, side="right") - 1
    return values[np.clip(idx, 0, time_s.size - 1)]


def _steering_ratio(config: Mapping[str, Any]) -> float | None:
    vehicle = config.get("vehicle")
    if isinstance(vehicle, Mapping):
        steering = vehicle.get("steering")
        if isinstance(steering, Mapping) and isinstance(steering.get("ratio"), (int, float)):
            return float(steering["ratio"])
    return None


def write_run(path: str | Path, time_s: np.ndarray, state: Mapping[str, np.ndarray],
              config: Mapping[str, Any], driver: Mapping[str, np.ndarray] | None = None,
              model: str = "") -> None:
    """Write arrays of a run (e.g. an offline simulation) as a fourws bag.

    Parameters
    ----------
    path : str or Path
        Bag directory to create.
    time_s : ndarray
        Simulation time of each sample, s (becomes ``header.stamp``).
    state : mapping of str to ndarray
        ``VehicleState`` fields (scalars of shape (N,), per-wheel of shape (N, 4)).
    config : mapping
        The run configuration (``/fourws/run_config``).
    driver : mapping of str to ndarray, optional
        ``DriverInput`` fields on the same time grid.
    model : str
        ``VehicleState.model``.
    """
    store = typestore()
    t = np.asarray(time_s, dtype=float)
    topics = [(TOPIC_STATE, state)] + ([(TOPIC_DRIVER, driver)] if driver else [])
    with BagWriter(path) as bag:
        bag.write_run_config(config, 0)
        for topic, values in topics:
            msgtype = TOPIC_TYPES[topic]
            msg = make_message(msgtype, header={"frame_id": "base_link"})
            if topic == TOPIC_STATE:
                msg.model = model
            # only the message's own numeric fields; integers stay integers (CDR types)
            arrays = {k: np.asarray(v) for k, v in values.items()
                      if k not in ("header", "step") and hasattr(msg, k)
                      and isinstance(getattr(msg, k), (int, float, np.ndarray))
                      and not isinstance(getattr(msg, k), bool)}
            ints = {k for k in arrays if isinstance(getattr(msg, k), int)}
            for i, ti in enumerate(t):
                ns = int(round(ti * _NS_PER_S))
                msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(ns, _NS_PER_S)
                if topic == TOPIC_STATE:
                    msg.step = i
                for key, arr in arrays.items():
                    if arr.ndim == 1:
                        setattr(msg, key, int(arr[i]) if key in ints else float(arr[i]))
                    else:
                        getattr(msg, key)[:] = arr[i]
                bag.write_raw(topic, store.serialize_cdr(msg, msgtype), max(ns, 0))
        # the writer is the only publisher here and wrote everything it was given
        account = RunAccount({t: TopicAccount(t, n, n) for t, n in bag.counts.items()})
        bag.set_accounting(account.to_dict(), account.complete)
