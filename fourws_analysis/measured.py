# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Measured logs: the one column set of test data, read from CSV, Parquet or a fourws bag.

A fourws run and a test-track log are the same kind of input to ``fourws identify`` and
``fourws validate``: a :class:`MeasuredLog`, the channels of :data:`COLUMNS` on one uniform
time grid, in SI units. :data:`COLUMNS` is the one definition of the column set; ``fourws
export`` writes it, :func:`read_table` reads it, and the README's table is made from it
(:func:`columns_markdown`).

Column names carry their unit (``yaw_rate_radps`` is rad/s). A column may also be given in
the unit engineers usually log it in, under the name that says so (``yaw_rate_degps``,
``steering_wheel_angle_deg``, ``speed_kmh``, ...: :attr:`Column.alternates`); it is converted
to SI on reading. Anything else in the file (other columns, comment lines starting with
``#``) is left alone.

Bad data is refused with one :class:`~fourws_sim.errors.ParameterError` naming the column
and the file: a missing required column, a value that is not a finite number, time that does
not increase or has a gap, a record that is too short, and (files: a fourws bag is SI by
construction) values whose size cannot be right in the stated unit -- beyond what any car
does (:attr:`Column.limit`), or inconsistent with another channel: the lateral acceleration
of a car is its speed times its yaw rate up to its sideslip rate, so with ``a_y`` and ``U r``
of different size one of the three is in another unit than its name says (yaw rate in deg/s,
speed in km/h, acceleration in g).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from fourws_analysis.bag import RunData, hold_sorted, load_bag, resample
from fourws_run.bagfile import BagError
from fourws_run.interface import REAR_STEER_CMD, WHEELS
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers.esc import phaseless_lowpass
from fourws_sim.params import MAX_REAR_ANGLE_RAD, MAX_SPEED_MPS

_DEG = math.pi / 180.0


@dataclass(frozen=True)
class Column:
    """One channel of the measured-log column set.

    Attributes
    ----------
    name : str
        Column name: the fourws channel name, its SI unit in the name.
    unit : str
        The SI unit.
    quantity : str
        What it is (sign convention included).
    required : bool
        Every log must have it.
    limit : float
        No car reaches a larger magnitude (SI): beyond it the unit must be wrong.
    noise_floor : float
        Resolution of test instrumentation for this channel (SI, one standard deviation):
        the least noise an identification assumes (see :mod:`fourws_analysis.fit`).
    alternates : mapping of str to float
        Other accepted column names and the factor from their unit to SI.
    label : str
        Short name with its symbol, for plots and tables.
    display : (float, str)
        Scale from SI to the unit plots and bands use, and that unit.
    """

    name: str
    unit: str
    quantity: str
    required: bool
    limit: float
    noise_floor: float
    alternates: Mapping[str, float]
    label: str
    display: tuple[float, str]


#: The time column: seconds, strictly increasing.
TIME_COLUMN = "time_s"

#: The column set of measured logs, SI, ISO 8855 axes (x forward, y left, z up; a left turn
#: has positive steer, yaw rate and lateral acceleration; roll positive right side down).
#: Limits: the largest magnitude a car (1:10 scale car to heavy truck) can show, spinning
#: included. Noise floors: typical resolution of a test vehicle's instrumentation (a
#: steering robot's angle encoder, a fibre-optic or MEMS inertial platform, an optical or
#: GNSS/INS sideslip sensor), 0.05-0.1 deg, 0.05 deg/s, 0.02 m/s^2.
COLUMNS: tuple[Column, ...] = (
    Column("steering_wheel_angle_rad", "rad", "steering-wheel (hand-wheel) angle, positive "
           "left", True, 6.0 * math.pi, 0.1 * _DEG, {"steering_wheel_angle_deg": _DEG},
           "steering-wheel angle δH", (1.0 / _DEG, "deg")),
    Column("speed_mps", "m/s", "forward speed of the CG", True, MAX_SPEED_MPS, 0.02,
           {"speed_kmh": 1.0 / 3.6}, "speed U", (1.0, "m/s")),
    Column("yaw_rate_radps", "rad/s", "yaw rate, positive left", True, 2.0 * math.pi,
           0.05 * _DEG, {"yaw_rate_degps": _DEG}, "yaw rate r", (1.0 / _DEG, "deg/s")),
    Column("lateral_accel_mps2", "m/s^2", "lateral acceleration of the CG in the body's yaw "
           "frame, positive left", True, 50.0, 0.02, {"lateral_accel_g": 9.80665},
           "lateral acceleration a_y", (1.0, "m/s²")),
    Column("sideslip_rad", "rad", "sideslip angle of the CG, atan(V/U)", False, math.pi,
           0.1 * _DEG, {"sideslip_deg": _DEG}, "sideslip β", (1.0 / _DEG, "deg")),
    Column("roll_rad", "rad", "roll angle of the body, positive right side down", False, 0.5,
           0.05 * _DEG, {"roll_deg": _DEG}, "roll φ", (1.0 / _DEG, "deg")),
    Column("roll_rate_radps", "rad/s", "roll rate of the body", False, 5.0, 0.05 * _DEG,
           {"roll_rate_degps": _DEG}, "roll rate p", (1.0 / _DEG, "deg/s")),
    Column("longitudinal_accel_mps2", "m/s^2", "longitudinal acceleration, positive forward",
           False, 50.0, 0.02, {"longitudinal_accel_g": 9.80665}, "longitudinal acceleration a_x",
           (1.0, "m/s²")),
    Column("rear_wheel_angle_rad", "rad", "rear road-wheel angle commanded by a rear-steer "
           "system (absent: no rear steer)", False, MAX_REAR_ANGLE_RAD, 0.01 * _DEG,
           {"rear_wheel_angle_deg": _DEG}, "rear road-wheel angle δr", (1.0 / _DEG, "deg")),
)
COLUMN_BY_NAME: dict[str, Column] = {c.name: c for c in COLUMNS}
REQUIRED_COLUMNS: tuple[str, ...] = tuple(c.name for c in COLUMNS if c.required)

#: The shortest record and the fewest samples a log may have.
MIN_DURATION_S = 1.0
MIN_SAMPLES = 50
#: Time steps longer than this many times the median step are a gap in the record.
MAX_GAP_STEPS = 3.0
#: Steps that differ from the median by less than this fraction count as one uniform grid
#: (the samples are taken as they are); else the log is interpolated onto the median step.
UNIFORM_TOLERANCE = 1e-6

#: Lateral-acceleration check (module docstring): samples with |a_y| and |U r| at most this,
#: m/s^2 (below the limit the sideslip rate is small), both low-passed at
#: :data:`_KINEMATIC_FILTER_HZ` ...
KINEMATIC_RANGE_MPS2 = 5.0
_KINEMATIC_FILTER_HZ = 1.0
#: ... judged only with this much lateral motion (standard deviation of U r, m/s^2) ...
KINEMATIC_MIN_MPS2 = 0.3
#: ... must have std(a_y) / std(U r) within this range (a factor 3.6, 9.8 or 57 is a unit) ...
KINEMATIC_RATIO = (0.6, 1.6)
#: ... over the samples where both are in range, when they are at least this share of those
#: where a_y is (else over the latter: U r is out of range where a_y is not).
KINEMATIC_MIN_SHARE = 0.2
#: Below this |a_y| (m/s^2, the linear range) no car has more sideslip or roll than this
#: (rad, 11 deg): larger values are in degrees.
LINEAR_RANGE_MPS2 = 4.0
LINEAR_RANGE_ANGLE_RAD = 0.2


@dataclass
class MeasuredLog:
    """A log on a uniform time grid, SI (the channels of :data:`COLUMNS` it has).

    Attributes
    ----------
    name : str
        Label (file stem or the bag's run name).
    source : str
        The file or bag it was read from.
    time_s : ndarray
        Uniform grid, s (the record's own clock).
    dt_s : float
        Grid step, s.
    channels : dict of str to ndarray
        Column name -> values on ``time_s``.
    config : dict
        The run configuration of a fourws bag (vehicle, maneuver, law); empty for a CSV.
    notes : list of str
        What the reader did (conversions, resampling, columns left alone).
    kind : str
        ``csv``, ``parquet`` or ``bag`` (a bag is SI by construction: its units are not
        checked).
    """

    name: str
    source: str
    time_s: np.ndarray
    dt_s: float
    channels: dict[str, np.ndarray]
    config: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    kind: str = "csv"

    @property
    def duration_s(self) -> float:
        """Span of the record, s."""
        return float(self.time_s[-1] - self.time_s[0])

    @property
    def maneuver(self) -> str:
        """Maneuver type of a fourws run (``""`` for a measured log)."""
        man = self.config.get("maneuver")
        return str(man.get("type", "")) if isinstance(man, Mapping) else ""

    def has(self, name: str) -> bool:
        """The log has channel ``name``."""
        return name in self.channels

    def require(self, names: Sequence[str], user: str) -> None:
        """Raise :class:`ParameterError` naming the first of ``names`` the log lacks."""
        for name in names:
            if name not in self.channels:
                raise ParameterError(name, f"missing channel; {user} needs it (the log has "
                                     f"{', '.join(self.channels) or 'none'})", self.source)


def columns_markdown() -> str:
    """The column set as a Markdown table (the README's)."""
    rows = ["| column | unit | quantity | required | also accepted as |", "|---|---|---|---|---|",
            f"| `{TIME_COLUMN}` | s | time, strictly increasing | yes | |"]
    for c in COLUMNS:
        alt = ", ".join(f"`{a}`" for a in c.alternates)
        rows.append(f"| `{c.name}` | {c.unit} | {c.quantity} | {'yes' if c.required else 'no'}"
                    f" | {alt} |")
    return "\n".join(rows)


# ------------------------------------------------------------------------------ reading

def load_log(path: str | Path, dt_s: float | None = None) -> MeasuredLog:
    """A measured log from a CSV or Parquet file or a fourws bag (folder or ``.mcap``).

    Parameters
    ----------
    path : str or Path
    dt_s : float, optional
        Grid step, s (default: the record's median step).

    Raises
    ------
    ParameterError
        Bad data (module docstring), naming the column and the file.
    BagError
        A bag that cannot be read.
    """
    p = Path(path)
    if p.suffix.lower() in (".csv", ".parquet"):
        time_s, columns, notes, line_of = (_read_csv(p) if p.suffix.lower() == ".csv"
                                           else _read_parquet(p))
        log = _from_columns(p.stem, str(p), time_s, columns, notes, line_of, dt_s)
        log.kind = p.suffix.lower()[1:]
        check_log(log)
    elif p.is_dir() or p.suffix == ".mcap":
        log = log_from_run(load_bag(p), dt_s)
        check_log(log, units=False)
    elif not p.exists():
        raise ParameterError("data", f"no such file or bag {str(p)!r}")
    else:
        raise ParameterError("data", f"{str(p)!r} is neither a .csv or .parquet log nor a "
                             "fourws bag (folder or .mcap)")
    return log


def log_from_run(run: RunData, dt_s: float | None = None) -> MeasuredLog:
    """The column set of a fourws run (its bag as :func:`fourws_analysis.bag.load_bag` reads
    it), on the uniform grid of :func:`fourws_analysis.bag.resample`. The steering-wheel angle
    is the driver's; the rear road-wheel angle is the controller's command (the state's
    applied angle adds roll steer, which a model adds itself), when the bag has it."""
    uniform = resample(run, dt_s)
    channels = {c.name: uniform.channels[c.name] for c in COLUMNS
                if c.name in uniform.channels and c.name != "rear_wheel_angle_rad"}
    notes = []
    cmd = run.topics.get(REAR_STEER_CMD)
    if cmd is not None and len(cmd) >= 1 and "angle_rad" in cmd.fields:
        channels["rear_wheel_angle_rad"] = hold(cmd.time_s, cmd.fields["angle_rad"],
                                                uniform.time_s, uniform.dt_s)
    else:
        notes.append(f"the bag has no {REAR_STEER_CMD}: no rear-steer column")
    return MeasuredLog(name=uniform.name, source=run.path, time_s=uniform.time_s,
                       dt_s=uniform.dt_s, channels=channels, config=dict(run.config),
                       notes=notes, kind="bag")


def hold(time_s: np.ndarray, values: np.ndarray, grid: np.ndarray,
         step_s: float) -> np.ndarray:
    """Zero-order hold of ``values`` stamped ``time_s`` (any order) on ``grid`` of step
    ``step_s`` (:func:`fourws_analysis.bag.hold_sorted`)."""
    order = np.argsort(time_s, kind="stable")
    return hold_sorted(np.asarray(time_s, float)[order], np.asarray(values, float)[order],
                       grid, step_s)


def _column_map(names: Sequence[str],
                source: str) -> tuple[dict[str, tuple[str, float]], list[str]]:
    """Which file column gives each channel (name, factor to SI), and the notes."""
    found: dict[str, tuple[str, float]] = {}
    notes: list[str] = []
    for c in COLUMNS:
        given = [(n, 1.0) for n in names if n == c.name] + [
            (n, f) for n in names for a, f in c.alternates.items() if n == a]
        if len(given) > 1:
            raise ParameterError(c.name, f"given twice (columns {', '.join(n for n, _ in given)}"
                                 "); keep one", source)
        if given:
            found[c.name] = given[0]
            if given[0][0] != c.name:
                notes.append(f"{given[0][0]} converted to {c.name}")
    if TIME_COLUMN not in names:
        raise ParameterError(TIME_COLUMN, f"missing column (the file has "
                             f"{', '.join(names) or 'none'})", source)
    missing = [c for c in REQUIRED_COLUMNS if c not in found]
    if missing:
        raise ParameterError(missing[0], f"missing column; a log needs "
                             f"{', '.join((TIME_COLUMN, *REQUIRED_COLUMNS))} (missing: "
                             f"{', '.join(missing)}; the file has {', '.join(names)})", source)
    known = {TIME_COLUMN} | {n for n, _ in found.values()}
    other = [n for n in names if n not in known]
    if other:
        notes.append(f"columns left alone: {', '.join(other[:8])}"
                     + (f" (+{len(other) - 8} more)" if len(other) > 8 else ""))
    return found, notes


def _read_csv(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray], list[str], np.ndarray]:
    """Time, channels (SI), notes and the file line of each sample."""
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ParameterError("data", "not a UTF-8 text file", str(path)) from None
    numbered = [(k + 1, ln) for k, ln in enumerate(text.splitlines())
                if ln.strip() and not ln.lstrip().startswith("#")]
    if not numbered:
        raise ParameterError("data", "empty CSV file (no header row)", str(path))
    line_of = np.array([k for k, _ in numbered[1:]], dtype=int)
    rows = list(csv.reader([ln for _, ln in numbered]))
    header = [h.strip() for h in rows[0]]
    found, notes = _column_map(header, str(path))
    wanted = {TIME_COLUMN: (TIME_COLUMN, 1.0), **found}
    index = {n: header.index(n) for n, _ in wanted.values()}
    values: dict[str, np.ndarray] = {}
    body = rows[1:]
    for channel, (name, factor) in wanted.items():
        k = index[name]
        arr = np.empty(len(body))
        for i, row in enumerate(body):
            try:
                arr[i] = float(row[k])
            except (ValueError, IndexError):
                cell = row[k] if k < len(row) else "<missing>"
                raise ParameterError(name, f"line {line_of[i]}: {cell!r} is not a number",
                                     str(path)) from None
        values[channel] = arr * factor if factor != 1.0 else arr
    time_s = values.pop(TIME_COLUMN)
    return time_s, values, notes, line_of


def _pyarrow_parquet(field_name: str, source: str) -> Any:
    """``pyarrow.parquet``, or a ParameterError saying how to install it."""
    try:
        # pyarrow: a pip-only dependency (no rosdep key); only Parquet files need it
        import pyarrow.parquet as pq
    except ImportError:
        raise ParameterError(field_name, "Parquet needs pyarrow (pip install pyarrow); CSV "
                             "does not", source) from None
    return pq


def _read_parquet(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray], list[str], None]:
    """Time, channels (SI), notes (and no file lines: samples are numbered)."""
    pq = _pyarrow_parquet("data", str(path))
    try:
        table = pq.read_table(path)
    except (OSError, ValueError) as exc:  # pyarrow.ArrowInvalid is a ValueError
        raise ParameterError("data", f"cannot read as Parquet ({exc})", str(path)) from None
    names = list(table.column_names)
    found, notes = _column_map(names, str(path))
    values = {}
    for channel, (name, factor) in {TIME_COLUMN: (TIME_COLUMN, 1.0), **found}.items():
        try:
            arr = np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(name, "is not a numeric column", str(path)) from None
        values[channel] = arr * factor
    time_s = values.pop(TIME_COLUMN)
    return time_s, values, notes, None


def _from_columns(name: str, source: str, time_s: np.ndarray, columns: dict[str, np.ndarray],
                  notes: list[str], line_of: np.ndarray | None,
                  dt_s: float | None) -> MeasuredLog:
    """Check the time column and put the channels on a uniform grid; ``line_of``: the file
    line of each sample (CSV), named in errors."""
    def where(i: int) -> str:
        return f"line {line_of[i]}" if line_of is not None else f"sample {i + 1}"

    for channel, arr in {TIME_COLUMN: time_s, **columns}.items():
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise ParameterError(channel, f"{where(int(bad[0]))}: {float(arr[bad[0]])!r} is "
                                 "not a finite number", source)
    if time_s.size < MIN_SAMPLES:
        raise ParameterError(TIME_COLUMN, f"{time_s.size} samples; a log needs at least "
                             f"{MIN_SAMPLES}", source)
    step = np.diff(time_s)
    back = np.flatnonzero(step <= 0.0)
    if back.size:
        i = int(back[0])
        raise ParameterError(TIME_COLUMN, f"time does not increase at {where(i + 1)} "
                             f"({float(time_s[i + 1])!r} s after {float(time_s[i])!r} s)",
                             source)
    median = float(np.median(step))
    gap = np.flatnonzero(step > MAX_GAP_STEPS * median)
    if gap.size:
        i = int(gap[0])
        raise ParameterError(TIME_COLUMN, f"a gap of {step[i]:.4g} s at {where(i + 1)} (t = "
                             f"{time_s[i]:.6g} s; the median step is {median:.4g} s)", source)
    grid_dt = median if dt_s is None else float(dt_s)
    if not (math.isfinite(grid_dt) and median / 100.0 <= grid_dt
            <= (time_s[-1] - time_s[0]) / (MIN_SAMPLES - 1)):
        raise ParameterError("dt_s", f"{grid_dt!r} s does not resample this log (median step "
                             f"{median:.4g} s over {time_s[-1] - time_s[0]:.4g} s)", source)
    if dt_s is None and np.max(np.abs(step - median)) <= UNIFORM_TOLERANCE * median:
        grid, channels = time_s.copy(), dict(columns)
    else:
        n = int(math.floor((time_s[-1] - time_s[0]) / grid_dt + 1e-9)) + 1
        grid = time_s[0] + grid_dt * np.arange(n)
        channels = {k: np.interp(grid, time_s, v) for k, v in columns.items()}
        notes.append(f"resampled onto a uniform {grid_dt:.4g} s grid (linear interpolation)")
    return MeasuredLog(name=name, source=source, time_s=grid, dt_s=grid_dt, channels=channels,
                       notes=notes)


# ------------------------------------------------------------------------------ checks

def check_log(log: MeasuredLog, units: bool = True) -> None:
    """Refuse a log that lacks a required channel, is too short, has values that are not
    finite, or (``units``) values that cannot be right in their units. A fourws bag is SI by
    construction: :func:`load_log` checks the units of files only (a spinning or diverging
    run is still a true record).

    Raises
    ------
    ParameterError
        Naming the column and the file (module docstring).
    """
    log.require(REQUIRED_COLUMNS, "every log")
    if log.time_s.size < MIN_SAMPLES or log.duration_s < MIN_DURATION_S:
        raise ParameterError(TIME_COLUMN, f"the record spans {log.duration_s:.3g} s in "
                             f"{log.time_s.size} samples; a log needs at least "
                             f"{MIN_DURATION_S:g} s and {MIN_SAMPLES} samples", log.source)
    for c in COLUMNS:
        arr = log.channels.get(c.name)
        if arr is not None and not np.all(np.isfinite(arr)):
            raise ParameterError(c.name, "has values that are not finite numbers", log.source)
    if units:
        check_units(log)


def check_units(log: MeasuredLog) -> None:
    """Refuse values that cannot be right in their units (module docstring).

    Raises
    ------
    ParameterError
        Naming the column and the file.
    """
    for c in COLUMNS:
        arr = log.channels.get(c.name)
        if arr is None:
            continue
        k = int(np.argmax(np.abs(arr)))
        if abs(arr[k]) > c.limit:
            alt = " or ".join(c.alternates)
            raise ParameterError(c.name, f"reaches {arr[k]:.4g} {c.unit} at t = "
                                 f"{log.time_s[k]:.4g} s, beyond what any car does "
                                 f"({c.limit:.4g} {c.unit}): the unit cannot be right"
                                 + (f" (a column named {alt} is converted)" if alt else ""),
                                 log.source)
    _check_kinematics(log)
    ay = log.channels["lateral_accel_mps2"]
    linear = np.abs(ay) <= LINEAR_RANGE_MPS2
    for name in ("sideslip_rad", "roll_rad"):
        arr = log.channels.get(name)
        if arr is None or not np.any(linear):
            continue
        worst = float(np.max(np.abs(arr[linear])))
        if worst > LINEAR_RANGE_ANGLE_RAD:
            raise ParameterError(name, f"reaches {worst:.4g} rad while |a_y| <= "
                                 f"{LINEAR_RANGE_MPS2:g} m/s^2; no car has more than "
                                 f"{LINEAR_RANGE_ANGLE_RAD:g} rad there: is it in degrees?",
                                 log.source)


def _check_kinematics(log: MeasuredLog) -> None:
    """a_y against U r (module docstring), over the samples where both are in the linear range
    (a car sliding at its limit has U r well above a_y; the record before it does not);
    skipped when the log has too little lateral motion there. A log whose U r leaves the
    linear range at most of the samples where a_y stays in it is refused as well: a unit."""
    ay = phaseless_lowpass(log.channels["lateral_accel_mps2"], log.dt_s, _KINEMATIC_FILTER_HZ)
    ur = phaseless_lowpass(log.channels["speed_mps"] * log.channels["yaw_rate_radps"], log.dt_s,
                           _KINEMATIC_FILTER_HZ)
    linear = np.abs(ay) <= KINEMATIC_RANGE_MPS2
    if np.count_nonzero(linear) < MIN_SAMPLES:
        return
    both = linear & (np.abs(ur) <= KINEMATIC_RANGE_MPS2)
    sel = both if np.count_nonzero(both) >= KINEMATIC_MIN_SHARE * np.count_nonzero(linear) \
        else linear
    s_ur, s_ay = float(np.std(ur[sel])), float(np.std(ay[sel]))
    if s_ur < KINEMATIC_MIN_MPS2 and s_ay < KINEMATIC_MIN_MPS2:
        return
    ratio = s_ay / s_ur if s_ur > 0.0 else math.inf
    low, high = KINEMATIC_RATIO
    if not low <= ratio <= high:
        raise ParameterError(
            "lateral_accel_mps2", f"varies {ratio:.3g} times as much as speed_mps * "
            f"yaw_rate_radps (a car's lateral acceleration is U r up to its sideslip rate: "
            f"{low:g}-{high:g}); one of the three is not in its column's unit (yaw rate in "
            "deg/s? speed in km/h? acceleration in g?)", log.source)


# ------------------------------------------------------------------------------ writing

#: File formats of :func:`write_table`.
FORMATS = ("csv", "parquet")


def write_table(log: MeasuredLog, path: str | Path, fmt: str,
                extra: Mapping[str, np.ndarray] | None = None) -> Path:
    """Write ``log`` in the column set (``time_s`` first, then :data:`COLUMNS` in order),
    plus ``extra`` columns on the same grid.

    Parameters
    ----------
    log : MeasuredLog
    path : str or Path
        The file to write.
    fmt : {"csv", "parquet"}
        CSV: a header row and one row per sample, every number written exactly (17
        significant digits). Parquet: float64 columns; the schema metadata
        ``fourws.units`` holds each column's unit and ``fourws.run_config`` the run
        configuration.
    extra : mapping, optional
        More columns (name -> array on ``log.time_s``).
    """
    names = [TIME_COLUMN] + [c.name for c in COLUMNS if c.name in log.channels]
    arrays = [log.time_s] + [log.channels[n] for n in names[1:]]
    for key, arr in (extra or {}).items():
        names.append(key)
        arrays.append(np.asarray(arr, dtype=float))
    out = Path(path)
    if fmt == "csv":
        table = np.column_stack(arrays)
        with open(out, "w", encoding="utf-8", newline="") as fh:
            fh.write(",".join(names) + "\n")
            np.savetxt(fh, table, fmt="%.17g", delimiter=",")
        return out
    if fmt == "parquet":
        pq = _pyarrow_parquet("--format", str(out))
        import pyarrow as pa  # pyarrow: optional (pip only), _pyarrow_parquet found it

        units = {TIME_COLUMN: "s", **{c.name: c.unit for c in COLUMNS}}
        meta = {"fourws.units": json.dumps({n: units.get(n, "") for n in names}),
                "fourws.run_config": json.dumps(log.config)}
        table = pa.table({n: a for n, a in zip(names, arrays)}).replace_schema_metadata(meta)
        pq.write_table(table, out)
        return out
    raise ParameterError("--format", f"unknown format {fmt!r} (valid: {', '.join(FORMATS)})")


def topic_columns(run: RunData, topics: Sequence[str], grid: np.ndarray) -> dict[str, np.ndarray]:
    """Every numeric field of ``topics`` held on ``grid`` (zero-order hold), named
    ``<topic name>.<field>`` (``state.normal_load_n_fl`` for per-wheel fields, wheels FL, FR,
    RL, RR): the units are those of the fields' names.

    Raises
    ------
    BagError
        A topic the bag does not have.
    """
    out: dict[str, np.ndarray] = {}
    for topic in topics:
        arrays = run.topics.get(topic)
        if arrays is None or len(arrays) == 0:
            have = ", ".join(sorted(run.topics))
            raise BagError(f"bag {run.path!r} has no messages on {topic} (it has {have})")
        short = topic.rsplit("/", 1)[-1]
        for key, arr in arrays.fields.items():
            if key.startswith("header.") or arr.dtype.kind not in "fiu":
                continue
            step = float(grid[1] - grid[0]) if grid.size > 1 else 1.0
            if arr.ndim == 1:
                out[f"{short}.{key}"] = hold(arrays.time_s, arr, grid, step)
            elif arr.ndim == 2 and arr.shape[1] == 4:
                for j, wheel in enumerate(WHEELS):
                    out[f"{short}.{key}_{wheel.lower()}"] = hold(arrays.time_s, arr[:, j], grid,
                                                                 step)
    return out


def json_ready(obj: Any) -> Any:
    """``obj`` (mappings, lists and numbers, NumPy's included) as plain JSON values: a
    non-finite number becomes None (JSON has no NaN), NumPy scalars plain ones, keys text."""
    if isinstance(obj, Mapping):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


__all__ = ["COLUMNS", "COLUMN_BY_NAME", "Column", "FORMATS", "MeasuredLog", "REQUIRED_COLUMNS",
           "TIME_COLUMN", "check_log", "check_units", "columns_markdown", "hold", "json_ready",
           "load_log", "log_from_run", "topic_columns", "write_table"]
