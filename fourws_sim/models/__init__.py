"""Vehicle models: one module per model, looked up by name.

Every model module exposes ``STATE`` and ``INPUT`` (``IntEnum``), ``params_for`` and
``derivatives(t, x, u, p) -> dx/dt``; the linear ones also ``matrices(vehicle, speed_mps)
-> (A, B)`` (see ``docs/architecture.md``). Modules are imported only when asked for, so a
model's heavy dependencies (numba for the 8-DOF) cost nothing to users of the others.

Adding a model is one line in :data:`MODELS` (name -> module path).
"""

from __future__ import annotations

import importlib
import math
from types import ModuleType

from fourws_sim.errors import ParameterError, UnknownNameError

#: Model name -> module path (imported lazily by :func:`get_model`).
MODELS: dict[str, str] = {
    "2dof": "fourws_sim.models.linear2dof",
    "2dof-free": "fourws_sim.models.free2dof",
    "2dof-lagged": "fourws_sim.models.lagged2dof",
    "3dof": "fourws_sim.models.roll3dof",
    "2dof-cubic": "fourws_sim.models.cubic2dof",
    "8dof": "fourws_sim.models.eightdof",
    "8dof-free": "fourws_sim.models.eightdof_free",
}

#: Models whose front angle is a state of a steering system driven by the driver's torque
#: (free steering control): they take torque-input maneuvers, the others angle inputs.
FREE_STEERING_MODELS = ("2dof-free", "8dof-free")


def get_model(name: str) -> ModuleType:
    """Return the module of model ``name``.

    Raises
    ------
    UnknownNameError
        If ``name`` is not a key of :data:`MODELS` (the message lists the valid names).
    """
    try:
        path = MODELS[name]
    except (KeyError, TypeError):
        raise UnknownNameError("model", str(name), list(MODELS)) from None
    return importlib.import_module(path)


def check_speed(speed_mps: float, source: str | None = None) -> float:
    """Validate a forward speed for the models linearized about straight running.

    Parameters
    ----------
    speed_mps : float
        Forward speed U in m/s.
    source : str, optional
        Where the value came from (named in the error message).

    Returns
    -------
    float
        ``speed_mps`` as a float.

    Raises
    ------
    ParameterError
        If the speed is not a finite number > 0 (the models divide by U).
    """
    if isinstance(speed_mps, bool) or not isinstance(speed_mps, (int, float)):
        try:
            speed_mps = float(speed_mps)  # numpy scalars
        except (TypeError, ValueError):
            raise ParameterError("speed_mps", f"must be a number, got {speed_mps!r}",
                                 source) from None
    value = float(speed_mps)
    if not math.isfinite(value):
        raise ParameterError("speed_mps", f"must be finite, got {value!r}", source)
    if value <= 0.0:
        raise ParameterError("speed_mps",
                             f"must be > 0 (the model divides by the forward speed), "
                             f"got {value!r}", source)
    return value
