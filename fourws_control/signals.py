"""The signals a law may use, and where each sits in a model's state/input vectors.

A law is ``delta_r = sum_s k_s * signal_s`` (:class:`Signal`). To close a model with it
analytically the signals are found among the model's ``STATE``/``INPUT`` members by name
(models name their components, ``docs/architecture.md``): a linear model (``matrices``), or the
8-DOF, linearized numerically about straight running by :mod:`fourws_analysis.linearize`. A
model whose roll angle is defined opposite to fourws' right-side-down convention declares
``ROLL_SIGN = -1``; the map then flips the roll gains. A model whose front road-wheel angle is
the state of a steering system under another name declares it (``FRONT_ANGLE_STATE``, the
8-DOF with free steering: ``DELTA_S``): the law's front-angle gain sits on that state, as the
free-control laws of the paper take the front angle state (ch. 3.4/4.4).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from types import ModuleType

from fourws_sim.errors import IncompatibleError
from fourws_sim.models import get_model


class Signal(IntEnum):
    """Signals a law may use; the order of :meth:`fourws_control.base.Law.gains`."""

    DELTA_F = 0  #: front road-wheel angle delta_f, rad
    YAW_RATE = 1  #: yaw rate r, rad/s
    ROLL = 2  #: roll angle phi (right side down positive), rad
    ROLL_RATE = 3  #: roll rate, rad/s
    LATERAL_VELOCITY = 4  #: lateral velocity V of the CG in the body frame, m/s


#: Unit of the gain on each signal (rear angle in rad per unit of the signal).
GAIN_UNITS = {
    Signal.DELTA_F: "rad/rad",
    Signal.YAW_RATE: "rad/(rad/s)",
    Signal.ROLL: "rad/rad",
    Signal.ROLL_RATE: "rad/(rad/s)",
    Signal.LATERAL_VELOCITY: "rad/(m/s)",
}

#: Member names a model may use for each signal (first match wins).
_NAMES: dict[Signal, tuple[str, ...]] = {
    Signal.DELTA_F: ("DELTA_F",),
    Signal.YAW_RATE: ("R", "YAW_RATE"),
    Signal.ROLL: ("PHI", "ROLL"),
    Signal.ROLL_RATE: ("PHI_DOT", "P", "ROLL_RATE", "PHIDOT"),
    Signal.LATERAL_VELOCITY: ("V", "LATERAL_VELOCITY"),
}
#: Name of the rear-steer input of every linear model.
REAR_INPUT = "DELTA_R"
#: Linear models a law can be written for.
LINEAR_MODELS = ("2dof", "2dof-free", "2dof-lagged", "3dof")
#: Nonlinear models a law can be written for in the state order of their linearization
#: (:func:`fourws_analysis.linearize.jacobians` about straight running).
LINEARIZED_MODELS = ("8dof", "8dof-free")


@dataclass(frozen=True)
class SignalMap:
    """Positions of the law signals in one model's state and input vectors.

    Attributes
    ----------
    model : str
        Model name.
    state_names, input_names : tuple of str
        ``STATE`` / ``INPUT`` member names in order.
    positions : dict
        ``Signal -> (where, index, sign)``; ``where`` is ``"state"`` or ``"input"``.
    rear_input : int
        Index of the rear-steer input in ``INPUT``.
    """

    model: str
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    positions: dict[Signal, tuple[str, int, float]]
    rear_input: int

    @property
    def available(self) -> frozenset[Signal]:
        """Signals the model has."""
        return frozenset(self.positions)

    @property
    def driver_inputs(self) -> tuple[int, ...]:
        """Indices of the inputs other than the rear steer (the driver's)."""
        return tuple(i for i in range(len(self.input_names)) if i != self.rear_input)


def _find(enum: type, names: tuple[str, ...]) -> int | None:
    members = enum.__members__
    for n in names:
        if n in members:
            return int(members[n])
    return None


def signal_map(model_name: str, module: ModuleType | None = None) -> SignalMap:
    """Build the :class:`SignalMap` of model ``model_name``: a linear model (it has
    ``matrices``) or one of :data:`LINEARIZED_MODELS`.

    Raises
    ------
    UnknownNameError
        Unknown model name.
    IncompatibleError
        The model is neither linear nor linearized for the laws, or has no rear-steer input.
    """
    mod = module if module is not None else get_model(model_name)
    if not hasattr(mod, "matrices") and model_name not in LINEARIZED_MODELS:
        raise IncompatibleError(f"model {model_name!r} is not linear; linear models: "
                                f"{', '.join(LINEAR_MODELS)}; linearized: "
                                f"{', '.join(LINEARIZED_MODELS)}")
    state, inp = mod.STATE, mod.INPUT
    rear = _find(inp, (REAR_INPUT,))
    if rear is None:
        raise IncompatibleError(f"model {model_name!r} has no rear-steer input {REAR_INPUT}")
    roll_sign = float(getattr(mod, "ROLL_SIGN", 1.0))
    positions: dict[Signal, tuple[str, int, float]] = {}
    front_state = getattr(mod, "FRONT_ANGLE_STATE", None)
    if front_state is not None:
        positions[Signal.DELTA_F] = ("state", int(state[front_state]), 1.0)
    for sig, names in _NAMES.items():
        if sig in positions:
            continue
        sign = roll_sign if sig in (Signal.ROLL, Signal.ROLL_RATE) else 1.0
        idx = _find(state, names)
        if idx is not None:
            positions[sig] = ("state", idx, sign)
            continue
        idx = _find(inp, names)
        if idx is not None:
            positions[sig] = ("input", idx, sign)
    return SignalMap(model_name, tuple(state.__members__), tuple(inp.__members__), positions,
                     rear)
