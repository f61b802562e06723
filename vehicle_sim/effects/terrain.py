"""What a rover's terrain effect does at one place and motion: :class:`TerrainEffect`.

Every rover effect (slope, wheel_slip, surface_patch, rover_payload) answers
``terrain(x_m, y_m, heading_rad, speed_mps, yaw_rate_radps)`` with one, and the rover simulator
combines them (products of scales, sums of drifts). Path-dependent terrain after [Ostafew16]
section 5: slopes, side slopes, gravel, sand, loose dirt.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

BIG_M = 1.0e4  # bound of world coordinates [m]


@dataclass(frozen=True)
class TerrainEffect:
    """What the terrain does to the robot at one place and motion (all neutral by default).

    Attributes:
        speed_scale: achieved ground speed / wheel speed [1].
        yaw_scale: achieved yaw rate / wheel (differential) yaw rate [1].
        lat_drift_mps: sideways ground velocity, positive to the robot's left [m/s].
    """

    speed_scale: float = 1.0
    yaw_scale: float = 1.0
    lat_drift_mps: float = 0.0

    def combine(self, other: TerrainEffect) -> TerrainEffect:
        return TerrainEffect(
            self.speed_scale * other.speed_scale,
            self.yaw_scale * other.yaw_scale,
            self.lat_drift_mps + other.lat_drift_mps,
        )


NEUTRAL = TerrainEffect()


def inside(centre: tuple[float, ...], radius_m: float, x_m: float, y_m: float) -> bool:
    """Whether (x_m, y_m) lies in the disc of ``radius_m`` [m] around ``centre`` [m]."""
    return math.hypot(x_m - centre[0], y_m - centre[1]) <= radius_m
