"""surface_patch: a disc of loose ground (mud, gravel, sand) in the rover's world.

Named stand-ins for [Ostafew16]'s surfaces: :func:`mud_patch` and :func:`gravel_patch`.
The ruts' sideways push is a slip angle, like a slope's (vehicle_sim.effects.slope): the ground
deflects the wheels by a distance per metre driven, so the sideways speed scales with the
robot's speed and the crab that holds the line does not depend on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from vehicle_sim.effects.base import Effect, ParamSpec, validate_effect
from vehicle_sim.effects.terrain import BIG_M, NEUTRAL, TerrainEffect, inside


@dataclass(frozen=True)
class SurfacePatch(Effect):
    """A disc of loose ground (mud, gravel, sand) placed in the world.

    Inside it the ground speed is ``traction`` times the wheel speed, the yaw rate
    ``yaw_efficiency`` times the differential yaw rate, and ruts push sideways by ``lat_slip``
    metres per metre driven (world-fixed direction: to the robot's left while it drives at
    heading 0, i.e. along +y in the world): a sideways speed of |v| lat_slip cos(heading).
    """

    name: ClassVar[str] = "surface_patch"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("centre_m", "m", 2, -BIG_M, BIG_M, "patch centre (x, y) in the world frame"),
        ParamSpec("radius_m", "m", 1, 0.1, 1000.0, "patch radius"),
        ParamSpec("traction", "1", 1, 0.2, 1.0, "ground speed / wheel speed on the patch"),
        ParamSpec("yaw_efficiency", "1", 1, 0.2, 1.0, "yaw rate / commanded wheel yaw rate"),
        ParamSpec("lat_slip", "1", 1, -0.5, 0.5, "sideways slip along world +y per m driven"),
    )
    VEHICLE: ClassVar[str] = "rover"
    ROLE: ClassVar[str] = "terrain"
    NEEDS: ClassVar[tuple[str, ...]] = ("drive_over",)
    EXCITE: ClassVar[str] = "drive across the patch in several headings and speeds"
    centre_m: tuple[float, float] = (5.0, 0.0)
    radius_m: float = 2.0
    traction: float = 0.7
    yaw_efficiency: float = 0.6
    lat_slip: float = 0.0

    def __post_init__(self) -> None:
        validate_effect(self)

    def terrain(
        self, x_m: float, y_m: float, heading_rad: float, speed_mps: float, yaw_rate_radps: float
    ) -> TerrainEffect:
        if not inside(self.centre_m, self.radius_m, x_m, y_m):
            return NEUTRAL
        # world +y slip expressed in the body frame's left axis
        return TerrainEffect(
            speed_scale=self.traction,
            yaw_scale=self.yaw_efficiency,
            lat_drift_mps=self.lat_slip * math.cos(heading_rad) * abs(speed_mps),
        )


def mud_patch(centre_m: tuple[float, float], radius_m: float = 2.0) -> SurfacePatch:
    """Mud: much less traction and turning authority, slight rut drift."""
    return SurfacePatch(centre_m, radius_m, traction=0.6, yaw_efficiency=0.5, lat_slip=0.05)


def gravel_patch(centre_m: tuple[float, float], radius_m: float = 2.0) -> SurfacePatch:
    """Loose gravel: a little less traction, noticeably less turning authority."""
    return SurfacePatch(centre_m, radius_m, traction=0.9, yaw_efficiency=0.7, lat_slip=0.0)
