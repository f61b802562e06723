"""Path-dependent terrain effects on a ground robot ([Ostafew16] section 5: slopes, side
slopes, gravel, sand, loose dirt), in the style of vehicle_sim/effects: frozen dataclasses with
one :class:`ParamSpec` per field (unit, default, range), validated on construction.

Every effect answers ``terrain(x_m, y_m, heading_rad, speed_mps, yaw_rate_radps)`` with a
:class:`TerrainEffect`, and the simulator combines them (products of scales, sums of drifts):

    effect         parameter                unit        default        range
    slope          centre_m                 m           (10, 0)        -1e4..1e4 (x, y)
                   radius_m                 m           3              0.1..1000
                   grade                    1           (0.2, 0.2)     -0.6..0.6 (dz/dx, dz/dy)
                   uphill_loss_per_grade    1           0.5            0..2
                   side_drift_mps_per_grade m/s         0.6            0..3
    wheel_slip     yaw_loss_per_mps         s/m         0.15           0..0.8
                   yaw_loss_per_curv_m      m           0.2            0..0.8
                   lat_slip_s               s           0.1            0..1
    surface_patch  centre_m                 m           (5, 0)         -1e4..1e4 (x, y)
                   radius_m                 m           2              0.1..1000
                   traction                 1           0.7            0.2..1
                   yaw_efficiency           1           0.6            0.2..1
                   lat_drift_mps            m/s         0.0            -0.5..0.5
    rover_payload  mass_ratio               1           1.3            0.5..2

Named stand-ins for the paper's surfaces: :func:`mud_patch` and :func:`gravel_patch`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from vehicle_sim.effects.base import ParamSpec, SimConfigError, effect_from_mapping, validate_effect

_BIG = 1.0e4


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


def _inside(centre: tuple[float, ...], radius_m: float, x_m: float, y_m: float) -> bool:
    return math.hypot(x_m - centre[0], y_m - centre[1]) <= radius_m


@dataclass(frozen=True)
class Slope:
    """A tilted disc of ground: climbing loses speed, a side slope pushes the robot downhill.

    With heading unit vector h and left unit vector l, the grade along the path is
    p = grade . h and across it r = grade . l; speed scales by 1 - uphill_loss_per_grade * max(p,0)
    and the robot drifts sideways (downhill, towards -r) at side_drift_mps_per_grade * r.
    """

    name: ClassVar[str] = "slope"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("centre_m", "m", 2, -_BIG, _BIG, "disc centre (x, y) in the world frame"),
        ParamSpec("radius_m", "m", 1, 0.1, 1000.0, "disc radius"),
        ParamSpec("grade", "1", 2, -0.6, 0.6, "ground gradient (dz/dx, dz/dy)"),
        ParamSpec("uphill_loss_per_grade", "1", 1, 0.0, 2.0, "speed lost per unit uphill grade"),
        ParamSpec(
            "side_drift_mps_per_grade", "m/s", 1, 0.0, 3.0, "downhill drift per unit side grade"
        ),
    )
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
        if not _inside(self.centre_m, self.radius_m, x_m, y_m):
            return NEUTRAL
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        along = self.grade[0] * c + self.grade[1] * s
        across = -self.grade[0] * s + self.grade[1] * c
        return TerrainEffect(
            speed_scale=max(0.1, 1.0 - self.uphill_loss_per_grade * max(along, 0.0)),
            lat_drift_mps=-self.side_drift_mps_per_grade * across * min(1.0, abs(speed_mps) * 4),
        )


@dataclass(frozen=True)
class WheelSlip:
    """Skid-steer turning slip growing with speed and curvature, plus centrifugal side slip.

    yaw_scale = 1 - min(0.9, yaw_loss_per_mps |v| + yaw_loss_per_curv_m |omega / v|);
    lateral drift = -lat_slip_s * v * omega (outwards of the turn).
    """

    name: ClassVar[str] = "wheel_slip"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("yaw_loss_per_mps", "s/m", 1, 0.0, 0.8, "yaw efficiency lost per m/s"),
        ParamSpec("yaw_loss_per_curv_m", "m", 1, 0.0, 0.8, "yaw efficiency lost per 1/m"),
        ParamSpec("lat_slip_s", "s", 1, 0.0, 1.0, "side-slip velocity per (v * omega)"),
    )
    yaw_loss_per_mps: float = 0.15
    yaw_loss_per_curv_m: float = 0.2
    lat_slip_s: float = 0.1

    def __post_init__(self) -> None:
        validate_effect(self)

    def terrain(
        self, x_m: float, y_m: float, heading_rad: float, speed_mps: float, yaw_rate_radps: float
    ) -> TerrainEffect:
        v = abs(speed_mps)
        curv = abs(yaw_rate_radps) / max(v, 0.1)
        loss = min(0.9, self.yaw_loss_per_mps * v + self.yaw_loss_per_curv_m * min(curv, 2.0))
        return TerrainEffect(
            yaw_scale=1.0 - loss, lat_drift_mps=-self.lat_slip_s * speed_mps * yaw_rate_radps
        )


@dataclass(frozen=True)
class SurfacePatch:
    """A disc of loose ground (mud, gravel, sand) placed in the world.

    Inside it the ground speed is ``traction`` times the wheel speed, the yaw rate
    ``yaw_efficiency`` times the differential yaw rate, and ruts push sideways at
    ``lat_drift_mps`` (world-fixed direction: to the robot's left while it drives at heading 0,
    i.e. along +y in the world).
    """

    name: ClassVar[str] = "surface_patch"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("centre_m", "m", 2, -_BIG, _BIG, "patch centre (x, y) in the world frame"),
        ParamSpec("radius_m", "m", 1, 0.1, 1000.0, "patch radius"),
        ParamSpec("traction", "1", 1, 0.2, 1.0, "ground speed / wheel speed on the patch"),
        ParamSpec("yaw_efficiency", "1", 1, 0.2, 1.0, "yaw rate / commanded wheel yaw rate"),
        ParamSpec("lat_drift_mps", "m/s", 1, -0.5, 0.5, "sideways drift along world +y"),
    )
    centre_m: tuple[float, float] = (5.0, 0.0)
    radius_m: float = 2.0
    traction: float = 0.7
    yaw_efficiency: float = 0.6
    lat_drift_mps: float = 0.0

    def __post_init__(self) -> None:
        validate_effect(self)

    def terrain(
        self, x_m: float, y_m: float, heading_rad: float, speed_mps: float, yaw_rate_radps: float
    ) -> TerrainEffect:
        if not _inside(self.centre_m, self.radius_m, x_m, y_m):
            return NEUTRAL
        # world +y drift expressed in the body frame's left axis
        moving = min(1.0, abs(speed_mps) * 4)
        return TerrainEffect(
            speed_scale=self.traction,
            yaw_scale=self.yaw_efficiency,
            lat_drift_mps=self.lat_drift_mps * math.cos(heading_rad) * moving,
        )


@dataclass(frozen=True)
class RoverPayload:
    """Extra mass: drive and yaw lags grow and acceleration limits shrink by ``mass_ratio``."""

    name: ClassVar[str] = "rover_payload"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("mass_ratio", "ratio", 1, 0.5, 2.0, "true mass / nominal mass"),
    )
    mass_ratio: float = 1.3

    def __post_init__(self) -> None:
        validate_effect(self)

    def terrain(
        self, x_m: float, y_m: float, heading_rad: float, speed_mps: float, yaw_rate_radps: float
    ) -> TerrainEffect:
        return NEUTRAL


def mud_patch(centre_m: tuple[float, float], radius_m: float = 2.0) -> SurfacePatch:
    """Mud: much less traction and turning authority, slight rut drift."""
    return SurfacePatch(centre_m, radius_m, traction=0.6, yaw_efficiency=0.5, lat_drift_mps=0.05)


def gravel_patch(centre_m: tuple[float, float], radius_m: float = 2.0) -> SurfacePatch:
    """Loose gravel: a little less traction, noticeably less turning authority."""
    return SurfacePatch(centre_m, radius_m, traction=0.9, yaw_efficiency=0.7, lat_drift_mps=0.0)


ROVER_EFFECTS: dict[str, type] = {c.name: c for c in (Slope, WheelSlip, SurfacePatch, RoverPayload)}
ROVER_EFFECT_NAMES: tuple[str, ...] = tuple(ROVER_EFFECTS)


def make_rover_effect(name: str, values: Mapping[str, Any] | None = None) -> Any:
    """A rover effect from its name and a config mapping (same validation as construction)."""
    if name not in ROVER_EFFECTS:
        raise SimConfigError(
            f"effects.{name}: unknown rover effect; choose one of {', '.join(ROVER_EFFECT_NAMES)}"
        )
    return effect_from_mapping(ROVER_EFFECTS[name], values or {})
