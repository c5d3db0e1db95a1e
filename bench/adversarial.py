#!/usr/bin/env python3
# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Adversarial pass over the fourws node graph: faults, rogue publishers, load, bad disks.

Runs a fixed list of attempts against one fourws installation (``--fourws PATH``, the
``fourws`` executable of a virtual environment; its ``python`` beside it runs the offline twin
and the rogue node) and classifies each outcome:

* **correct** -- exit 0, the run says ``ok``, the bag holds every message the run published
  and nothing else, and (lockstep) its states, driver inputs and rear-steer commands equal the
  offline twin of the same installation (``fourws_run.closed_loop.run_scenario``, or
  ``fourws_sim.closed_loop.run_scenario`` in installations before ``fourws_run`` existed);
* **clear error** -- a non-zero exit with a one-line ``fourws run: ...`` error naming the
  cause (the node at fault where there is one), no ``Traceback``, no process left behind, and
  the bag keeps what was recorded up to the failure within the documented bound;
* **unclear** -- a non-zero exit whose error names no cause or the wrong node;
* **traceback** -- ``Traceback`` in the command's stdout or stderr;
* **hang** -- the command did not end within the attempt's time limit, or node processes
  outlived it;
* **silent wrong** -- exit 0 or ``ok``, but the bag is short, holds foreign data, or differs
  from the twin (or an absurd input was accepted);
* **data lost** -- a failure was reported, but the bag lost more than the documented bound:
  states missing in the middle, states that are not the twin's, more than 1.0 s of simulated
  time lost before the reported end (0.5 s flush period + 0.5 s lockstep flow window, README
  "What a run's `ok` means"), or a bag that rosbags cannot open even after the installation's
  own ``fourws bag repair`` (where it has one).

Attempts (each bounded in time): two and three ``fourws run`` side by side, also under a CPU hog
(two busy processes); SIGKILL and SIGSTOP of each node process and of the launcher at several
moments; double SIGINT to the launcher; rogue publishers on the run's domain (NaN states,
states at t = 1e6 s, future-stamped commands, 100 rad driver inputs, ``done`` statuses, floods,
a node answering every state); realtime runs whose maneuver node is stopped; a full and a
read-only output disk (tmpfs; skipped where mounting is not permitted); a few absurd but
well-formed scenario values; and the tools beside the graph (:func:`tool_attempts`): study
files with a duplicate key, in Latin-1, with an unknown report metric, damaged or stray block
files; a vehicle with an unknown tire coefficient in ``linear``, ``handling`` and ``run``;
node parameter files with an unknown parameter or empty; a node stopped while it imports;
``bag repair``/``verify`` of a bag still being recorded; ``ROS_DOMAIN_ID=300``; a law given
twice; ``--help``, ``--version``, the summary of ``analyze``, a subcommand's unknown option.
There an input that must be refused is *clear error* when the command exits with code 2 and
one error line naming the cause (and the file), *silent wrong* when it is accepted, *unclear*
otherwise; a command that must work is *correct* or *silent wrong*.

Usage (a pass takes 15-30 min on two loaded cores)::

    nice -n 10 .venv/bin/python bench/adversarial.py --fourws .venv/bin/fourws \\
        --label after --json /tmp/adv-after.json
    .venv/bin/python bench/adversarial.py --table /tmp/adv-before.json /tmp/adv-after.json

Benchmark-like script, not part of ``make test``: it measures how the graph behaves under
attack on this machine; nothing here is asserted.
"""

from __future__ import annotations

import argparse
import dataclasses
import fcntl
import hashlib
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path
from typing import Any, Callable

CLASSES = ("correct", "clear error", "unclear", "traceback", "hang", "silent wrong",
           "data lost")
#: Loss a failed run may show, s of simulated time: one 0.5 s flush period plus the 0.5 s
#: lockstep flow window (README "What a run's `ok` means").
LOSS_BOUND_S = 1.0
#: Wall time after which a run counts as hung, s. A stopped node must end the run after the
#: launcher's 20 s stall timeout plus the nodes' shutdown; a minute on top is generous.
HANG_S = 120.0
#: Time node processes get to disappear after their launcher ended, s.
ORPHAN_GRACE_S = 20.0
NODES = ("simulator", "maneuver", "controller", "recorder")
CONTROL_PERIOD_S = 0.01
LAW = "sol1"

STEP = ("{type: step_steer, initial_speed_mps: 23.611111111111111, duration_s: %s, "
        "steer_input: road_wheel, amplitude_rad: %s, start_s: 0.5, ramp_time_s: 0.1}")
#: Scenario files of the attempts: name -> (YAML text, clock mode, duration s or None for an
#: absurd scenario that must not run).
SCENARIOS: dict[str, tuple[str, str, float | None]] = {
    # ISO 7401 step steer of the default scenario, 3 s simulated: the short lockstep run
    "short": (f"vehicle: table_8_1\nmaneuver: {STEP % (3.0, 0.0261799387799)}\n"
              f"laws: [{LAW}]\n", "lockstep", 3.0),
    # 60 s simulated, lockstep (3-10 s of wall time): long enough to hit it at a chosen moment
    "long": (f"vehicle: table_8_1\nmaneuver: {STEP % (60.0, 0.0261799387799)}\n"
             f"laws: [{LAW}]\n", "lockstep", 60.0),
    "rt": (f"vehicle: table_8_1\nmaneuver: {STEP % (4.0, 0.0261799387799)}\n"
           f"laws: [{LAW}]\nclock_mode: realtime\n", "realtime", 4.0),
    "rt_long": (f"vehicle: table_8_1\nmaneuver: {STEP % (8.0, 0.0261799387799)}\n"
                f"laws: [{LAW}]\nclock_mode: realtime\n", "realtime", 8.0),
    "absurd_amplitude": (f"vehicle: table_8_1\nmaneuver: {STEP % (3.0, 1e300)}\n"
                         f"laws: [{LAW}]\n", "lockstep", None),
    "absurd_duration": (f"vehicle: table_8_1\nmaneuver: {STEP % (1e9, 0.0261799387799)}\n"
                        f"laws: [{LAW}]\n", "lockstep", None),
    "absurd_speed": ("vehicle: table_8_1\nmaneuver: {type: step_steer, initial_speed_mps: 1e6,"
                     " duration_s: 3.0, steer_input: road_wheel, amplitude_rad: 0.02, "
                     f"start_s: 0.5, ramp_time_s: 0.1}}\nlaws: [{LAW}]\n", "lockstep", None),
    "absurd_step": (f"vehicle: table_8_1\nmaneuver: {STEP % (3.0, 0.0261799387799)}\n"
                    f"laws: [{LAW}]\nintegration_step_s: 5.0\ncontrol_period_s: 5.0\n"
                    "state_period_s: 5.0\n", "lockstep", None),
}

TWIN_CODE = r"""
import json, math, sys
try:
    from fourws_run.scenario import load_scenario
    from fourws_run.closed_loop import run_scenario
except ImportError:  # before fourws_run existed
    from fourws_sim.scenario import load_scenario
    from fourws_sim.closed_loop import run_scenario
import numpy as np
ref = run_scenario(load_scenario(sys.argv[1]), sys.argv[2])
def scalar(v):
    return isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, bool)
out = {"time_s": ref.time_s.tolist(),
       "outputs": {k: np.asarray(v).tolist() for k, v in ref.outputs.items()},
       "final": {k: float(v) for k, v in ref.final_outputs.items() if scalar(v)},
       "front": ref.driver["front_wheel_angle_rad"].tolist(),
       "rear": np.asarray(ref.rear_angle_rad).tolist(), "end_reason": str(ref.end_reason)}
with open(sys.argv[3], "w") as f:
    json.dump(out, f)
"""

ROGUE_CODE = r'''
"""Rogue node: publishes on a fourws run's domain what no node of the run sends."""
import math, signal, sys, time
import rclpy
from rclpy.executors import SingleThreadedExecutor
from fourws_ros import topics
try:
    from fourws.msg import (DriverInput, ManeuverStatus, RearSteerCommand, SimulatorStatus,
                            VehicleState)
except ImportError:  # installations with the former interface package
    from fourws_msgs.msg import (DriverInput, ManeuverStatus, RearSteerCommand,
                                 SimulatorStatus, VehicleState)

def set_stamp(stamp, t):
    sec = math.floor(t)
    stamp.sec = int(sec)
    stamp.nanosec = min(int(round((t - sec) * 1e9)), 999_999_999)

def setf(msg, **values):
    for k, v in values.items():
        if hasattr(msg, k):
            setattr(msg, k, v)

def state(t, step, yaw=0.1):
    m = VehicleState()
    set_stamp(m.header.stamp, t)
    m.header.frame_id = "base_link"
    setf(m, step=step, sim_time_s=t, model="8dof", speed_mps=23.6, yaw_rate_radps=yaw,
         front_wheel_angle_rad=0.026)
    return m

def cmd(t_state, step, angle):
    m = RearSteerCommand()
    set_stamp(m.header.stamp, t_state)
    set_stamp(m.state_stamp, t_state)
    setf(m, angle_rad=angle, law="rogue", state_step=step)
    return m

def driver(t, front):
    m = DriverInput()
    set_stamp(m.header.stamp, t)
    setf(m, front_wheel_angle_rad=front, steering_wheel_angle_rad=front * 16.0)
    return m

def main(kinds, seconds):
    rclpy.init()
    node = rclpy.create_node("rogue")
    qos = topics.TOPIC_QOS
    pub = {t: node.create_publisher(c, t, qos[t]) for t, c in (
        (topics.STATE, VehicleState), (topics.DRIVER_INPUT, DriverInput),
        (topics.REAR_STEER_CMD, RearSteerCommand), (topics.MANEUVER_STATUS, ManeuverStatus),
        (topics.SIM_STATUS, SimulatorStatus))}
    sent = 0
    stop = []
    signal.signal(signal.SIGTERM, lambda *a: stop.append(1))
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    if "mimic" in kinds:
        def answer(s):
            nonlocal sent
            d = driver(0.0, 0.03)
            d.header.stamp = s.header.stamp
            pub[topics.DRIVER_INPUT].publish(d)
            c = cmd(0.0, s.step, 0.08)
            c.header.stamp = s.header.stamp
            c.state_stamp = s.header.stamp
            pub[topics.REAR_STEER_CMD].publish(c)
            sent += 2
        node.create_subscription(VehicleState, topics.STATE, answer, qos[topics.STATE])
    print("rogue ready", flush=True)
    end = time.monotonic() + seconds
    k = 0
    while time.monotonic() < end and not stop:
        k += 1
        t = 0.01 * (k % 6000)  # plausible simulation times of a run
        if "nan_state" in kinds:
            pub[topics.STATE].publish(state(t, k * 10, yaw=math.nan))
            sent += 1
        if "clock_state" in kinds:  # finite states on the run's own clock grid
            pub[topics.STATE].publish(state(t, k * 10))
            sent += 1
        if "future_state" in kinds:
            pub[topics.STATE].publish(state(1e6 + k, 10 ** 9 + k))
            sent += 1
        if "future_cmd" in kinds:
            pub[topics.REAR_STEER_CMD].publish(cmd(1e5 + k, 10 ** 8 + k, 0.08))
            sent += 1
        if "driver_100rad" in kinds:
            pub[topics.DRIVER_INPUT].publish(driver(t, 100.0))
            sent += 1
        if "done_status" in kinds:
            m = ManeuverStatus()
            set_stamp(m.header.stamp, t)
            setf(m, maneuver="step_steer", phase="done", progress=1.0, done=True,
                 event="completed", end="completed")
            pub[topics.MANEUVER_STATUS].publish(m)
            sent += 1
        if "final_status" in kinds:
            s = SimulatorStatus()
            set_stamp(s.header.stamp, 1e6)
            setf(s, clock_mode="lockstep", sim_time_s=1e6, running=False, final=True,
                 end_reason="maneuver completed")
            pub[topics.SIM_STATUS].publish(s)
            sent += 1
        if "flood" in kinds:
            for j in range(50):
                pub[topics.STATE].publish(state(t, k * 10 + j))
                pub[topics.DRIVER_INPUT].publish(driver(t, 0.03))
                pub[topics.REAR_STEER_CMD].publish(cmd(t, k * 10 + j, 0.08))
                sent += 3
        executor.spin_once(timeout_sec=0.0 if "flood" in kinds else 0.002)
    print(f"rogue {','.join(kinds)}: sent {sent} messages", flush=True)
    node.destroy_node()
    rclpy.try_shutdown()

main(sys.argv[1].split(","), float(sys.argv[2]))
'''


# ---------------------------------------------------------------------------------------------
# installations, scenarios, the offline twin

@dataclasses.dataclass
class Installation:
    """A fourws installation: its ``fourws`` executable and the ``python`` beside it."""

    label: str
    fourws: Path
    python: Path
    has_repair: bool

    @classmethod
    def from_path(cls, fourws: Path, label: str) -> "Installation":
        fourws = fourws.absolute()
        python = fourws.parent / "python"
        if not fourws.is_file() or not python.is_file():
            raise SystemExit(f"adversarial: {fourws} is not the fourws of a venv (no python "
                             "beside it)")
        probe = subprocess.run([str(python), "-c", "import fourws_run.bagfile"],
                               capture_output=True, text=True, cwd=tempfile.gettempdir(),
                               env=base_env())
        return cls(label, fourws, python, probe.returncode == 0)


class Work:
    """The pass's scratch folder: scenario files, twins (cached), attempt folders."""

    def __init__(self, root: Path, inst: Installation) -> None:
        self.root = root
        self.inst = inst
        root.mkdir(parents=True, exist_ok=True)
        self.scenarios = {}
        for name, (text, _clock, _dur) in SCENARIOS.items():
            path = root / f"{name}.yaml"
            path.write_text(text)
            self.scenarios[name] = path
        self.rogue = root / "rogue.py"
        self.rogue.write_text(ROGUE_CODE)
        self._twins: dict[str, dict[str, Any]] = {}
        self._count = 0

    def attempt_dir(self, name: str) -> Path:
        self._count += 1
        safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", name)[:60]
        path = self.root / f"{self._count:03d}-{safe}"
        path.mkdir(parents=True, exist_ok=True)
        return path

    def twin(self, scenario: str) -> dict[str, Any] | None:
        """The offline twin of ``scenario`` with :data:`LAW` (cached); None for realtime or
        absurd scenarios."""
        _text, clock, duration = SCENARIOS[scenario]
        if clock != "lockstep" or duration is None:
            return None
        if scenario not in self._twins:
            key = hashlib.sha1(SCENARIOS[scenario][0].encode()).hexdigest()[:10]
            out = self.root / f"twin-{scenario}-{key}.json"
            if not out.is_file():
                res = subprocess.run([str(self.inst.python), "-c", TWIN_CODE,
                                      str(self.scenarios[scenario]), LAW, str(out)],
                                     capture_output=True, text=True, timeout=900,
                                     cwd=self.root, env=base_env())
                if res.returncode != 0:
                    raise SystemExit(f"adversarial: the offline twin failed:\n{res.stderr}")
            self._twins[scenario] = json.loads(out.read_text())
        return self._twins[scenario]


# ---------------------------------------------------------------------------------------------
# processes

def _proc_text(pid: int, what: str) -> str:
    try:
        return Path(f"/proc/{pid}/{what}").read_bytes().replace(b"\0", b" ").decode(
            errors="replace")
    except OSError:
        return ""


def node_pids(marker: str) -> dict[str, list[int]]:
    """Live node processes whose command line holds ``marker`` (the run folder; the node
    processes' ``--params-file`` lies in it), by node kind."""
    found: dict[str, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        cmdline = _proc_text(int(entry.name), "cmdline")
        if marker not in cmdline or "params.yaml" not in cmdline:
            continue
        if "\nState:\tZ" in _proc_text(int(entry.name), "status"):
            continue
        words = cmdline.split()
        kind = "user"
        if "node" in words:
            i = words.index("node")
            if i + 1 < len(words):
                kind = words[i + 1]
        found.setdefault(kind, []).append(int(entry.name))
    return found


def proc_environ(pid: int) -> dict[str, str]:
    try:
        raw = Path(f"/proc/{pid}/environ").read_bytes()
    except OSError:
        return {}
    env = {}
    for item in raw.split(b"\0"):
        if b"=" in item:
            k, v = item.split(b"=", 1)
            env[k.decode(errors="replace")] = v.decode(errors="replace")
    return env


def base_env() -> dict[str, str]:
    """The environment of a run (and of an installation's python): no ROS domain of the
    caller's, and none of the library paths the harness's own ROS wheels set at start-up
    (another installation would load this one's message libraries)."""
    env = dict(os.environ)
    for key in ("ROS_DOMAIN_ID", "ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY", "LD_LIBRARY_PATH",
                "_ROS_WHEELS_BOOTSTRAP_COMPLETE", "PYTHONPATH"):
        env.pop(key, None)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["PYTHONUNBUFFERED"] = "1"
    return env


class Run:
    """One ``fourws run`` process of an attempt."""

    def __init__(self, inst: Installation, scenario: Path, out: Path, logs: Path,
                 env: dict[str, str] | None = None, extra: tuple[str, ...] = ()) -> None:
        self.inst = inst
        self.out = out
        self.scenario = scenario
        self.cmd = [str(inst.fourws), "run", str(scenario), "--law", LAW, "--out", str(out),
                    *extra]
        self.env_note = ""
        self.stdout_path = logs / f"{out.name}.stdout"
        self.stderr_path = logs / f"{out.name}.stderr"
        self._stdout = open(self.stdout_path, "w")
        self._stderr = open(self.stderr_path, "w")
        self.t0 = time.monotonic()
        # the working directory is the attempt's folder: the nodes run ``python -m
        # fourws_cli.main``, which would import a fourws source tree found in the cwd
        self.proc = subprocess.Popen(self.cmd, stdout=self._stdout, stderr=self._stderr,
                                     env=env or base_env(), start_new_session=True,
                                     cwd=logs)
        self.rc: int | None = None
        self.timed_out = False
        self.timeout_s = HANG_S
        self.wall_s = 0.0

    @property
    def marker(self) -> str:
        return f"{self.out}/"

    def stderr(self) -> str:
        return self.stderr_path.read_text(errors="replace")

    def stdout(self) -> str:
        return self.stdout_path.read_text(errors="replace")

    def running(self) -> bool:
        return self.proc.poll() is None

    def wait_for(self, condition: Callable[[], bool], timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if condition():
                return True
            if not self.running():
                return condition()
            time.sleep(0.05)
        return False

    def graph_up(self) -> bool:
        return "graph up after" in self.stderr()

    def domain(self) -> int | None:
        m = re.search(r"on ROS domain (\d+)", self.stderr())
        return int(m.group(1)) if m else None

    def wait(self, timeout_s: float) -> None:
        self.timeout_s = timeout_s
        try:
            self.rc = self.proc.wait(timeout=max(timeout_s - (time.monotonic() - self.t0), 1))
        except subprocess.TimeoutExpired:
            self.timed_out = True
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.rc = self.proc.wait()
        self.wall_s = time.monotonic() - self.t0
        self._stdout.close()
        self._stderr.close()

    def leftovers(self) -> list[int]:
        """Node processes still alive ``ORPHAN_GRACE_S`` after the launcher ended (a node
        the attack stopped counts too: the launcher must end it)."""
        deadline = time.monotonic() + ORPHAN_GRACE_S
        while time.monotonic() < deadline:
            pids = [p for ps in node_pids(self.marker).values() for p in ps]
            if not pids:
                return []
            time.sleep(0.25)
        return [p for ps in node_pids(self.marker).values() for p in ps]

    def kill_leftovers(self) -> None:
        for pids in node_pids(self.marker).values():
            for pid in pids:
                try:
                    os.kill(pid, signal.SIGCONT)
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass


# ---------------------------------------------------------------------------------------------
# bags

@dataclasses.dataclass
class Bag:
    """What a bag folder holds, read from its raw MCAP file(s) (truncation tolerated)."""

    path: Path
    exists: bool = False
    metadata: bool = False
    rosbags_ok: bool = False
    rosbags_error: str = ""
    read_error: str = ""
    messages: dict[str, list[Any]] = dataclasses.field(default_factory=dict)
    publishers: dict[str, set[str]] = dataclasses.field(default_factory=dict)

    def counts(self) -> dict[str, int]:
        return {t: len(m) for t, m in sorted(self.messages.items())}


class _CdrDecoders:
    """Decoders of a bag's ros2msg schemas built from the definitions the bag embeds (rosbags'
    type system, not fourws's message classes: the harness reads the bag as an outside
    tool would)."""

    def __init__(self) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.store = get_typestore(Stores.EMPTY)

    def decoder_for(self, encoding: str, schema: Any) -> Any:
        from rosbags.typesys import get_types_from_msg

        if encoding != "cdr" or schema.encoding != "ros2msg":
            raise ValueError(f"cannot decode {encoding}/{schema.encoding}")
        text = schema.data.decode()
        types: dict[str, Any] = {}
        name, body = schema.name, []
        for line in text.splitlines():
            if line.startswith("=" * 10):
                types.update(get_types_from_msg("\n".join(body), name))
                name, body = "", []
            elif line.startswith("MSG: ") and not name:
                name = line[5:].strip()
            else:
                body.append(line)
        types.update(get_types_from_msg("\n".join(body), name))
        self.store.register({k: v for k, v in types.items() if k not in self.store.fielddefs})
        msgtype = schema.name if "/msg/" in schema.name else schema.name.replace("/", "/msg/")
        store = self.store
        return lambda data: store.deserialize_cdr(data, msgtype)


def read_bag(path: Path | None) -> Bag:
    """Every message of the bag's ``.mcap`` files up to the first damaged record; whether
    ``metadata.yaml`` exists and rosbags opens the bag."""
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    bag = Bag(path if path is not None else Path("-"))
    if path is None or not path.is_dir():
        return bag
    bag.exists = True
    bag.metadata = (path / "metadata.yaml").is_file()
    factory = _CdrDecoders()
    for file in sorted(path.glob("*.mcap")):
        schemas: dict[int, Any] = {}
        channels: dict[int, Any] = {}
        decoders: dict[int, Any] = {}
        try:
            with open(file, "rb") as fh:
                for rec in StreamReader(fh, validate_crcs=True).records:
                    if isinstance(rec, Schema):
                        schemas[rec.id] = rec
                    elif isinstance(rec, Channel):
                        channels[rec.id] = rec
                    elif isinstance(rec, Message):
                        ch = channels[rec.channel_id]
                        if ch.schema_id not in decoders:
                            decoders[ch.schema_id] = factory.decoder_for(
                                ch.message_encoding, schemas[ch.schema_id])
                        bag.messages.setdefault(ch.topic, []).append(
                            decoders[ch.schema_id](rec.data))
        except Exception as exc:  # a killed writer's file ends anywhere: keep what came before
            bag.read_error = f"{file.name}: {type(exc).__name__}: {exc}"[:200]
    if bag.metadata:
        try:
            from rosbags.rosbag2 import Reader

            with Reader(path) as reader:
                _ = sum(c.msgcount for c in reader.connections)
            bag.rosbags_ok = True
        except Exception as exc:  # any reason rosbags refuses is the finding; say which
            bag.rosbags_error = f"{type(exc).__name__}: {exc}"[:200]
    else:
        bag.rosbags_error = "no metadata.yaml"
    return bag


def find_bag(out: Path) -> Path | None:
    bags = sorted(out.glob("*/bag"))
    return bags[0] if bags else None


def _stamp_s(stamp: Any) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


@dataclasses.dataclass
class BagVerdict:
    """What the bag says about a run: problems for an ``ok`` run, losses for a failed one."""

    short: list[str] = dataclasses.field(default_factory=list)    # missing messages
    foreign: list[str] = dataclasses.field(default_factory=list)  # data not of this run
    differs: list[str] = dataclasses.field(default_factory=list)  # not the twin's values
    gaps: list[str] = dataclasses.field(default_factory=list)     # holes in the middle
    last_state_s: float = -1.0
    states: int = 0


def inspect_bag(bag: Bag, twin: dict[str, Any] | None, duration_s: float | None,
                clock: str) -> BagVerdict:
    """Compare the bag with what the run must have published: the twin (lockstep) or the
    realtime state grid."""
    v = BagVerdict()
    states = bag.messages.get("/fourws/state", [])
    cmds = bag.messages.get("/fourws/rear_steer_cmd", [])
    drivers = bag.messages.get("/fourws/driver_input", [])
    v.states = len(states)
    # foreign content, whatever the mode
    bad_law = sum(1 for c in cmds if c.law != LAW)
    if bad_law:
        v.foreign.append(f"{bad_law} rear-steer commands of law != {LAW}")
    nonfinite = sum(1 for s in states
                    if not (math.isfinite(s.sim_time_s) and math.isfinite(s.yaw_rate_radps)))
    if nonfinite:
        v.foreign.append(f"{nonfinite} states with non-finite time or yaw rate")
    if duration_s is not None:
        late = sum(1 for s in states if s.sim_time_s > duration_s + 1.0)
        if late:
            v.foreign.append(f"{late} states beyond the maneuver's end (max "
                             f"{max(s.sim_time_s for s in states):.3g} s)")
    big = sum(1 for d in drivers if not abs(d.front_wheel_angle_rad) < 1.0)
    if big:
        v.foreign.append(f"{big} driver inputs with |front angle| >= 1 rad")
    times = [s.sim_time_s for s in states]
    if times:
        v.last_state_s = max(t for t in times if math.isfinite(t)) if any(
            math.isfinite(t) for t in times) else -1.0
    if twin is not None:
        ref_t = twin["time_s"]
        n = len(ref_t)
        yaw = twin["outputs"]["yaw_rate_radps"]
        if len(states) < n + 1:
            v.short.append(f"/fourws/state {len(states)} of {n + 1}")
        if len(states) > n + 1:
            v.foreign.append(f"/fourws/state {len(states)} > {n + 1}")
        if len(drivers) < n:
            v.short.append(f"/fourws/driver_input {len(drivers)} of {n}")
        if len(cmds) < n:
            v.short.append(f"/fourws/rear_steer_cmd {len(cmds)} of {n}")
        viz = n // 2 + 1
        for topic in ("/fourws/odom", "/fourws/imu"):
            got = len(bag.messages.get(topic, []))
            if got < viz:
                v.short.append(f"{topic} {got} of {viz}")
        # prefix equality with the twin, in bag order (lockstep is deterministic)
        first_bad = None
        worst = 0.0
        for i, s in enumerate(states[:n]):
            dy = abs(s.yaw_rate_radps - yaw[i]) if math.isfinite(s.yaw_rate_radps) else math.inf
            worst = max(worst, dy)
            if s.sim_time_s != ref_t[i] or dy > 1e-9:
                first_bad = first_bad if first_bad is not None else i
        if first_bad is not None:
            s = states[first_bad]
            v.differs.append(f"state #{first_bad} (t = {s.sim_time_s:.6g} s, twin "
                             f"{ref_t[first_bad]:.6g} s) differs from the twin; max |yaw rate "
                             f"diff| {worst:.3g} rad/s")
        for name, msgs, ref, field in (("driver input", drivers, twin["front"],
                                        "front_wheel_angle_rad"),
                                       ("rear-steer command", cmds, twin["rear"], "angle_rad")):
            bad = [i for i, m in enumerate(msgs[:len(ref)])
                   if not abs(getattr(m, field) - ref[i]) <= 1e-12]
            if bad:
                v.differs.append(f"{len(bad)} {name}s differ from the twin (first #{bad[0]})")
        if len(states) == n + 1 and "sim_time_s" in twin["final"]:
            if states[n].sim_time_s != twin["final"]["sim_time_s"]:
                v.differs.append("the final state is not the twin's")
    # holes: consecutive states must be one period apart
    period = CONTROL_PERIOD_S
    holes = [(a, b) for a, b in zip(times, times[1:])
             if math.isfinite(a) and math.isfinite(b) and abs(b - a - period) > 1e-6
             and a < 1e5 and b < 1e5]
    if holes:
        a, b = holes[0]
        v.gaps.append(f"{len(holes)} holes in /fourws/state (first {a:.2f} -> {b:.2f} s)")
    for name, msgs in (("driver_input", drivers), ("rear_steer_cmd", cmds)):
        ts = [_stamp_s(m.header.stamp) for m in msgs if m.law == LAW] if name == \
            "rear_steer_cmd" else [_stamp_s(m.header.stamp) for m in msgs
                                   if abs(m.front_wheel_angle_rad) < 1.0]
        hs = [(a, b) for a, b in zip(ts, ts[1:]) if clock == "lockstep"
              and abs(b - a - period) > 1e-6]
        if hs:
            v.gaps.append(f"{len(hs)} holes in /fourws/{name} (first {hs[0][0]:.2f} -> "
                          f"{hs[0][1]:.2f} s)")
    if clock == "realtime" and duration_s is not None and states:
        if v.last_state_s < duration_s - 0.02:
            v.short.append(f"states end at {v.last_state_s:.2f} s of {duration_s} s")
        if len(drivers) == 0 or len(cmds) == 0:
            v.short.append(f"driver inputs {len(drivers)}, commands {len(cmds)}")
    return v


# ---------------------------------------------------------------------------------------------
# attempts

@dataclasses.dataclass
class Result:
    name: str
    group: str
    verdict: str
    rc: int | None
    wall_s: float
    error: str = ""
    notes: list[str] = dataclasses.field(default_factory=list)
    counts: dict[str, int] = dataclasses.field(default_factory=dict)
    reproduce: str = ""
    run_dir: str = ""


@dataclasses.dataclass
class Expect:
    """What an attempt is judged against."""

    scenario: str
    culprit: tuple[str, ...] = ()   # an error must name one of these (case-insensitive)
    absurd: bool = False            # exit 0 means an absurd input was accepted
    signal_exit: bool = False       # the launcher itself was killed: no message possible
    disk_full: bool = False         # the end of the run cannot be on disk: no loss bound


def _error_lines(stdout: str, stderr: str) -> list[str]:
    """The command's own error lines (``fourws run: <law> failed: ...``, ``fourws run:
    error: ...`` on stderr; ``run <law>: FAILED: ...`` / ``INTERRUPTED`` on stdout), not its
    progress lines."""
    return ([line for line in stdout.splitlines()
             if re.match(r"^run \S+: (FAILED|INTERRUPTED|ABORTED|DIVERGED)", line)]
            + [line for line in stderr.splitlines() if line.startswith("fourws run: ")])


def _reached_s(stdout: str, out: Path) -> float | None:
    m = re.search(r"simulated ([0-9.eE+-]+) s in", stdout)
    if m:
        return float(m.group(1))
    for rec in out.glob("*/run.json"):
        try:
            return float(json.loads(rec.read_text()).get("sim_time_s", 0.0))
        except (OSError, ValueError):
            return None
    return None


def judge(work: Work, run: Run, expect: Expect, name: str, group: str, how: str,
          notes: list[str]) -> Result:
    """Classify one finished run (see the module docstring)."""
    inst = work.inst
    _text, clock, duration = SCENARIOS[expect.scenario]
    stdout, stderr = run.stdout(), run.stderr()
    res = Result(name, group, "", run.rc, round(run.wall_s, 1), notes=list(notes),
                 reproduce=how)
    bag_path = find_bag(run.out)
    res.run_dir = str(bag_path.parent) if bag_path else str(run.out)
    left = [] if run.timed_out else run.leftovers()
    if left:
        res.notes.append(f"node processes alive {ORPHAN_GRACE_S:.0f} s after the launcher "
                         f"ended: {sorted(left)}")
    run.kill_leftovers()
    says_ok = bool(re.search(r"^run \S+: ok( \(.*\))?$", stdout, re.M))  # ok, or ok (a note)
    errors = _error_lines(stdout, stderr)
    res.error = errors[-1] if errors else ""
    twin = work.twin(expect.scenario)
    if bag_path is not None and not (bag_path / "metadata.yaml").is_file() and \
            inst.has_repair and not run.timed_out:
        # the installation's own recovery, on a copy (the disk of the run may be full)
        copy = work.root / "repaired" / re.sub(r"\W+", "_", name)
        shutil.rmtree(copy, ignore_errors=True)
        shutil.copytree(bag_path, copy)
        rep = subprocess.run([str(inst.fourws), "bag", "repair", str(copy)],
                             capture_output=True, text=True, timeout=120, cwd=work.root,
                             env=base_env())
        tail = (rep.stdout + rep.stderr).strip().splitlines()
        res.notes.append(f"bag had no metadata.yaml; `fourws bag repair` (on a copy) exit "
                         f"{rep.returncode}: {tail[-1] if tail else ''}"[:240])
        if "Traceback" in rep.stdout + rep.stderr:
            res.notes.append("`fourws bag repair` printed a traceback")
        bag_path = copy
    bag = read_bag(bag_path)
    res.counts = bag.counts()
    verdict = inspect_bag(bag, twin, duration, clock)
    if bag.read_error:
        res.notes.append(f"mcap read stopped: {bag.read_error}")
    if run.timed_out:
        res.verdict = "hang"
        res.notes.append(f"no exit within {run.timeout_s:.0f} s (killed)")
    elif left:
        res.verdict = "hang"
    elif "Traceback" in stdout + stderr:
        res.verdict = "traceback"
        tb = [line for line in (stdout + stderr).splitlines() if line and not
              line.startswith(" ")]
        res.notes.append("last line: " + (tb[-1] if tb else "")[:200])
    elif run.rc == 0 or says_ok:
        problems = []
        if expect.absurd:
            problems.append("absurd input accepted")
        if run.rc != 0:
            problems.append(f"says ok but exit {run.rc}")
        if not says_ok:
            problems.append("exit 0 without 'ok'")
        if bag_path is None:
            problems.append("no bag")
        elif not bag.metadata or not bag.rosbags_ok:
            problems.append(f"bag not readable by rosbags ({bag.rosbags_error})")
        problems += verdict.short + verdict.foreign + verdict.differs + verdict.gaps
        if not problems and not verdict.states:
            problems.append("empty bag")
        res.verdict = "silent wrong" if problems else "correct"
        res.notes += problems
    else:
        lost = []
        if bag_path is not None:
            if verdict.gaps:
                lost += verdict.gaps
            reached = _reached_s(stdout, run.out)
            if reached is not None and verdict.last_state_s >= -0.5:
                loss = reached - max(verdict.last_state_s, 0.0)
                if expect.disk_full:
                    res.notes.append(f"bag ends at t = {verdict.last_state_s:.2f} s, run "
                                     f"reached {reached:.2f} s (the disk was full)")
                elif loss > LOSS_BOUND_S + CONTROL_PERIOD_S:
                    lost.append(f"bag ends at t = {verdict.last_state_s:.2f} s, run reached "
                                f"{reached:.2f} s: {loss:.2f} s lost (bound "
                                f"{LOSS_BOUND_S:.1f} s)")
            elif reached is not None and reached > LOSS_BOUND_S and not verdict.states:
                lost.append(f"bag holds no state, run reached {reached:.2f} s")
            if verdict.states and (not bag.metadata or not bag.rosbags_ok):
                lost.append(f"bag not readable by rosbags ({bag.rosbags_error})")
            if verdict.foreign:
                res.notes.append("foreign data in the bag: " + "; ".join(verdict.foreign))
        if lost:
            res.verdict = "data lost"
            res.notes += lost
        elif expect.signal_exit and run.rc is not None and run.rc < 0:
            res.verdict = "clear error"
        elif not errors:
            res.verdict = "unclear"
            res.notes.append(f"exit {run.rc} without a one-line 'fourws run: ...' error")
        elif expect.culprit and not any(c.lower() in res.error.lower()
                                        for c in expect.culprit):
            res.verdict = "unclear"
            res.notes.append(f"the error names none of {list(expect.culprit)}")
        else:
            res.verdict = "clear error"
    if verdict.foreign and res.verdict in ("correct", "clear error"):
        res.notes.append("foreign data in the bag: " + "; ".join(verdict.foreign))
    return res


def _moment(run: Run, moment: str) -> str:
    """Wait for a moment of the run; returns what was seen ('' if the run ended first)."""
    if moment == "startup":
        ok = run.wait_for(lambda: len(node_pids(run.marker)) >= 4, 60)
        time.sleep(0.7)
        if not ok or not run.running():
            return ""
        return "graph not up yet" if not run.graph_up() else "graph already up"
    ok = run.wait_for(run.graph_up, 90)
    if not ok or not run.running():
        return ""
    time.sleep({"early": 0.2, "mid": 1.0, "late": 2.0}[moment])
    return "running" if run.running() else ""


def _signal_node(run: Run, kind: str, sig: signal.Signals) -> str:
    pids = node_pids(run.marker).get(kind, [])
    for pid in pids:
        os.kill(pid, sig)
    return f"{sig.name} to {kind} {pids}" if pids else f"no {kind} process found"


class Attempts:
    """The attempts of one pass and their results."""

    def __init__(self, work: Work, only: str | None) -> None:
        self.work = work
        self.only = re.compile(only) if only else None
        self.results: list[Result] = []

    def wanted(self, name: str) -> bool:
        return self.only is None or bool(self.only.search(name))

    def record(self, res: Result) -> None:
        self.results.append(res)
        flag = "" if res.verdict in ("correct", "clear error") else "  <<<"
        print(f"  {res.name:58s} {res.verdict:12s} exit {res.rc!s:>4s} {res.wall_s:6.1f} s"
              f"{flag}", flush=True)
        if flag:
            for n in res.notes:
                print(f"      - {n}", flush=True)
            if res.error:
                print(f"      error: {res.error}", flush=True)

    def how(self, scenario: str, extra: str = "") -> str:
        return (f"{self.work.inst.fourws} run {self.work.scenarios[scenario]} --law {LAW} "
                f"--out DIR" + (f"; {extra}" if extra else ""))

    # -- one run with an action at a moment ---------------------------------------------------
    def single(self, name: str, *args: Any, **kw: Any) -> None:
        """One run with an action (see :meth:`_single`); a fault of the harness itself is
        reported and the pass goes on."""
        try:
            self._single(name, *args, **kw)
        except Exception as exc:  # the harness's own bug must not end a 30 min pass
            print(f"  {name:58s} HARNESS ERROR {type(exc).__name__}: {exc}", flush=True)

    def _single(self, name: str, group: str, expect: Expect,
                action: Callable[[Run], str] | None = None, env: dict[str, str] | None = None,
                out: Path | None = None, how: str = "", before: Callable[[], str] | None = None,
                timeout_s: float = HANG_S) -> None:
        if not self.wanted(name):
            return
        adir = self.work.attempt_dir(name)
        notes = []
        if before is not None:
            notes.append(before())
        run = Run(self.work.inst, self.work.scenarios[expect.scenario], out or adir / "runs",
                  adir, env=env)
        try:
            if action is not None:
                seen = action(run)
                if seen:
                    notes.append(seen)
        finally:
            run.wait(timeout_s)
        res = judge(self.work, run, expect, name, group, how or self.how(expect.scenario),
                    notes)
        if out is not None and out.is_dir():
            # a run folder on a scratch disk: keep a copy before the disk goes
            shutil.copytree(out, adir / "kept", dirs_exist_ok=True,
                            ignore_dangling_symlinks=True)
            res.run_dir = str(adir / "kept")
        self.record(res)

    def side_by_side(self, k: int, hog: bool, trial: int) -> None:
        name = f"side-by-side x{k}{' +hog' if hog else ''} #{trial}"
        if not self.wanted(name):
            return
        self.work.twin("short")
        adir = self.work.attempt_dir(name)
        hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"], cwd=adir)
                for _ in range(2 if hog else 0)]
        try:
            runs = [Run(self.work.inst, self.work.scenarios["short"], adir / f"runs{i}", adir)
                    for i in range(k)]
            for r in runs:
                r.wait(HANG_S)
        finally:
            for h in hogs:
                h.kill()
                h.wait()
        how = (f"{k}x `{self.how('short')}` started at once"
               + (" while 2 `python -c 'while True: pass'` run" if hog else ""))
        for i, r in enumerate(runs):
            self.record(judge(self.work, r, Expect("short"), f"{name} run {i + 1}",
                              "side by side" + (" + CPU hog" if hog else ""), how, []))

    def rogue(self, kinds: str, scenario: str, extra: Callable[[Run], str] | None = None,
              culprit: tuple[str, ...] = ("rogue", "second publisher", "foreign")) -> None:
        name = (f"rogue {kinds} ({SCENARIOS[scenario][1]})"
                + (" +controller stopped" if extra else ""))
        if not self.wanted(name):
            return
        inst = self.work.inst
        self.work.twin(scenario)
        holder: dict[str, Any] = {}
        env = base_env()
        domain = None
        if inst.has_repair:
            # this installation takes the user's ROS_DOMAIN_ID: start the rogue first
            domain = free_domain()
            env["ROS_DOMAIN_ID"] = str(domain)

        def start_rogue(renv: dict[str, str]) -> subprocess.Popen:
            proc = subprocess.Popen([str(inst.python), str(self.work.rogue), kinds, "600"],
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                    text=True, env=renv, start_new_session=True,
                                    cwd=self.work.root)
            line = proc.stdout.readline()
            holder["ready"] = line.strip()
            return proc

        def before() -> str:
            holder["proc"] = start_rogue(dict(env))
            return f"rogue started on domain {domain} before the run ({holder['ready']})"

        def action(run: Run) -> str:
            seen = ""
            if "proc" not in holder:
                # the installation picks its own domain: take the nodes' environment
                run.wait_for(lambda: bool(node_pids(run.marker).get("simulator")), 60)
                pids = node_pids(run.marker).get("simulator", [])
                if not pids:
                    return "no simulator process: rogue not started"
                nenv = proc_environ(pids[0])
                renv = base_env()
                for key, value in nenv.items():
                    if key.startswith(("ROS_", "RMW_", "FASTDDS", "FASTRTPS")):
                        renv[key] = value
                holder["proc"] = start_rogue(renv)
                seen = (f"rogue started on the nodes' domain {renv.get('ROS_DOMAIN_ID')} "
                        f"(from /proc/{pids[0]}/environ)")
            if extra is not None:
                seen += "; " + extra(run)
            return seen

        try:
            self.single(name, "rogue publisher", Expect(scenario, culprit=culprit),
                        action=action, env=env, before=before if domain is not None else None,
                        how=(f"ROS_DOMAIN_ID=D {self.how(scenario)} with "
                             f"`python rogue.py {kinds} 600` (the harness's ROGUE_CODE) "
                             f"publishing on domain D"
                             + (" ; SIGSTOP of the controller 2 s after graph up"
                                if extra else "")))
        finally:
            proc = holder.get("proc")
            if proc is not None:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                proc.wait()


def free_domain() -> int:
    """A ROS domain no fourws run holds (above fourws's own range, so automatic picks of other
    runs never take it); fourws's lock stays with the run that uses it."""
    lock_dir = Path(tempfile.gettempdir()) / "fourws-domains"
    lock_dir.mkdir(parents=True, exist_ok=True)
    for domain in range(150 + os.getpid() % 50, 232):
        with open(lock_dir / f"{domain}.lock", "w") as handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                continue
            fcntl.flock(handle, fcntl.LOCK_UN)
            return domain
    raise SystemExit("adversarial: no free ROS domain")


def _mount(where: Path, opts: str) -> str:
    where.mkdir(parents=True, exist_ok=True)
    res = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(where)],
                         capture_output=True, text=True)
    return "" if res.returncode == 0 else (res.stderr.strip() or "mount failed")


def _umount(where: Path) -> None:
    subprocess.run(["umount", "-l", str(where)], capture_output=True)


def run_pass(work: Work, only: str | None, trials: int) -> list[Result]:
    """Every attempt against ``work.inst``."""
    at = Attempts(work, only)
    sig = signal

    # baselines
    at.single("baseline lockstep", "baseline", Expect("short"))
    at.single("baseline realtime", "baseline", Expect("rt"))

    # side by side, with and without a CPU hog
    for hog in (False, True):
        for k in (2, 3):
            for trial in range(1, trials + 1):
                at.side_by_side(k, hog, trial)

    # SIGKILL / SIGSTOP of each node at several moments (lockstep, 60 s simulated)
    for kind in NODES:
        for moment in ("startup", "early", "late"):
            def act(run: Run, kind=kind, moment=moment) -> str:
                seen = _moment(run, moment)
                if not seen:
                    return "run ended before the fault"
                return f"{moment} ({seen}): " + _signal_node(run, kind, sig.SIGKILL)
            at.single(f"SIGKILL {kind} @{moment}", "SIGKILL node",
                      Expect("long", culprit=(f"fourws_{kind}",)), action=act,
                      how=at.how("long", f"SIGKILL the {kind} node ({moment})"))
    for kind in NODES:
        for moment in ("startup", "mid"):
            def act(run: Run, kind=kind, moment=moment) -> str:
                seen = _moment(run, moment)
                if not seen:
                    return "run ended before the fault"
                return f"{moment} ({seen}): " + _signal_node(run, kind, sig.SIGSTOP)
            at.single(f"SIGSTOP {kind} @{moment}", "SIGSTOP node",
                      Expect("long", culprit=(f"fourws_{kind}",)), action=act,
                      how=at.how("long", f"SIGSTOP the {kind} node ({moment}), never continued"))

    # the launcher: SIGKILL, SIGSTOP (continued after 10 s), double SIGINT
    for moment in ("startup", "early", "late"):
        def act(run: Run, moment=moment) -> str:
            seen = _moment(run, moment)
            if not seen:
                return "run ended before the fault"
            os.kill(run.proc.pid, sig.SIGKILL)
            return f"{moment} ({seen}): SIGKILL to the launcher {run.proc.pid}"
        at.single(f"SIGKILL launcher @{moment}", "launcher",
                  Expect("long", signal_exit=True), action=act,
                  how=at.how("long", f"SIGKILL the fourws run process ({moment})"))
    for moment in ("startup", "mid"):
        def act(run: Run, moment=moment) -> str:
            seen = _moment(run, moment)
            if not seen:
                return "run ended before the fault"
            os.kill(run.proc.pid, sig.SIGSTOP)
            time.sleep(10.0)
            os.kill(run.proc.pid, sig.SIGCONT)
            return f"{moment} ({seen}): launcher stopped for 10 s, then continued"
        # the graph may well finish meanwhile: ok, or a failure that says what happened
        at.single(f"SIGSTOP launcher 10 s @{moment}", "launcher",
                  Expect("long", culprit=("launcher",)), action=act,
                  how=at.how("long", f"SIGSTOP the fourws run process ({moment}), SIGCONT "
                                     "10 s later"))
    for moment, gap in (("startup", 0.1), ("early", 0.1), ("mid", 1.0)):
        def act(run: Run, moment=moment, gap=gap) -> str:
            seen = _moment(run, moment)
            if not seen:
                return "run ended before the fault"
            os.kill(run.proc.pid, sig.SIGINT)
            time.sleep(gap)
            if run.running():
                os.kill(run.proc.pid, sig.SIGINT)
            return f"{moment} ({seen}): SIGINT twice, {gap} s apart"
        at.single(f"double SIGINT @{moment} gap {gap}s", "launcher",
                  Expect("long", culprit=("interrupted",)), action=act,
                  how=at.how("long", f"Ctrl-C twice {gap} s apart ({moment})"))

    # rogue publishers on the run's domain
    for kinds in ("nan_state", "clock_state", "future_state", "future_cmd", "driver_100rad",
                  "done_status", "final_status", "flood", "mimic"):
        at.rogue(kinds, "long")
    at.rogue("nan_state,future_state,future_cmd,driver_100rad,done_status", "rt_long")

    def stop_controller(run: Run) -> str:
        if not run.wait_for(run.graph_up, 90):
            return "graph never up"
        time.sleep(2.0)
        return _signal_node(run, "controller", sig.SIGSTOP)
    at.rogue("future_cmd", "rt_long", extra=stop_controller,
             culprit=("fourws_controller", "controller"))

    # realtime, maneuver node stopped
    for moment in ("early", "late"):
        def act(run: Run, moment=moment) -> str:
            seen = _moment(run, moment)
            if not seen:
                return "run ended before the fault"
            return f"{moment}: " + _signal_node(run, "maneuver", sig.SIGSTOP)
        at.single(f"realtime, maneuver SIGSTOP @{moment}", "realtime maneuver stopped",
                  Expect("rt_long", culprit=("maneuver",)), action=act,
                  how=at.how("rt_long", f"SIGSTOP the maneuver node ({moment})"))

    # disks
    disk = work.root / "disk"
    for name, opts, fill, sub in (("full disk during the run", "size=256k", False, ""),
                                  ("full disk before the run", "size=256k", True, ""),
                                  ("read-only output folder", "ro,size=64k", False, "runs")):
        if not at.wanted(name):
            continue
        where = disk / re.sub(r"\W+", "_", name)
        why = _mount(where, opts)
        if why:
            print(f"  {name:58s} skipped: cannot mount a tmpfs ({why})", flush=True)
            continue
        try:
            if fill:
                fd = os.open(where / "filler", os.O_WRONLY | os.O_CREAT)
                try:
                    while os.write(fd, b"\0" * 4096):
                        pass
                except OSError:  # the disk is full: what we wanted
                    pass
                finally:
                    os.close(fd)
            at.single(name, "disk", Expect("long", culprit=("space", "read-only"),
                                           disk_full="full" in name),
                      out=where / sub if sub else where,
                      how=f"{work.inst.fourws} run {work.scenarios['long']} --out "
                          f"<{'full 256 KiB' if 'full' in name else 'read-only'} tmpfs>"
                          + (" (filled before the run)" if fill else ""))
        finally:
            _umount(where)

    # absurd but well-formed scenario values
    for scen in ("absurd_amplitude", "absurd_duration", "absurd_speed", "absurd_step"):
        at.single(scen.replace("_", " "), "absurd input", Expect(scen, absurd=True),
                  timeout_s=90.0)

    # the tools beside the graph
    tool_attempts(at)
    return at.results


# ---------------------------------------------------------------------------------------------
# the tools beside the graph: files, command lines, environment (issue 20, points 6-8)

#: A one-point study of the 8-DOF closed loop (1 s of simulated time): the base of the study
#: file attempts.
STUDY = """name: adv
scenario:
  name: adv
  vehicle: table_8_1
  model: 8dof
  laws: [fws]
  maneuver: {name: s, type: step_steer, initial_speed_mps: 20.0, duration_s: 1.0,
             amplitude_rad: 0.02, start_s: 0.2, ramp_time_s: 0.1}
block_size: 1
"""
#: A bag writer kept open (a recording in progress) until its stdin is closed.
LIVE_BAG_CODE = r"""
import sys
from fourws_analysis import bag as B
store = B.typestore()
mt = B.TOPIC_TYPES[B.TOPIC_STATE]
writer = B.BagWriter(sys.argv[1]).open()
for i in range(50):
    msg = B.make_message(mt, header={"stamp": B.stamp(0.01 * i)}, step=i, model="2dof")
    writer.write_raw(B.TOPIC_STATE, store.serialize_cdr(msg, mt), 10_000_000 * i)
writer.flush()
print("recording", flush=True)
sys.stdin.read()
writer.close()
"""
#: Byte offset of the last byte of one data column of a Parquet block (inside a data page).
DATA_PAGE_CODE = r"""
import sys
import pyarrow.parquet as pq
meta = pq.ParquetFile(sys.argv[1]).metadata.row_group(0)
col = next(meta.column(i) for i in range(meta.num_columns)
           if meta.column(i).path_in_schema == "max_abs_sideslip_rad")
print(col.data_page_offset + col.total_compressed_size - 1)
"""
SHIPPED_CODE = "from fourws_sim.params import CONFIG_DIR; print(CONFIG_DIR)"


@dataclasses.dataclass
class Finished:
    """A command of a tool attempt, finished (or killed at its time limit)."""

    rc: int | None
    stdout: str
    stderr: str
    wall_s: float
    timed_out: bool


def run_command(argv: list[str], cwd: Path, env: dict[str, str] | None = None,
                timeout_s: float = 300.0, stdin: str | None = None) -> Finished:
    t0 = time.monotonic()
    proc = subprocess.Popen(argv, cwd=cwd, env=env or base_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, stdin=subprocess.PIPE, text=True,
                            errors="replace", start_new_session=True)
    try:
        out, err = proc.communicate(stdin, timeout=timeout_s)
        timed_out = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        timed_out = True
    return Finished(proc.returncode, out, err, time.monotonic() - t0, timed_out)


def refusal(done: Finished, prefix: str, needles: tuple[str, ...],
            code: int = 2) -> tuple[str, str, list[str]]:
    """(verdict, error line, notes) of a command that must refuse its input: exit ``code``
    and one line starting with ``prefix`` that holds every needle."""
    ours = [line for line in done.stderr.splitlines() if line.startswith(prefix)]
    error = ours[-1] if ours else ""
    if done.timed_out:
        return "hang", error, ["no exit within its time limit (killed): the input was taken"]
    if "Traceback" in done.stdout + done.stderr:
        tail = [line for line in done.stderr.splitlines() if line.strip()]
        return "traceback", error, [f"last line: {tail[-1][:200] if tail else ''}"]
    if done.rc == 0:
        return "silent wrong", error, ["exit 0: the input was accepted"]
    missing = [n for n in needles if n not in error]
    if done.rc != code or len(ours) != 1 or missing:
        notes = [f"exit {done.rc} (want {code}), {len(ours)} line(s) starting "
                 f"{prefix!r}"] + ([f"the error lacks {missing}"] if missing else [])
        return "unclear", error, notes
    return "clear error", error, []


def tool_attempts(at: "Attempts") -> None:
    """The tool attempts of a pass (module docstring)."""
    inst, work = at.work.inst, at.work
    fourws = str(inst.fourws)
    config = Path(run_command([str(inst.python), "-c", SHIPPED_CODE], work.root).stdout
                  .strip() or ".")

    def case(name: str, group: str, how: str,
             body: Callable[[Path], tuple[str, str, list[str], Finished | None]]) -> None:
        if not at.wanted(name):
            return
        adir = work.attempt_dir(name)
        try:
            verdict, error, notes, done = body(adir)
        except Exception as exc:  # the harness's own bug must not end a 30 min pass
            print(f"  {name:58s} HARNESS ERROR {type(exc).__name__}: {exc}", flush=True)
            return
        at.record(Result(name, group, verdict, done.rc if done else None,
                         round(done.wall_s, 1) if done else 0.0, error, notes,
                         reproduce=how, run_dir=str(adir)))

    def refuse(argv: list[str], needles: Callable[[Path], tuple[str, ...]], prefix: str,
               setup: Callable[[Path], None] | None = None, env: dict[str, str] | None = None,
               absent: str = "", code: int = 2, timeout_s: float = 300.0):
        def body(adir: Path):
            if setup is not None:
                setup(adir)
            done = run_command([a.replace("{A}", str(adir)) for a in argv], adir, env,
                               timeout_s)
            verdict, error, notes = refusal(done, prefix, needles(adir), code)
            if absent and (adir / absent).exists() and verdict == "clear error":
                verdict, notes = "unclear", [f"{absent} was created before the refusal"]
            return verdict, error, notes, done
        return body

    def study_file(text: str, name: str = "study.yaml", data: bytes | None = None):
        def setup(adir: Path) -> None:
            path = adir / name
            if data is not None:
                path.write_bytes(data)
            else:
                path.write_text(text)
        return setup

    # study files (point 6)
    twice = STUDY.replace("block_size: 1\n", "block_size: 1\nblock_size: 2\n")
    case("study file with a duplicate key", "study files",
         f"{fourws} study S --out D --no-report  # S: block_size twice",
         refuse([fourws, "study", "{A}/study.yaml", "--out", "{A}/out", "--no-report"],
                lambda a: (str(a / "study.yaml"), "duplicate key"), "fourws study: error:",
                setup=study_file(twice), absent="out"))
    latin1 = STUDY.replace("name: adv\n", "name: adv\ndescription: f\u00fcr\n", 1)
    case("study file in Latin-1", "study files",
         f"{fourws} study S --out D --no-report  # S: Latin-1 text",
         refuse([fourws, "study", "{A}/study.yaml", "--out", "{A}/out", "--no-report"],
                lambda a: (str(a / "study.yaml"), "UTF-8"), "fourws study: error:",
                setup=study_file("", data=latin1.encode("latin-1")), absent="out"))
    metric = STUDY + "report: {metrics: [no_such_metric]}\n"
    case("study with an unknown report metric", "study files",
         f"{fourws} study S --out D --no-report  # S: report.metrics [no_such_metric]",
         refuse([fourws, "study", "{A}/study.yaml", "--out", "{A}/out", "--no-report"],
                lambda a: ("no_such_metric", "valid: "), "fourws study: error:",
                setup=study_file(metric), absent="out", timeout_s=600.0))

    finished: dict[str, Path] = {}

    def finished_study(adir: Path) -> Path:
        """A copy of a finished study folder (the study runs once per pass)."""
        if "dir" not in finished:
            base = work.root / "study-finished"
            shutil.rmtree(base, ignore_errors=True)
            base.mkdir()
            (base / "study.yaml").write_text(STUDY)
            done = run_command([fourws, "study", str(base / "study.yaml"), "--out",
                                str(base / "out"), "--no-report"], base, timeout_s=900.0)
            if done.rc != 0:
                raise RuntimeError(f"the base study failed: {done.stderr[-300:]}")
            finished["dir"] = base
        shutil.copytree(finished["dir"], adir / "s", dirs_exist_ok=True)
        return adir / "s"

    def stray(adir: Path):
        root = finished_study(adir)
        block = root / "out" / "blocks" / "block-000000.parquet"
        shutil.copy(block, block.with_name("block-000099.parquet"))
        done = run_command([fourws, "study", str(root / "study.yaml"), "--out",
                            str(root / "out"), "--resume", "--no-report"], adir)
        verdict, error, notes = refusal(done, "fourws study: error:",
                                        (str(block.with_name("block-000099.parquet")),))
        return verdict, error, notes, done
    case("study --resume with a stray block file", "study files",
         f"{fourws} study S --out D --resume  # D/blocks/block-000099.parquet a stray copy",
         stray)

    def flipped(adir: Path):
        root = finished_study(adir)
        block = root / "out" / "blocks" / "block-000000.parquet"
        where = run_command([str(inst.python), "-c", DATA_PAGE_CODE, str(block)], adir)
        data = bytearray(block.read_bytes())
        data[int(where.stdout.strip())] ^= 0x10
        block.write_bytes(bytes(data))
        done = run_command([fourws, "study", "report", str(root / "out")], adir)
        verdict, error, notes = refusal(done, "fourws study: error:", (str(block),))
        if verdict == "clear error":
            again = run_command([fourws, "study", str(root / "study.yaml"), "--out",
                                 str(root / "out"), "--resume", "--no-report"], adir,
                                timeout_s=600.0)
            if again.rc != 0:
                verdict = "unclear"
                notes.append(f"--resume did not recompute the damaged block (exit {again.rc})")
        return verdict, error, notes, done
    case("study report with a flipped byte in a block", "study files",
         f"{fourws} study report D  # a byte of a data page of block 0 flipped; then "
         "--resume", flipped)

    # a vehicle with an unknown tire coefficient, in every tool (point 6)
    def bad_vehicle(adir: Path) -> None:
        text = (config / "vehicles" / "table_8_1.yaml").read_text()
        text = re.sub(r"^(  sti:.*)$", r"\1\n    bogus_key: 1.0", text, count=1, flags=re.M)
        (adir / "vehicle.yaml").write_text(text)
        (adir / "scenario.yaml").write_text(SCENARIOS["short"][0].replace(
            "vehicle: table_8_1", f"vehicle: {adir / 'vehicle.yaml'}"))
    for tool, argv in (("linear", ["--vehicle", "{A}/vehicle.yaml", "--model", "3dof",
                                   "--law", "sol1", "--speed-kmh", "85"]),
                       ("handling", ["--vehicle", "{A}/vehicle.yaml", "--law", "sol1"]),
                       ("run", ["{A}/scenario.yaml", "--law", LAW, "--out", "{A}/runs"])):
        case(f"unknown tire coefficient, fourws {tool}", "vehicle files",
             f"{fourws} {tool} ... # the vehicle's tire.sti has bogus_key",
             refuse([fourws, tool, *argv], lambda a: ("bogus_key", str(a / "vehicle.yaml")),
                    f"fourws {tool}: error:", setup=bad_vehicle, timeout_s=HANG_S))

    # node parameter files (point 6); the node runs on its own domain
    def node_env() -> dict[str, str]:
        return {**base_env(), "ROS_DOMAIN_ID": str(free_domain())}

    def typo_params(adir: Path) -> None:
        text = (config / "params" / "lockstep.yaml").read_text()
        (adir / "params.yaml").write_text(text.replace("    integrator: rk4",
                                                       "    integrater: rk4", 1))
    for what, setup, needle in (
            ("an unknown parameter", typo_params, "integrater"),
            ("empty", lambda a: (a / "params.yaml").write_text("# empty\n"), "empty")):
        case(f"simulator params file with {what}", "node parameters",
             f"{fourws} node simulator --ros-args --params-file P  # P {what}",
             refuse([fourws, "node", "simulator", "--ros-args", "--params-file",
                     "{A}/params.yaml"], lambda a, n=needle: (n, str(a / "params.yaml")),
                    "[fourws_simulator] error:", setup=setup, env=node_env(), timeout_s=90.0))

    # a node stopped while it is still importing (point 6)
    def stopped_importing(adir: Path):
        proc = subprocess.Popen([fourws, "node", "simulator", "--ros-args", "--params-file",
                                 str(config / "params" / "lockstep.yaml")], cwd=adir,
                                env=node_env(), stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, errors="replace",
                                start_new_session=True)
        t0 = time.monotonic()
        sent = False
        while proc.poll() is None and time.monotonic() - t0 < 60.0:
            if "_rclpy_pybind11" in _proc_text(proc.pid, "maps"):
                os.kill(proc.pid, signal.SIGINT)
                sent = True
                break
            time.sleep(0.001)
        try:
            out, err = proc.communicate(timeout=60.0)
            timed_out = False
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out, err = proc.communicate()
            timed_out = True
        done = Finished(proc.returncode, out, err, time.monotonic() - t0, timed_out)
        if not sent:
            return "unclear", "", ["rclpy was never mapped: no SIGINT sent"], done
        if timed_out:
            return "hang", "", ["the node did not end after SIGINT"], done
        if "Traceback" in out + err or "KeyboardInterrupt" in out + err:
            return "traceback", "", ["a KeyboardInterrupt traceback in the node's log"], done
        if proc.returncode != 0:
            return "unclear", "", [f"exit {proc.returncode} (a stop is exit 0)"], done
        return "correct", "", [], done
    case("SIGINT to a node while it imports rclpy", "nodes",
         f"{fourws} node simulator ...; SIGINT once /proc/PID/maps holds _rclpy_pybind11",
         stopped_importing)

    # a bag still being recorded (point 6)
    def live_bag(adir: Path):
        bag = adir / "live"
        writer = subprocess.Popen([str(inst.python), "-c", LIVE_BAG_CODE, str(bag)],
                                  cwd=adir, env=base_env(), stdin=subprocess.PIPE,
                                  stdout=subprocess.PIPE, text=True)
        try:
            if writer.stdout.readline().strip() != "recording":
                raise RuntimeError("the bag writer did not start")
            mcap = next(bag.glob("*.mcap"))
            before = mcap.read_bytes()
            done = run_command([fourws, "bag", "repair", str(bag)], adir, timeout_s=120.0)
            verdict, error, notes = refusal(done, "fourws bag: error:",
                                            (str(bag), "being recorded"))
            rewritten = list(bag.glob("*.damaged")) or not mcap.is_file() \
                or mcap.read_bytes() != before
            if rewritten:
                notes.append("the live bag's file was rewritten under its writer")
                if verdict in ("unclear", "clear error"):
                    verdict = "silent wrong"
        finally:
            writer.kill()
            writer.wait()
        return verdict, error, notes, done
    case("bag repair of a bag being recorded", "bags",
         f"{fourws} bag repair B  # while another process writes B", live_bag)

    # the environment and the command line (point 7)
    case("ROS_DOMAIN_ID=300", "environment", f"ROS_DOMAIN_ID=300 {fourws} run S --out D",
         refuse([fourws, "run", str(work.scenarios["short"]), "--law", LAW, "--out",
                 "{A}/runs"], lambda a: ("ROS_DOMAIN_ID",), "fourws run: error:",
                env={**base_env(), "ROS_DOMAIN_ID": "300"}, absent="runs",
                timeout_s=HANG_S))
    case("a law given twice", "command line", f"{fourws} run S --law fws --law fws --out D",
         refuse([fourws, "run", str(work.scenarios["short"]), "--law", "fws", "--law", "fws",
                 "--out", "{A}/runs"], lambda a: ("fws", "--law"), "fourws run: error:",
                absent="runs", timeout_s=2 * HANG_S))
    case("unknown option of a subcommand", "command line",
         f"{fourws} handling --vehicle table_4_4 --law sol1 --speed-kmh 85",
         refuse([fourws, "handling", "--vehicle", "table_4_4", "--law", "sol1", "--speed-kmh",
                 "85"], lambda a: ("unrecognized arguments: --speed-kmh 85",),
                "fourws handling: error:", timeout_s=60.0))

    def helps(adir: Path):
        done = run_command([fourws, "--help"], adir, timeout_s=60.0)
        version = run_command([fourws, "--version"], adir, timeout_s=60.0)
        notes = []
        if "Entry point" in done.stdout:
            notes.append("--help shows a module docstring as its description")
        if not re.search(r"^ {4}node\b", done.stdout, re.M):
            notes.append("--help does not list `node`")
        if version.rc != 0 or not re.match(r"^fourws \S+$", version.stdout.strip()):
            notes.append(f"--version: exit {version.rc}, {version.stdout.strip()[:60]!r}")
        return ("silent wrong" if notes else "correct"), "", notes, done
    case("--help and --version", "command line", f"{fourws} --help; {fourws} --version", helps)

    def summary(adir: Path):
        run_command([fourws, "run", str(work.scenarios["short"]), "--law", LAW, "--out",
                     str(adir / "runs")], adir, timeout_s=HANG_S)
        bag = find_bag(adir / "runs")
        if bag is None:
            raise RuntimeError("the run for the analysis recorded no bag")
        as_json = run_command([fourws, "analyze", str(bag), "--json", "--no-sweep",
                               "--quiet"], adir, timeout_s=300.0)
        done = run_command([fourws, "analyze", str(bag), "--no-sweep", "--quiet"], adir,
                           timeout_s=300.0)
        group = next(iter(json.loads(as_json.stdout)["runs"].values()))["iso7401_step"]
        leaves = []

        def walk(value: Any, prefix: str) -> None:
            if isinstance(value, dict):
                for key, item in value.items():
                    walk(item, f"{prefix}{key}.")
            elif isinstance(value, float):
                leaves.append(prefix[:-1].rsplit(".", 1)[-1])
        walk(group, "")
        missing = [key for key in leaves if key not in done.stdout]
        notes = [f"{len(missing)} of {len(leaves)} ISO 7401 values not printed whole, e.g. "
                 f"{missing[:3]}"] if missing else []
        return ("silent wrong" if missing or done.rc != 0 else "correct"), "", notes, done
    case("analyze summary without --report", "command line",
         f"{fourws} analyze BAG --no-sweep  # every ISO 7401 value of --json printed", summary)


# ---------------------------------------------------------------------------------------------
# report

def table(passes: dict[str, list[dict[str, Any]]]) -> str:
    head = ["", "attempts", *CLASSES]
    rows = [head]
    for label, results in passes.items():
        counts = {c: sum(1 for r in results if r["verdict"] == c) for c in CLASSES}
        rows.append([label, str(len(results)), *(str(counts[c]) for c in CLASSES)])
    widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
    lines = ["  ".join(cell.rjust(w) if i else cell.ljust(w)
                       for i, (cell, w) in enumerate(zip(row, widths))) for row in rows]
    return "\n".join(lines)


def group_table(passes: dict[str, list[dict[str, Any]]]) -> str:
    groups: list[str] = []
    for results in passes.values():
        for r in results:
            if r["group"] not in groups:
                groups.append(r["group"])
    lines = []
    for g in groups:
        cells = []
        for label, results in passes.items():
            rs = [r for r in results if r["group"] == g]
            bad = {}
            for r in rs:
                bad[r["verdict"]] = bad.get(r["verdict"], 0) + 1
            cells.append(f"{label}: " + ", ".join(f"{n} {v}" for v, n in bad.items()))
        lines.append(f"  {g:28s} " + " | ".join(cells))
    return "\n".join(lines)


def failures(label: str, results: list[dict[str, Any]]) -> str:
    lines = []
    for r in results:
        if r["verdict"] in ("correct", "clear error") and not any(
                "foreign data" in n for n in r["notes"]):
            continue
        lines.append(f"[{label}] {r['name']}: {r['verdict'].upper()} (exit {r['rc']}, "
                     f"{r['wall_s']} s)")
        if r["error"]:
            lines.append(f"    error: {r['error']}")
        for n in r["notes"]:
            lines.append(textwrap.fill(n, 96, initial_indent="    - ",
                                       subsequent_indent="      "))
        if r["counts"]:
            lines.append("    bag: " + ", ".join(f"{t.rsplit('/', 1)[-1]} {n}"
                                                 for t, n in r["counts"].items()))
        lines.append(f"    reproduce: {r['reproduce']}")
        lines.append(f"    folder: {r['run_dir']}")
    return "\n".join(lines) if lines else f"[{label}] none"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--fourws", type=Path, help="the fourws executable to attack")
    p.add_argument("--label", default=None, help="name of the installation in the table")
    p.add_argument("--work", type=Path, default=None,
                   help="scratch folder (default: a new folder under the temp dir)")
    p.add_argument("--json", type=Path, default=None, help="write the results here")
    p.add_argument("--only", default=None, help="regex: run only attempts whose name matches")
    p.add_argument("--trials", type=int, default=2,
                   help="side-by-side trials per configuration (default 2)")
    p.add_argument("--table", type=Path, nargs="+", default=None, metavar="JSON",
                   help="print the table of saved passes instead of running one")
    args = p.parse_args(argv)
    if args.table:
        passes = {}
        for path in args.table:
            data = json.loads(path.read_text())
            passes[data["label"]] = data["results"]
    else:
        if args.fourws is None:
            p.error("--fourws or --table is required")
        inst = Installation.from_path(args.fourws, args.label or str(args.fourws))
        root = args.work or Path(tempfile.mkdtemp(prefix=f"fourws-adv-{inst.label}-"))
        work = Work(root, inst)
        print(f"adversarial pass '{inst.label}' on {inst.fourws} (scratch {root})", flush=True)
        t0 = time.monotonic()
        results = run_pass(work, args.only, args.trials)
        elapsed = time.monotonic() - t0
        data = {"label": inst.label, "fourws": str(inst.fourws), "elapsed_s": round(elapsed),
                "results": [dataclasses.asdict(r) for r in results]}
        if args.json:
            args.json.write_text(json.dumps(data, indent=1))
        passes = {inst.label: data["results"]}
        print(f"\n{len(results)} attempts in {elapsed / 60:.1f} min", flush=True)
    print("\n" + table(passes))
    print("\nby group:\n" + group_table(passes))
    print("\nnot correct and not a clear error (or foreign data kept):")
    for label, results in passes.items():
        print(failures(label, results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
