"""ground_effect: more thrust for the same rotor speed close to the ground.

With h the rotor-plane height above ground (altitude + ``rotor_height_m``) and R the rotor
radius, the thrust is multiplied by

    1 + max_gain * (1 - h / (2 R))^2    for h < 2 R,   1 above,

a bounded stand-in for the Cheeseman-Bennett curve 1 / (1 - (R / 4h)^2) [Cheeseman55]: with
max_gain 0.25 the two agree at h = R (6.3 % against 6.7 %), the law stays finite near the ground
where theirs diverges, and it vanishes at two rotor radii (theirs leaves 1.6 % there). Defaults for
an Iris-class quad: R = 0.127 m (10-inch rotors), rotors 0.1 m above ground when landed, 25 %
more thrust with the rotor plane on the ground.

What a flight constrains: the rotor plane never comes lower than ``rotor_height_m``, so
``max_gain`` is the curve extrapolated from the heights flown, and ``max_gain`` and
``rotor_radius_m`` trade off unless several heights between about R and 2R are held
(``missions/excite_full.toml`` ends with a staircase of 2 s holds for that: its longer holds
before are flown at 8-9 cm whatever is commanded).
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
    EXCITE: ClassVar[str] = (
        "fly a staircase of 2 s altitude holds from 0.2 m down to 3 cm and back up over flat"
        " ground (several heights within two rotor radii, each seen more than once)"
    )
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
