"""ground_effect: more thrust for the same rotor speed close to the ground.

With h the rotor-plane height above ground (altitude + ``rotor_height_m``) and R the rotor
radius, the thrust is multiplied by

    1 + max_gain * (1 - h / (2 R))^2    for h < 2 R,   1 above,

a smooth fit to the Cheeseman-Bennett curve that vanishes at two rotor radii. Defaults for an
Iris-class quad: R = 0.127 m (10-inch rotors), rotors 0.1 m above ground when landed, 25 % more
thrust at the ground.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class GroundEffect(Effect):
    """``max_gain`` (thrust fraction gained at h = 0), ``rotor_radius_m``, ``rotor_height_m``."""

    name: ClassVar[str] = "ground_effect"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "max_gain", "fraction", 1, 0.0, 1.0, "thrust fraction gained at the ground",
            Search(0.0, 1.0, start=0.2), typical=(0.15, 0.4),
        ),
        ParamSpec(
            "rotor_radius_m", "m", 1, 0.02, 1.0, "rotor radius",
            Search(0.03, 0.5, 0.15), typical=(0.11, 0.16),
        ),
        ParamSpec("rotor_height_m", "m", 1, 0.0, 1.0, "rotor plane height when landed"),
    )  # fmt: skip
    ROLE: ClassVar[str] = "force"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust", "near_ground")
    EXCITE: ClassVar[str] = "fly altitude holds at 0.05, 0.1, 0.2 and 0.5 m above flat ground"
    max_gain: float = 0.25
    rotor_radius_m: float = 0.127
    rotor_height_m: float = 0.1

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.GROUND_GAIN] = self.max_gain
        ep[layout.GROUND_RADIUS] = self.rotor_radius_m
        ep[layout.GROUND_HEIGHT] = self.rotor_height_m

    def thrust_factor(self, alt_m: np.ndarray, discharge: np.ndarray) -> np.ndarray:
        h = np.maximum(alt_m, 0.0) + self.rotor_height_m
        s = np.clip(1.0 - h / (2.0 * self.rotor_radius_m), 0.0, None)
        return 1.0 + self.max_gain * s * s
