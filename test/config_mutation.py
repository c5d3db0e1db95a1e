"""Mutations of the shipped configuration files and the classification of what fourws does
with them: shared by ``test/test_config_mutation.py`` (hypothesis, bounded) and the
before/after table of bad-input handling::

    .venv/bin/python test/config_mutation.py --examples 300     # prints the table

A mutation changes one thing in a shipped vehicle, maneuver, scenario or ROS parameter file: a
value (random floats including NaN, infinities, huge, tiny and negative ones, or the shipped
value scaled by 10^-9 .. 10^9), a type, a deleted, added or duplicated key, a null subsystem, a
number rewritten in YAML 1.2 exponent form, an alias bomb, deep nesting, or the bytes (random
bytes, UTF-16, Latin-1, NUL). Each mutation carries what a correct reader must do with it:

* ``reject`` -- it must be refused: non-finite or |x| >= 1e15 in any SI field, a value
  10^9 times the shipped one, a duplicate key, an unknown key, an alias bomb, UTF-16/Latin-1/NUL
  bytes;
* ``same`` -- it must load to exactly what the shipped file gives (YAML 1.2 numbers);
* ``any`` -- success or a clear error are both right (e.g. a deleted key).

Outcomes: ``ok`` (accepted, as allowed), ``clear`` (one-line package error naming the file),
``unclear`` (a package error of several lines, or not naming the file), ``refused_valid`` (an
error for a ``same`` mutation), ``traceback`` (any other exception), ``hang`` (no answer within
the time limit), ``silent_wrong`` (accepted although it must be refused, or loaded to a
different value).
"""

from __future__ import annotations

import contextlib
import copy
import io
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import yaml
from hypothesis import strategies as st

OUTCOMES = ("ok", "clear", "unclear", "refused_valid", "traceback", "hang", "silent_wrong")
#: Absurd in any SI field of a road vehicle or a maneuver (kg, m, s, rad, N, Hz, m/s).
ABSURD_MAGNITUDE = 1e15
#: Shipped value scaled by this (or more) is absurd whatever the field.
ABSURD_SCALE = 1e9
#: Speed argument of ``fourws linear`` that no road vehicle reaches, km/h.
ABSURD_SPEED_KMH = 1000.0
#: The paper's speed, the one most linear examples use, km/h.
NOMINAL_SPEED_KMH = 85.0


@dataclass(frozen=True)
class Mutation:
    """One mutated file: its bytes, what was done and what a correct reader must do."""

    kind: str
    data: bytes
    expect: str  # "reject" | "same" | "any"
    note: str


# ------------------------------------------------------------------ structure helpers

def _paths(doc: Any, prefix: tuple = ()) -> list[tuple]:
    """Paths (key/index tuples) of every node below the root."""
    out = []
    if isinstance(doc, dict):
        for k, v in doc.items():
            out.append(prefix + (k,))
            out.extend(_paths(v, prefix + (k,)))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out.append(prefix + (i,))
            out.extend(_paths(v, prefix + (i,)))
    return out


def _get(doc: Any, path: tuple) -> Any:
    for k in path:
        doc = doc[k]
    return doc


def _set(doc: Any, path: tuple, value: Any) -> None:
    _get(doc, path[:-1])[path[-1]] = value


def _dump(doc: Any) -> bytes:
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True).encode()


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


# ------------------------------------------------------------------------- mutators

_SPECIAL = [0.0, -1.0, 1e300, -1e300, 1e-300, 1e15, -1e15, 1e-12, 1e6, math.nan, math.inf,
            -math.inf]


def _m_value(draw: Any, text: str, strict_keys: bool) -> Mutation:
    doc = yaml.safe_load(text)
    leaves = [p for p in _paths(doc) if _is_number(_get(doc, p))]
    path = draw(st.sampled_from(leaves))
    old = _get(doc, path)
    how = draw(st.sampled_from(["special", "random", "scale"]))
    if how == "special":
        new = draw(st.sampled_from(_SPECIAL))
    elif how == "random":
        new = draw(st.floats(allow_nan=True, allow_infinity=True))
    else:
        new = float(old) * 10.0 ** draw(st.sampled_from([-9, -6, -3, 3, 6, 9]))
    _set(doc, path, new)
    absurd = (not math.isfinite(new) or abs(new) >= ABSURD_MAGNITUDE
              or (isinstance(old, float) and abs(old) >= 1e-3
                  and abs(new) >= ABSURD_SCALE * abs(old)))
    return Mutation("value", _dump(doc), "reject" if absurd else "any",
                    f"{'.'.join(map(str, path))}: {old!r} -> {new!r}")


def _m_type(draw: Any, text: str, strict_keys: bool) -> Mutation:
    doc = yaml.safe_load(text)
    path = draw(st.sampled_from(_paths(doc)))
    new = draw(st.sampled_from(["abc", "", True, None, [1, 2], {"x": 1}, 7, -3]))
    _set(doc, path, new)
    return Mutation("type", _dump(doc), "any", f"{'.'.join(map(str, path))} -> {new!r}")


def _m_delete(draw: Any, text: str, strict_keys: bool) -> Mutation:
    doc = yaml.safe_load(text)
    keys = [p for p in _paths(doc) if isinstance(_get(doc, p[:-1]), dict)]
    path = draw(st.sampled_from(keys))
    del _get(doc, path[:-1])[path[-1]]
    return Mutation("delete", _dump(doc), "any", f"deleted {'.'.join(map(str, path))}")


def _m_add(draw: Any, text: str, strict_keys: bool) -> Mutation:
    doc = yaml.safe_load(text)
    maps = [()] + [p for p in _paths(doc) if isinstance(_get(doc, p), dict)]
    path = draw(st.sampled_from(maps))
    _get(doc, path)["zz_unknown_m"] = draw(st.sampled_from([1.0, "x", None]))
    # a ROS parameter file may carry parameters a node does not declare (rcl ignores them)
    return Mutation("add", _dump(doc), "reject" if strict_keys else "any",
                    f"added {'.'.join(map(str, path + ('zz_unknown_m',)))}")


def _m_null(draw: Any, text: str, strict_keys: bool) -> Mutation:
    doc = yaml.safe_load(text)
    path = draw(st.sampled_from(_paths(doc)))
    _set(doc, path, None)
    return Mutation("null", _dump(doc), "any", f"{'.'.join(map(str, path))}: null")


_KEY_LINE = re.compile(r"^(\s*)([A-Za-z_][A-Za-z0-9_]*):(\s.*)?$")


def _m_duplicate(draw: Any, text: str, strict_keys: bool) -> Mutation:
    lines = text.splitlines()
    candidates = [i for i, line in enumerate(lines) if _KEY_LINE.match(line)]
    i = draw(st.sampled_from(candidates))
    indent, key = _KEY_LINE.match(lines[i]).group(1, 2)
    value = draw(st.sampled_from(["1.0", "0.5", "abc", "table_8_1"]))
    # inserted before the original line: the duplicate never lands in a block scalar
    lines.insert(i, f"{indent}{key}: {value}")
    return Mutation("duplicate", ("\n".join(lines) + "\n").encode(), "reject",
                    f"line {i + 1}: {key} given twice")


_FLOAT_TOKEN = re.compile(r"(?<=: )(-?\d+\.\d+)(?=\s*(#.*)?$)", re.MULTILINE)


def _exponent_form(token: str, draw: Any) -> str:
    """``token`` (a decimal float) in a YAML 1.2 exponent form with the same digits."""
    from decimal import Decimal

    mantissa, exponent = f"{Decimal(token).normalize():e}".split("e")
    exp = int(exponent)
    form = draw(st.sampled_from(["e", "E", "dotless"]))
    if form == "dotless" and token.lstrip("-").startswith("0.") and exp == -1:
        return token.replace("0.", ".", 1)  # 0.414 -> .414
    if form == "dotless" and "." in mantissa:
        digits = mantissa.replace(".", "")  # 1.25e3 -> 125e1
        return f"{digits}e{exp - (len(mantissa.split('.')[1]))}"
    return f"{mantissa}{'E' if form == 'E' else 'e'}{exp}"


def _m_exponent(draw: Any, text: str, strict_keys: bool) -> Mutation:
    matches = list(_FLOAT_TOKEN.finditer(text))
    m = draw(st.sampled_from(matches))
    new = _exponent_form(m.group(1), draw)
    out = text[:m.start(1)] + new + text[m.end(1):]
    return Mutation("exponent", out.encode(), "same", f"{m.group(1)} written as {new}")


def _m_bytes(draw: Any, text: str, strict_keys: bool) -> Mutation:
    how = draw(st.sampled_from(["random", "utf16", "latin1", "nul", "truncate"]))
    raw = text.encode()
    if how == "random":
        return Mutation("bytes", draw(st.binary(min_size=0, max_size=400)), "any",
                        "random bytes")
    if how == "utf16":
        return Mutation("bytes", text.encode("utf-16"), "reject", "UTF-16 with BOM")
    at = draw(st.integers(0, len(raw)))
    if how == "latin1":
        return Mutation("bytes", raw[:at] + "\n# réglage\n".encode("latin-1") + raw[at:],
                        "reject", "Latin-1 comment")
    if how == "nul":
        return Mutation("bytes", raw[:at] + b"\x00" + raw[at:], "reject", "NUL byte")
    return Mutation("bytes", raw[:at], "any", f"cut at {at} bytes")


def _replace_description(text: str, value: str) -> str:
    """Give the top-level ``description`` (added when absent) the flow value ``value``."""
    lines = text.splitlines()
    out, skip = [], False
    for line in lines:
        if skip and (line.startswith((" ", "\t")) or not line.strip()):
            continue
        skip = False
        if line.startswith("description:"):
            out.append(f"description: {value}")
            skip = True
            continue
        out.append(line)
    if not any(line.startswith("description:") for line in out):
        out.append(f"description: {value}")
    return "\n".join(out) + "\n"


def _m_bomb(draw: Any, text: str, strict_keys: bool) -> Mutation:
    levels = draw(st.integers(5, 7))
    parts = ['&l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for k in range(1, levels + 1):
        parts.append(f"&l{k} [" + ", ".join([f"*l{k - 1}"] * 9) + "]")
    value = "[" + ", ".join(parts) + "]"
    return Mutation("bomb", _replace_description(text, value).encode(), "reject",
                    f"alias bomb, 9^{levels + 1} strings")


def _m_deep(draw: Any, text: str, strict_keys: bool) -> Mutation:
    depth = draw(st.integers(10, 600))
    value = "[" * depth + "1" + "]" * depth
    return Mutation("deep", _replace_description(text, value).encode(), "any",
                    f"description nested {depth} deep")


MUTATORS: dict[str, Callable[..., Mutation]] = {
    "value": _m_value, "type": _m_type, "delete": _m_delete, "add": _m_add, "null": _m_null,
    "duplicate": _m_duplicate, "exponent": _m_exponent, "bytes": _m_bytes, "bomb": _m_bomb,
    "deep": _m_deep,
}
#: Mutations a ROS parameter file goes through (rcl parses it, not fourws).
PARAMS_FILE_MUTATORS = ("value", "type", "delete", "null", "bytes", "duplicate")


@st.composite
def mutations(draw: Any, bases: list[Path], kinds: tuple[str, ...] = tuple(MUTATORS),
              strict_keys: bool = True) -> tuple[Path, Mutation]:
    """A shipped file (one of ``bases``) and one mutation of it."""
    base = draw(st.sampled_from(bases))
    kind = draw(st.sampled_from(kinds))
    return base, MUTATORS[kind](draw, base.read_text(), strict_keys)


# ------------------------------------------------------------------------ outcomes

class Hang(Exception):
    """Raised by the alarm when a target takes longer than its limit."""


@contextlib.contextmanager
def time_limit(seconds: float):
    """Raise :class:`Hang` in this (main) thread after ``seconds`` of wall time: a guard
    against hangs only, far above what any answer takes."""
    def on_alarm(_signum, _frame):
        raise Hang(f"no answer within {seconds} s")

    previous = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def classify_call(target: Callable[[], Any], mutation: Mutation, path: Path,
                  reference: Any = None, limit_s: float = 60.0) -> tuple[str, str]:
    """Run an in-process loader ``target`` (returns a comparable value, e.g. ``to_dict()``)
    and classify its outcome; returns (outcome, detail)."""
    from fourws_sim.errors import FourwsError

    try:
        with time_limit(limit_s):
            value = target()
    except Hang as exc:
        return "hang", str(exc)
    except FourwsError as exc:
        msg = str(exc)
        if mutation.expect == "same":
            return "refused_valid", msg
        if "\n" in msg or path.name not in msg:
            return "unclear", msg
        return "clear", msg
    except Exception as exc:  # noqa: BLE001 -- the point: any other exception is a finding
        return "traceback", f"{type(exc).__name__}: {exc}"[:300]
    if mutation.expect == "reject":
        return "silent_wrong", "accepted"
    if mutation.expect == "same" and reference is not None and value != reference:
        return "silent_wrong", "loaded a different value"
    return "ok", ""


def classify_cli(argv: list[str], mutation: Mutation | None, must_reject: bool,
                 limit_s: float = 60.0) -> tuple[str, str]:
    """Run ``fourws ARGV`` in this process (``fourws_cli.main.main``) and classify it."""
    from fourws_cli.main import main

    out, err = io.StringIO(), io.StringIO()
    try:
        with time_limit(limit_s), contextlib.redirect_stdout(out), \
                contextlib.redirect_stderr(err):
            code = main(argv)
    except Hang as exc:
        return "hang", str(exc)
    except SystemExit as exc:  # argparse
        code = exc.code if isinstance(exc.code, int) else 2
    except Exception as exc:  # noqa: BLE001 -- any exception out of main is a finding
        return "traceback", f"{type(exc).__name__}: {exc}"[:300]
    text = err.getvalue().strip()
    if code == 0:
        if must_reject:
            return "silent_wrong", "exit 0"
        return "ok", ""
    if mutation is not None and mutation.expect == "same":
        return "refused_valid", text
    lines = text.splitlines()
    if len(lines) == 1 and lines[0].startswith(f"fourws {argv[0]}: error:"):
        return "clear", lines[0]
    return "unclear", text[:300]


def classify_node(node: str, params_file: Path, env: dict[str, str],
                  limit_s: float = 60.0) -> tuple[str, str]:
    """Start ``fourws node NODE --ros-args --params-file FILE`` and classify its start-up:
    ``ok`` if it starts (logs its first INFO line, or is still running without a word after
    ``limit_s``; it is then stopped with SIGINT, and what it does on shutdown is not judged
    here), ``clear`` if it exits with code 2 and no traceback, ``traceback`` otherwise."""
    import threading

    proc = subprocess.Popen(
        [sys.executable, "-m", "fourws_cli.main", "node", node, "--ros-args",
         "--params-file", str(params_file)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, text=True,
        errors="replace", start_new_session=True)
    lines: list[str] = []
    decided = threading.Event()
    logged = threading.Event()

    def read() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            lines.append(line.rstrip("\n"))
            if line.startswith("[INFO]") and f"[fourws_{node}]" in line:
                logged.set()
                decided.set()
        decided.set()  # end of output: the process is ending

    reader = threading.Thread(target=read, daemon=True)
    try:
        reader.start()
        decided.wait(limit_s)
        if not logged.is_set() and not reader.is_alive():
            proc.wait(timeout=limit_s)  # its output ended: judge it by its exit
        started = (logged.is_set() or proc.poll() is None) \
            and not any("Traceback" in line for line in lines)
    finally:  # whatever happens here, the node does not outlive the example
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGINT)
            try:
                proc.wait(timeout=20.0)
            except subprocess.TimeoutExpired:
                os.kill(proc.pid, signal.SIGKILL)
                proc.wait()
    reader.join(timeout=5.0)
    if started:
        return "ok", ""
    text = "\n".join(lines).strip()
    if "Traceback" in text or proc.returncode != 2:
        return "traceback", f"exit {proc.returncode}: {text[-300:]}"
    return "clear", text.splitlines()[-1] if text else ""


# --------------------------------------------------------------------------- targets

def _nominal_outputs(speed_mps: float) -> dict[str, float]:
    # the VehicleState fields a maneuver reads (a torque-input maneuver reports the applied
    # front angle as the steering system's angle)
    return {"speed_mps": speed_mps, "x_m": 0.0, "y_m": 0.0, "heading_rad": 0.0,
            "yaw_rate_radps": 0.0, "sideslip_rad": 0.0, "lateral_accel_mps2": 0.0,
            "lateral_velocity_mps": 0.0, "roll_rad": 0.0, "roll_rate_radps": 0.0,
            "front_wheel_angle_rad": 0.0}


def vehicle_target(path: Path) -> Any:
    from fourws_sim.params import load_vehicle

    return load_vehicle(path).to_dict()


def maneuver_target(path: Path) -> Any:
    """Load the maneuver, bind it to table_8_1 and drive it for a few ticks."""
    from fourws_sim.maneuvers import load_maneuver_spec, make_maneuver
    from fourws_sim.params import load_vehicle

    spec = load_maneuver_spec(path)
    man = make_maneuver(spec, load_vehicle("table_8_1"))
    outputs = _nominal_outputs(spec.initial_speed_mps)
    for t in (0.0, 0.01, 0.5, 1.0):
        man.command(t, outputs)
        man.done(t, outputs)
    return spec.to_dict()


def scenario_target(path: Path) -> Any:
    """Load the scenario and build what a run builds before it starts its nodes."""
    from fourws_sim.maneuvers import make_maneuver
    try:
        from fourws_run.scenario import load_scenario
    except ImportError:  # the layout before fourws_run (for the "before" table)
        from fourws_sim.scenario import load_scenario

    scenario = load_scenario(path)
    vehicle = scenario.build_vehicle()
    scenario.build_belief(vehicle)
    if getattr(scenario.maneuver.params, "resolved", True):  # else resolved per law, by a run
        make_maneuver(scenario.maneuver, vehicle)
    return scenario.to_dict()


def config_dirs() -> dict[str, list[Path]]:
    """Shipped files per kind (from the fourws on the import path)."""
    from fourws_sim.params import CONFIG_DIR

    return {"vehicle": sorted((CONFIG_DIR / "vehicles").glob("*.yaml")),
            "maneuver": sorted((CONFIG_DIR / "maneuvers").glob("*.yaml")),
            "scenario": sorted((CONFIG_DIR / "scenarios").glob("*.yaml")),
            "params": sorted((CONFIG_DIR / "params").glob("*.yaml"))}


def reference_dict(kind: str, base: Path) -> Any:
    return {"vehicle": vehicle_target, "maneuver": maneuver_target,
            "scenario": scenario_target}[kind](base)


LINEAR_VEHICLES = ("table_4_1_set_1", "table_4_1_set_2", "table_8_1")  # all have roll data


def linear_argv(path: Path, model: str, speed_kmh: float) -> list[str]:
    return ["linear", "--vehicle", str(path), "--model", model, "--law", "sol1",
            f"--speed-kmh={speed_kmh!r}"]


def linear_case(path: Path, model: str, speed: float, mutation: Mutation
                ) -> tuple[list[str], Mutation | None, bool]:
    """``fourws linear`` arguments, the mutation whose ``same`` expectation applies (only at
    the nominal speed: another speed may be refused on its own) and whether it must fail."""
    absurd_speed = not 0.0 < speed <= ABSURD_SPEED_KMH
    return (linear_argv(path, model, speed), mutation if speed == NOMINAL_SPEED_KMH else None,
            mutation.expect == "reject" or absurd_speed)


def linear_speeds() -> st.SearchStrategy[float]:
    """Mostly the paper's 85 km/h, sometimes anything a float can be."""
    return st.one_of(st.just(NOMINAL_SPEED_KMH), st.just(NOMINAL_SPEED_KMH),
                     st.floats(allow_nan=True, allow_infinity=True),
                     st.sampled_from([1e6, -85.0, 0.0, 1e-9, 540.0]))


# ------------------------------------------------------------------------ the table

def _run_in_child(fn: Callable[[], tuple[str, str]], limit_s: float) -> tuple[str, str]:
    """Run ``fn`` in a forked child with a memory cap (a hang or a blow-up in C code cannot
    take the table run, or the machine, with it)."""
    import pickle
    import resource

    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # child
        os.close(read)
        try:
            resource.setrlimit(resource.RLIMIT_AS, (6 << 30, 6 << 30))
            result = fn()
        except MemoryError:
            result = ("traceback", "MemoryError")
        except BaseException as exc:  # noqa: BLE001 -- reported, never raised in a fork
            result = ("traceback", f"{type(exc).__name__}: {exc}"[:300])
        with os.fdopen(write, "wb") as stream:
            pickle.dump(result, stream)
        os._exit(0)
    os.close(write)
    deadline = time.monotonic() + limit_s
    while time.monotonic() < deadline:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        time.sleep(0.01)
    else:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        os.close(read)
        return "hang", f"no answer within {limit_s} s"
    with os.fdopen(read, "rb") as stream:
        data = stream.read()
    if not data:
        return "traceback", f"child died (status {status})"
    return pickle.loads(data)


def table(examples: int, node_examples: int, limit_s: float, verbose: bool) -> None:
    """Run every target over ``examples`` mutations (hypothesis, derandomized) and print
    the outcome counts per target."""
    from collections import Counter

    from hypothesis import HealthCheck, given, settings

    try:
        from fourws_ros.domains import reserve_domain_id
    except ImportError:  # the layout before fourws_ros.domains (for the "before" table)
        from fourws_ros.launcher import reserve_domain_id

    dirs = config_dirs()
    tmp = Path(tempfile.mkdtemp(prefix="fourws-mutation-"))
    counts: dict[str, Counter] = {}
    refs = {(kind, base): reference_dict(kind, base)
            for kind in ("vehicle", "maneuver", "scenario") for base in dirs[kind]}
    lease = reserve_domain_id()
    env = dict(os.environ, ROS_DOMAIN_ID=str(lease.domain_id),
               ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")

    def cfg(n: int) -> Any:
        return settings(max_examples=n, derandomize=True, database=None, deadline=None,
                        suppress_health_check=list(HealthCheck))

    def record(target: str, outcome: tuple[str, str], note: str) -> None:
        counts.setdefault(target, Counter())[outcome[0]] += 1
        if verbose and outcome[0] in ("traceback", "hang", "silent_wrong", "unclear",
                                      "refused_valid"):
            print(f"  {target:9s} {outcome[0]:13s} {note} :: {outcome[1][:160]}",
                  file=sys.stderr)

    def loader_run(kind: str, fn: Callable[[Path], Any]) -> Callable[[], None]:
        @cfg(examples)
        @given(mutations(dirs[kind]))
        def run(pair: tuple[Path, Mutation]) -> None:
            base, mutation = pair
            path = tmp / f"mutated_{kind}.yaml"
            path.write_bytes(mutation.data)
            outcome = _run_in_child(
                lambda: classify_call(lambda: fn(path), mutation, path, refs[(kind, base)],
                                      limit_s), limit_s + 5.0)
            record(kind, outcome, f"{base.name} {mutation.kind} {mutation.note[:80]}")

        return run

    for kind, fn in (("vehicle", vehicle_target), ("maneuver", maneuver_target),
                     ("scenario", scenario_target)):
        loader_run(kind, fn)()

    vehicles = [p for p in dirs["vehicle"] if p.stem in LINEAR_VEHICLES]

    @cfg(examples)
    @given(mutations(vehicles), st.sampled_from(["2dof", "3dof"]), linear_speeds())
    def run_linear(pair: tuple[Path, Mutation], model: str, speed: float) -> None:
        base, mutation = pair
        path = tmp / "mutated_linear.yaml"
        path.write_bytes(mutation.data)
        outcome = _run_in_child(
            lambda: classify_cli(*linear_case(path, model, speed, mutation), limit_s),
            limit_s + 5.0)
        record("linear", outcome, f"{base.name} {model} {speed!r} {mutation.kind} "
                                  f"{mutation.note[:80]}")

    run_linear()

    @cfg(node_examples)
    @given(mutations(dirs["params"], PARAMS_FILE_MUTATORS, strict_keys=False),
           st.sampled_from(["controller", "maneuver"]))
    def run_node(pair: tuple[Path, Mutation], node: str) -> None:
        base, mutation = pair
        path = tmp / "mutated_params.yaml"
        path.write_bytes(mutation.data)
        outcome = classify_node(node, path, env, limit_s)
        record("node", outcome, f"{node} {mutation.kind} {mutation.note[:80]}")

    try:
        run_node()
    finally:
        lease.release()
    print(f"{'target':10s} {'attempts':>8s} " + " ".join(f"{o:>13s}" for o in OUTCOMES))
    total: Counter = Counter()
    for target, c in counts.items():
        total.update(c)
        print(f"{target:10s} {sum(c.values()):8d} "
              + " ".join(f"{c[o]:13d}" for o in OUTCOMES))
    print(f"{'all':10s} {sum(total.values()):8d} "
          + " ".join(f"{total[o]:13d}" for o in OUTCOMES))


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=200)
    parser.add_argument("--node-examples", type=int, default=20)
    parser.add_argument("--limit-s", type=float, default=60.0)
    parser.add_argument("--verbose", action="store_true")
    a = parser.parse_args()
    table(a.examples, a.node_examples, a.limit_s, a.verbose)
