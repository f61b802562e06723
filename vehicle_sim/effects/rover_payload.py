"""rover_payload: a rover heavier than its preset says."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from vehicle_sim.effects.base import Effect, ParamSpec, validate_effect
from vehicle_sim.effects.terrain import NEUTRAL, TerrainEffect


@dataclass(frozen=True)
class RoverPayload(Effect):
    """Extra mass: drive and yaw lags grow and acceleration limits shrink by ``mass_ratio``."""

    name: ClassVar[str] = "rover_payload"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("mass_ratio", "ratio", 1, 0.5, 2.0, "true mass / nominal mass"),
    )
    VEHICLE: ClassVar[str] = "rover"
    ROLE: ClassVar[str] = "terrain"
    NEEDS: ClassVar[tuple[str, ...]] = ("ground_speed_span",)
    EXCITE: ClassVar[str] = "drive speed steps and turn steps (acceleration limits and lags show)"
    mass_ratio: float = 1.3

    def __post_init__(self) -> None:
        validate_effect(self)

    def terrain(
        self, x_m: float, y_m: float, heading_rad: float, speed_mps: float, yaw_rate_radps: float
    ) -> TerrainEffect:
        return NEUTRAL
