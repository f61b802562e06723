"""The named effects (docs/design.md section 4), one class and one file each, and their one
registry, for the multirotor and the rover alike. Each class owns its parameters (units, valid
ranges, diagnosis search ranges), its physics, what the diagnosis needs to identify it and what
to fly to excite it (see :mod:`.base`; how to add one: README.md in this folder).

Build one from code (``RotorDrag(k_n_per_mps=(0.4, 0.4, 0.1))``) or from a config mapping
(:func:`make_effect`, ``[effects.<name>]`` in TOML), then :func:`pack_effects` them into the
vector the physics reads. Parameters, units and defaults:

    effect         parameter            unit         default           range
    rotor_drag     k_n_per_mps          N/(m/s)      (0.35, 0.35, 0.1) 0..50 per FRD axis
    body_drag      c_n_per_mps2         N/(m/s)^2    (0.02, 0.02, 0.04) 0..10 per FRD axis
    isotropic_drag k_n_per_mps2         N/(m/s)^2    0.03              0..10 (along the airspeed)
    wind           vel_ned_mps          m/s          (3, 0, 0)         -40..40 (needs a drag)
    gusts          intensity_mps        m/s          1.0               0..20 (needs a drag)
                   length_scale_m       m            20.0              0.5..2000
    payload        mass_ratio           1            1.2               0.5..1.8
    battery_sag    full_flight_time_s   s            900               10..36000
                   max_thrust_loss      1            0.2               0..0.6
    ground_effect  max_gain             1            0.25              0..1
                   rotor_radius_m       m            0.127             0.02..1
                   rotor_height_m       m            0.1               0..1
    motor_lag      tau_s                s            0.05              0.005..0.5
    command_delay  delay_s              s            0.1               0..2
    wind_field     see wind_field.py

Rover (terrain) effects, see terrain.py: slope, wheel_slip, surface_patch, rover_payload.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from vehicle_sim.effects.base import Effect, ParamSpec, SimConfigError, effect_from_mapping
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
from vehicle_sim.effects.wheel_slip import WheelSlip
from vehicle_sim.effects.wind import Wind
from vehicle_sim.effects.wind_field import WindField

# The one registry; its order is the order the diagnosis tries and reports causes in.
REGISTRY: dict[str, type[Effect]] = {
    cls.name: cls
    for cls in (
        RotorDrag, BodyDrag, IsotropicDrag, Wind, Gusts, Payload, BatterySag, GroundEffect,
        CommandDelay, MotorLag, WindField, Slope, WheelSlip, SurfacePatch, RoverPayload,
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
    "pack_effects",
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


def pack_effects(effects: Iterable[Effect]) -> np.ndarray:
    """The packed effect vector (shape (layout.N_EFFECT,)) for a set of effects."""
    ep = neutral_effect_vector()
    for effect in effects:
        effect.pack(ep)
    return ep
