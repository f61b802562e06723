"""payload: the vehicle is heavier (or lighter) than its preset says.

The true mass is ``mass_ratio`` times the preset's nominal mass; the payload sits at the centre
of gravity, so the inertia is unchanged. The flight controller still believes the nominal hover
thrust and its velocity integrator makes up the difference, so hover thrust grows by the ratio.
Default 1.2 (a 300 g camera on a 1.5 kg quad).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class Payload(Effect):
    """True mass / nominal mass, ``mass_ratio`` (dimensionless)."""

    name: ClassVar[str] = "payload"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "mass_ratio",
            "ratio",
            1,
            0.5,
            1.8,
            "true mass / nominal mass",
            Search(0.5, 1.8, 1.0),
            typical=(1.1, 1.5),
        ),
    )
    ROLE: ClassVar[str] = "force"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust",)
    EXCITE: ClassVar[str] = "hover and fly vertical steps (climb and descend at 1-2 m/s)"
    mass_ratio: float = 1.2

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.PAYLOAD_RATIO] = self.mass_ratio

    def mass_ratio_of(self) -> float:
        return self.mass_ratio
