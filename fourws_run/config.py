# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The one description of a run: :class:`RunConfig`.

A run is one vehicle (and the controller's belief of it), one maneuver, one rear-steer law or
controller, one model/tire/integrator and the rates and clock of the loop. A
:class:`RunConfig` is built from a scenario and a law (:meth:`RunConfig.from_scenario`), and
everything that needs to know what a run is reads it: the node parameters of the graph
(:mod:`fourws_ros.node_params`), the offline twin (:func:`fourws_run.closed_loop.run_config`),
the bag (``/fourws/run_config`` holds :meth:`RunConfig.to_dict` as JSON), ``fourws analyze``
and the study tool. A graph started by hand has no launcher to publish it; its nodes publish
what they run with (``/fourws/node_config``) and :meth:`RunConfig.from_node_configs` puts the
parts together.

Serialized layout (``to_dict``, JSON-ready, ``version`` 2): ``vehicle`` and ``belief_vehicle``
as vehicle-file mappings, ``maneuver`` as a maneuver-file mapping, ``law``, ``law_options``,
``controller`` (``command``, ``node_name``), ``model``, ``tire``, ``integrator``,
``integration_step_s``, ``control_period_s``, ``state_period_s``, ``clock_mode``,
``speed_mps``, ``scenario`` (its name), ``recorded_topics``, ``versions``, ``realtime``
(:class:`RealtimeDemand`; absent in older bags: the defaults). Version 1 (bags
recorded before the typed description; no ``version`` key, the belief sometimes a name) still
loads.
"""

from __future__ import annotations

import dataclasses
import os
import platform
import re
import shlex
import shutil
import sys
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from typing import Any, Mapping

from fourws_run import interface
from fourws_sim.errors import ParameterError
from fourws_sim.maneuvers import ManeuverSpec, maneuver_spec_from_mapping
from fourws_sim.params import (Vehicle, dataclass_from_mapping, declare_field, load_vehicle,
                               vehicle_from_mapping)

#: Layout version written by :meth:`RunConfig.to_dict`.
RUN_CONFIG_VERSION = 2
#: ``fourws run --driver NAME``: the fourws input-driver nodes (``fourws node <node>``) by the
#: name that selects them; any other ``--driver`` is a user's command.
INPUT_DRIVERS = {"ackermann": "ackermann_driver", "joy": "joy_driver"}
#: The law label of a run whose controller is the user's own and has not said its law.
USER_LAW = "user"


@dataclass(frozen=True)
class ControllerSpec:
    """Which controller node answers the states.

    Attributes
    ----------
    command : tuple of str
        The user's controller: an executable and its arguments, started with the run's ROS
        environment and ``--ros-args`` (remapping its node name to ``node_name`` and giving
        it the run's parameter file). Empty: fourws's own controller node with the run's law.
    node_name : str
        ROS node name of the controller.
    """

    command: tuple[str, ...] = ()
    node_name: str = interface.NODE_NAMES[interface.Role.CONTROLLER]

    @property
    def builtin(self) -> bool:
        """fourws's own controller node."""
        return not self.command

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {"command": list(self.command), "node_name": self.node_name}

    def check_runnable(self, source: str | None = None) -> None:
        """Refuse a user controller whose program or script does not exist, before anything
        of a run is created (a missing file would otherwise be found only once the graph is
        starting). The program is looked up on ``PATH`` with this Python's folder first (as
        the launcher starts it); for a Python interpreter, its script must exist too.

        Raises
        ------
        ParameterError
            ``controller.command`` names a program or script that is not there.
        """
        if self.builtin:
            return
        program = self.command[0]
        path = os.pathsep.join([os.path.dirname(sys.executable), os.environ.get("PATH", "")])
        if not program.endswith(".py") and shutil.which(program, path=path) is None \
                and not os.path.isfile(program):
            raise ParameterError("controller.command", f"{program!r}: no such program (on "
                                 "PATH or as a file)", source)
        script = program if program.endswith(".py") else next(
            (a for a in self.command[1:] if not a.startswith("-")), None)
        python = re.fullmatch(r"python[0-9.]*", os.path.basename(program)) is not None
        if (program.endswith(".py") or python) and script is not None \
                and not os.path.isfile(script):
            raise ParameterError("controller.command", f"{script!r}: no such file", source)

    @classmethod
    def from_mapping(cls, data: Any, source: str = "<controller>") -> "ControllerSpec":
        """Validate ``{command: [...] or "cmd args", name: ...}`` (a scenario's
        ``controller`` field).

        Raises
        ------
        ParameterError
            Unknown key, an empty or non-string command, a bad ROS node name.
        """
        if data is None:
            return cls()
        if not isinstance(data, Mapping):
            raise ParameterError("controller", "must be a mapping with command and name",
                                 source)
        bad = sorted(set(data) - {"command", "name", "node_name"})
        if bad:
            raise ParameterError(f"controller.{bad[0]}", "unknown field (valid: command, name)",
                                 source)
        command = data.get("command", ())
        if isinstance(command, str):
            command = shlex.split(command)
        if not isinstance(command, (list, tuple)) or not all(
                isinstance(c, str) and c for c in command):
            raise ParameterError("controller.command",
                                 "must be a command line (a string or a list of strings)",
                                 source)
        name = data.get("name", data.get("node_name", cls.node_name))
        check_node_name(name, "controller.name", source)
        return cls(tuple(command), str(name))


@dataclass(frozen=True)
class RealtimeDemand:
    """What a realtime run must achieve to be ``ok`` (scenario key ``realtime``).

    A realtime run cannot wait for a late command: a control tick without a command that
    answers a state of the last ``command_stale_periods`` control periods applies zero rear
    steer (the simulator's ``command_stale_periods``). A few such ticks on a loaded machine
    are a fact of wall-clock running, a controller that stopped answering or sends unusable
    commands is a failed run: above ``max_stale_share`` of the ticks stale, or of the commands
    refused, the run fails naming the controller. ``min_realtime_factor`` demands a pace:
    a run that simulated less than this per wall time fails (0: none demanded; a run that fell
    behind real time is said so either way). Lockstep runs ignore both: they never substitute
    an input and have no pace.
    """

    min_realtime_factor: float = declare_field(
        "nonnegative", default=0.0,
        doc="simulated time per wall time a realtime run must reach, 1 (0: no demand)",
        bounds=(0.0, 1.0))
    max_stale_share: float = declare_field(
        "fraction", default=0.01,
        doc="largest share of control ticks run without a fresh command, and of commands "
            "refused, 1", bounds=(0.0, 1.0))

    def to_dict(self) -> dict[str, float]:
        """The file layout."""
        return {"min_realtime_factor": self.min_realtime_factor,
                "max_stale_share": self.max_stale_share}

    @classmethod
    def from_mapping(cls, data: Any, source: str | None = None) -> "RealtimeDemand":
        """Validate a ``realtime`` mapping (None: the defaults).

        Raises
        ------
        ParameterError
            Unknown key, a value that is not a number in range.
        """
        if data is None:
            return cls()
        return dataclass_from_mapping(cls, data, source, "realtime.")


def check_node_name(name: Any, field_name: str, source: str | None = None) -> str:
    """A valid ROS node name (letters, digits, underscores; not starting with a digit).

    Raises
    ------
    ParameterError
        Otherwise.
    """
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,254}", name):
        raise ParameterError(field_name, f"must be a ROS node name (letters, digits, _), got "
                             f"{name!r}", source)
    return name


@dataclass(frozen=True)
class RunConfig:
    """Everything that defines one run (see the module docstring).

    Attributes
    ----------
    vehicle : Vehicle
        The simulated vehicle (tire override applied).
    belief : Vehicle
        The controller's belief of it (gains and actuator limits come from it).
    maneuver : ManeuverSpec
    law : str
        The rear-steer law (built-in controller), or the user controller's law label.
    law_options : mapping
        Options of the law.
    model, tire, integrator : str
        Vehicle model, tire model (None: the vehicle file's), integrator.
    integration_step_s, control_period_s, state_period_s : float
        Integration step, control period and (realtime) state period, s.
    clock_mode : str
        ``lockstep`` or ``realtime``.
    controller : ControllerSpec
    scenario : str
        Name of the scenario it came from ('' if none).
    recorded_topics : tuple of str
        The topics the bag records (empty: not recorded).
    realtime : RealtimeDemand
        What a realtime run must achieve to be ``ok``.
    versions : mapping
        Software versions the run used.
    """

    vehicle: Vehicle
    belief: Vehicle
    maneuver: ManeuverSpec
    law: str
    law_options: Mapping[str, Any] = field(default_factory=dict)
    model: str = "8dof"
    tire: str | None = None
    integrator: str = "rk4"
    integration_step_s: float = 1e-3
    control_period_s: float = 1e-2
    state_period_s: float = 1e-2
    clock_mode: str = "lockstep"
    controller: ControllerSpec = field(default_factory=ControllerSpec)
    driver: tuple[str, ...] = ()
    scenario: str = ""
    recorded_topics: tuple[str, ...] = interface.RECORDED_TOPICS
    versions: Mapping[str, str] = field(default_factory=dict)
    realtime: RealtimeDemand = field(default_factory=RealtimeDemand)

    @property
    def speed_mps(self) -> float:
        """Initial forward speed, m/s (the maneuver's)."""
        return float(self.maneuver.initial_speed_mps)

    @property
    def driver_node(self) -> str:
        """The fourws node that drives (``maneuver``, or an input driver of
        :data:`INPUT_DRIVERS`); '' for a user's driver command (:attr:`driver`)."""
        if not self.driver:
            return "maneuver"
        return INPUT_DRIVERS.get(self.driver[0], "") if len(self.driver) == 1 else ""

    @property
    def lockstep(self) -> bool:
        """The loop runs in lockstep."""
        return self.clock_mode == "lockstep"

    @property
    def controller_period_s(self) -> float:
        """Interval between the controller's answers, over which its command is held, s: it
        answers every published state, in lockstep once per control period, in realtime once
        per state period. The law is built for this period."""
        return self.control_period_s if self.lockstep else self.state_period_s

    def replace(self, **changes: Any) -> "RunConfig":
        """A copy with ``changes`` applied."""
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------------ building
    @classmethod
    def from_scenario(cls, scenario: Any, law: str,
                      controller: ControllerSpec | None = None,
                      maneuver: ManeuverSpec | None = None) -> "RunConfig":
        """The run of ``scenario`` with ``law`` (or ``controller``, the user's): what
        :meth:`fourws_run.scenario.Scenario.run_config` builds (a maneuver that depends on the
        law is resolved for it there; ``maneuver``, a member of the scenario's series, runs
        instead of its maneuver)."""
        return scenario.run_config(law, controller, maneuver)

    # ------------------------------------------------------------------ serializing
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (layout in the module docstring)."""
        return {
            "version": RUN_CONFIG_VERSION,
            "vehicle": self.vehicle.to_dict(), "belief_vehicle": self.belief.to_dict(),
            "maneuver": self.maneuver.to_dict(), "law": self.law,
            "law_options": dict(self.law_options), "controller": self.controller.to_dict(),
            "driver": list(self.driver),
            "model": self.model, "tire": self.tire, "integrator": self.integrator,
            "integration_step_s": self.integration_step_s,
            "control_period_s": self.control_period_s,
            "state_period_s": self.state_period_s, "clock_mode": self.clock_mode,
            "controller_period_s": self.controller_period_s, "speed_mps": self.speed_mps,
            "scenario": self.scenario,
            "recorded_topics": list(self.recorded_topics), "versions": dict(self.versions),
            "realtime": self.realtime.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<run config>") -> "RunConfig":
        """Inverse of :meth:`to_dict`; also reads version 1 (older bags).

        Raises
        ------
        ParameterError
            Not a run configuration (names the first bad field).
        """
        if not isinstance(data, Mapping):
            raise ParameterError("run_config", "must be a mapping", source)
        version = data.get("version", 1)
        if version not in (1, RUN_CONFIG_VERSION):
            raise ParameterError("run_config.version", f"unknown layout version {version!r}",
                                 source)
        for key in ("vehicle", "maneuver", "law"):
            if key not in data:
                raise ParameterError(f"run_config.{key}", "missing", source)
        vehicle = vehicle_from_mapping(data["vehicle"], source)
        belief_data = data.get("belief_vehicle")
        if isinstance(belief_data, Mapping):
            belief = vehicle_from_mapping(belief_data, source)
        elif isinstance(belief_data, str) and belief_data and belief_data != vehicle.name:
            belief = load_vehicle(belief_data)  # version 1 twin runs stored a name
        else:
            belief = vehicle
        scenario = data.get("scenario", "")
        if isinstance(scenario, Mapping):  # version 1 stored the whole scenario mapping
            scenario = scenario.get("name", "")
        topics = data.get("recorded_topics", interface.RECORDED_TOPICS)
        return cls(
            vehicle=vehicle, belief=belief,
            maneuver=maneuver_spec_from_mapping(data["maneuver"], source),
            law=str(data["law"]), law_options=dict(data.get("law_options") or {}),
            model=str(data.get("model", "8dof")), tire=data.get("tire"),
            integrator=str(data.get("integrator", "rk4")),
            integration_step_s=float(data.get("integration_step_s", 1e-3)),
            control_period_s=float(data.get("control_period_s", 1e-2)),
            state_period_s=float(data.get("state_period_s", 1e-2)),
            clock_mode=str(data.get("clock_mode", "lockstep")),
            controller=ControllerSpec.from_mapping(data.get("controller"), source),
            driver=tuple(str(a) for a in data.get("driver") or ()),
            scenario=str(scenario), recorded_topics=tuple(topics),
            versions={str(k): str(v) for k, v in dict(data.get("versions") or {}).items()},
            realtime=RealtimeDemand.from_mapping(data.get("realtime"), source))

    @classmethod
    def from_node_configs(cls, parts: list[Mapping[str, Any]],
                          law_label: str = "") -> "RunConfig":
        """Assemble a run description from the nodes' own ``/fourws/node_config`` messages
        (a graph started by hand).

        Parameters
        ----------
        parts : list of mapping
            ``{"node", "role", "config"}`` of the simulator, the maneuver and (if it
            publishes one) the controller; the latest per role wins.
        law_label : str
            The law a user controller names in its commands, used when no controller
            configuration is present.

        Raises
        ------
        ParameterError
            The simulator's or the maneuver's part is missing.
        """
        by_role: dict[str, Mapping[str, Any]] = {}
        names: dict[str, str] = {}
        for part in parts:
            role = str(part.get("role", ""))
            by_role[role] = part.get("config", {})
            names[role] = str(part.get("node", ""))
        for role in (interface.Role.SIMULATOR.value, interface.Role.MANEUVER.value):
            if role not in by_role:
                raise ParameterError("node_config", f"no configuration of the {role} node")
        sim = by_role[interface.Role.SIMULATOR.value]
        man = by_role[interface.Role.MANEUVER.value]
        ctrl = by_role.get(interface.Role.CONTROLLER.value)
        vehicle = vehicle_from_mapping(sim["vehicle"], "node_config (simulator)")
        belief = (vehicle_from_mapping(ctrl["belief_vehicle"], "node_config (controller)")
                  if ctrl else vehicle)
        law = str(ctrl["law"]) if ctrl else (law_label or USER_LAW)
        ctrl_name = names.get(interface.Role.CONTROLLER.value,
                              interface.NODE_NAMES[interface.Role.CONTROLLER])
        return cls(
            vehicle=vehicle, belief=belief,
            maneuver=maneuver_spec_from_mapping(man["maneuver"], "node_config (maneuver)"),
            law=law, law_options=dict(ctrl.get("law_options", {})) if ctrl else {},
            model=str(sim["model"]), tire=sim.get("tire") or None,
            integrator=str(sim["integrator"]),
            integration_step_s=float(sim["integration_step_s"]),
            control_period_s=float(sim["control_period_s"]),
            state_period_s=float(sim["state_period_s"]), clock_mode=str(sim["clock_mode"]),
            controller=ControllerSpec((), ctrl_name) if ctrl else ControllerSpec(
                ("(started by hand)",), ctrl_name),
            scenario="", versions=software_versions())


def software_versions() -> dict[str, str]:
    """Versions of the software a run uses (Python, fourws, the ROS client, numpy, rosbags)."""
    versions: dict[str, str] = {"python": platform.python_version()}
    for dist in ("fourws", "rosbags", "numpy", "ros-rclpy"):
        try:
            versions[dist] = version(dist)
        except PackageNotFoundError:
            versions[dist] = "unknown"
    return versions


__all__ = ["ControllerSpec", "INPUT_DRIVERS", "RUN_CONFIG_VERSION", "RealtimeDemand", "RunConfig",
           "USER_LAW",
           "check_node_name",
           "software_versions"]
