"""slope: a tilted disc of ground a rover climbs or crosses ([Ostafew16] section 5)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from vehicle_sim.effects.base import Effect, ParamSpec, validate_effect
from vehicle_sim.effects.terrain import BIG_M, NEUTRAL, TerrainEffect, inside


@dataclass(frozen=True)
class Slope(Effect):
    """A tilted disc of ground: climbing loses speed, a side slope pushes the robot downhill.

    With heading unit vector h and left unit vector l, the grade along the path is
    p = grade . h and across it r = grade . l; speed scales by 1 - uphill_loss_per_grade * max(p,0)
    and the robot drifts sideways (downhill, towards -r) at side_drift_mps_per_grade * r.
    """

    name: ClassVar[str] = "slope"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("centre_m", "m", 2, -BIG_M, BIG_M, "disc centre (x, y) in the world frame"),
        ParamSpec("radius_m", "m", 1, 0.1, 1000.0, "disc radius"),
        ParamSpec("grade", "1", 2, -0.6, 0.6, "ground gradient (dz/dx, dz/dy)"),
        ParamSpec("uphill_loss_per_grade", "1", 1, 0.0, 2.0, "speed lost per unit uphill grade"),
        ParamSpec(
            "side_drift_mps_per_grade", "m/s", 1, 0.0, 3.0, "downhill drift per unit side grade"
        ),
    )
    VEHICLE: ClassVar[str] = "rover"
    ROLE: ClassVar[str] = "terrain"
    NEEDS: ClassVar[tuple[str, ...]] = ("drive_over",)
    EXCITE: ClassVar[str] = "drive over the disc uphill, downhill and across it"
    centre_m: tuple[float, float] = (10.0, 0.0)
    radius_m: float = 3.0
    grade: tuple[float, float] = (0.2, 0.2)
    uphill_loss_per_grade: float = 0.5
    side_drift_mps_per_grade: float = 0.6

    def __post_init__(self) -> None:
        validate_effect(self)

    def terrain(
        self, x_m: float, y_m: float, heading_rad: float, speed_mps: float, yaw_rate_radps: float
    ) -> TerrainEffect:
        if not inside(self.centre_m, self.radius_m, x_m, y_m):
            return NEUTRAL
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        along = self.grade[0] * c + self.grade[1] * s
        across = -self.grade[0] * s + self.grade[1] * c
        return TerrainEffect(
            speed_scale=max(0.1, 1.0 - self.uphill_loss_per_grade * max(along, 0.0)),
            lat_drift_mps=-self.side_drift_mps_per_grade * across * min(1.0, abs(speed_mps) * 4),
        )
