"""The named effects (docs/design.md section 4), one class and one file each, and their one
registry, for the multirotor and the rover alike. Each class owns its parameters (units, valid
ranges, diagnosis search ranges), its physics, what the diagnosis needs to identify it and what
to fly to excite it (see :mod:`.base`; how to add one: README.md in this folder).

Build one from code (``RotorDrag(k_n_per_mps=(0.4, 0.4, 0.1))``) or from a config mapping
(:func:`make_effect`, ``[effects.<name>]`` in TOML), then :func:`pack_effects` them into the
vector the physics reads. Parameters, units, defaults, valid and search ranges come from the
classes alone; :func:`parameter_table` lists them
(``python -c "from vehicle_sim.effects import parameter_table; print(parameter_table())"``).
Multirotor effects: rotor_drag, body_drag, isotropic_drag, wind, gusts, payload, battery_sag,
ground_effect, command_delay, motor_lag, thrust_curve, wind_field. Rover (terrain) effects, see
terrain.py: slope, wheel_slip, surface_patch, rover_payload.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from vehicle_sim.effects.base import (
    Effect,
    ParamSpec,
    SimConfigError,
    effect_as_mapping,
    effect_from_mapping,
)
from vehicle_sim.effects.battery_sag import BatterySag
from vehicle_sim.effects.body_drag import BodyDrag
from vehicle_sim.effects.command_delay import CommandDelay
from vehicle_sim.effects.ground_effect import GroundEffect
from vehicle_sim.effects.gusts import Gusts
from vehicle_sim.effects.isotropic_drag import IsotropicDrag
from vehicle_sim.effects.layout import neutral_effect_vector
from vehicle_sim.effects.motor_lag import MotorLag
from vehicle_sim.effects.payload import Payload
from vehicle_sim.effects.rotor_drag import RotorDrag
from vehicle_sim.effects.rover_payload import RoverPayload
from vehicle_sim.effects.slope import Slope
from vehicle_sim.effects.surface_patch import SurfacePatch, gravel_patch, mud_patch
from vehicle_sim.effects.thrust_curve import ThrustCurve
from vehicle_sim.effects.wheel_slip import WheelSlip
from vehicle_sim.effects.wind import Wind
from vehicle_sim.effects.wind_field import WindField

# The one registry; its order is the order the diagnosis tries and reports causes in.
REGISTRY: dict[str, type[Effect]] = {
    cls.name: cls
    for cls in (
        RotorDrag, BodyDrag, IsotropicDrag, Wind, Gusts, Payload, BatterySag, GroundEffect,
        CommandDelay, MotorLag, ThrustCurve, WindField, Slope, WheelSlip, SurfacePatch,
        RoverPayload,
    )
}  # fmt: skip
EFFECT_CLASSES: dict[str, type[Effect]] = {
    n: c for n, c in REGISTRY.items() if c.VEHICLE == "multirotor"
}
EFFECT_NAMES: tuple[str, ...] = tuple(EFFECT_CLASSES)
ROVER_EFFECTS: dict[str, type[Effect]] = {n: c for n, c in REGISTRY.items() if c.VEHICLE == "rover"}
ROVER_EFFECT_NAMES: tuple[str, ...] = tuple(ROVER_EFFECTS)

__all__ = [
    "EFFECT_CLASSES", "EFFECT_NAMES", "REGISTRY", "ROVER_EFFECTS", "ROVER_EFFECT_NAMES",
    "BatterySag", "BodyDrag", "CommandDelay", "Effect", "GroundEffect", "Gusts",
    "IsotropicDrag", "MotorLag", "ParamSpec", "Payload", "RotorDrag", "RoverPayload",
    "SimConfigError", "Slope", "SurfacePatch", "WheelSlip", "Wind", "WindField",
    "effects_with_role", "gravel_patch", "make_effect", "make_rover_effect", "mud_patch",
    "pack_effects", "parameter_table",
]  # fmt: skip


def effects_with_role(role: str) -> tuple[str, ...]:
    """Names of the registered effects with ``ROLE`` ``role``, in registry order."""
    return tuple(n for n, c in REGISTRY.items() if role == c.ROLE)


def make_effect(name: str, values: Mapping[str, Any] | None = None) -> Effect:
    """The multirotor effect called ``name`` with ``values`` (missing parameters take their
    defaults)."""
    return _make(EFFECT_CLASSES, "effect", name, values)


def make_rover_effect(name: str, values: Mapping[str, Any] | None = None) -> Effect:
    """A rover effect from its name and a config mapping (same validation as construction)."""
    return _make(ROVER_EFFECTS, "rover effect", name, values)


def _make(
    classes: Mapping[str, type[Effect]], what: str, name: str, values: Mapping[str, Any] | None
) -> Effect:
    cls = classes.get(name)
    if cls is None:
        raise SimConfigError(f"effects.{name}: unknown {what}; choose from {', '.join(classes)}")
    if values is not None and not isinstance(values, Mapping):
        raise SimConfigError(
            f"effects.{name}: expected a table of parameters, got {values!r}; "
            f"write [effects.{name}] with its parameters (or {{}} for the defaults)"
        )
    return effect_from_mapping(cls, values or {})


def parameter_table() -> str:
    """Every registered effect's parameters as a text table: effect, parameter, unit, default,
    valid range and the diagnosis' search range ("-" where not searched)."""
    rows = [("effect", "parameter", "unit", "default", "range", "search")]
    for name, cls in REGISTRY.items():
        default = effect_as_mapping(cls())
        for spec in cls.PARAMS:
            s = spec.search
            rows.append(
                (
                    name,
                    spec.name,
                    spec.unit,
                    f"{default[spec.name]}",
                    f"{spec.lo:g}..{spec.hi:g}",
                    "-" if s is None else f"{s.lo:g}..{s.hi:g}",
                )
            )
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    return "\n".join(
        "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in rows
    )


def pack_effects(effects: Iterable[Effect]) -> np.ndarray:
    """The packed effect vector (shape (layout.N_EFFECT,)) for a set of effects."""
    ep = neutral_effect_vector()
    for effect in effects:
        effect.pack(ep)
    return ep
