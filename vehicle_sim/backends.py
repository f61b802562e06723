"""Physics backends by name: the built-in rigid body ("builtin") or JSBSim's F450 ("jsbsim")."""

from __future__ import annotations

from vehicle_sim.builtin_plant import BuiltinPlant, PlantBackend
from vehicle_sim.config import BACKEND_NAMES, SimConfig

__all__ = ["BACKEND_NAMES", "backend_name", "make_backend"]


def backend_name(backend: PlantBackend | str | None, config: SimConfig) -> str:
    """The name ``make_backend`` resolves ``backend`` to: the name given, the config's
    ``backend`` for None, or the class name of a backend object."""
    if backend is None:
        return config.backend
    return backend if isinstance(backend, str) else type(backend).__name__


def make_backend(backend: PlantBackend | str | None, config: SimConfig) -> PlantBackend:
    """The backend called ``backend`` for ``config`` (None: the config's ``backend``, by
    default built-in); an object is used as is.

    Raises:
        ValueError: an unknown name (the message lists the valid ones).
        SimConfigError: a config the backend cannot fly (e.g. effects on "jsbsim").
    """
    if backend is not None and not isinstance(backend, str):
        return backend
    name = backend_name(backend, config)
    if name == "builtin":
        return BuiltinPlant(config)
    if name == "jsbsim":
        from vehicle_sim.jsbsim_backend import JsbsimBackend  # loads JSBSim only when asked for

        return JsbsimBackend(config)
    raise ValueError(f"unknown backend {name!r}; choose one of {', '.join(BACKEND_NAMES)}")
