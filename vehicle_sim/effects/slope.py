"""slope: a tilted disc of ground a rover climbs or crosses ([Ostafew16] section 5).

Side slip is an angle, not a rate: a wheel's lateral force depends on its slip angle
beta = atan(v_lat / v_x) [Ishigami09] (terramechanics), and at the quasi-static speeds of
[Ostafew16] (0.35-1.2 m/s) the downhill pull m g sin(phi) is balanced at a beta set by the
slope and the soil, not by the speed. So the robot slides downhill at v tan(beta), with
tan(beta) = side_slip_per_grade * (side grade): the distance it loses per metre driven does not
depend on how fast it drives, and the crab that holds the line (beta) neither. With a linear
lateral stiffness C = c_n m g (c_n per rad), tan(beta) ~ tan(phi) / c_n, so side_slip_per_grade
is 1 / c_n: 0.3-0.6 is loose soil (c_n 1.7-3 per rad); firm ground is several times stiffer.

[Ishigami09]: G. Ishigami, K. Nagatani, K. Yoshida, "Slope traversal controls for planetary
exploration rover on sandy terrain", J. Field Robotics 26(3), 2009 (cited by [Ostafew16]).
"""

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
    and the robot slides sideways (downhill, towards -r) at |v| * side_slip_per_grade * r, a
    side slip angle atan(side_slip_per_grade * r) whatever the speed (module docstring).
    """

    name: ClassVar[str] = "slope"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("centre_m", "m", 2, -BIG_M, BIG_M, "disc centre (x, y) in the world frame"),
        ParamSpec("radius_m", "m", 1, 0.1, 1000.0, "disc radius"),
        ParamSpec("grade", "1", 2, -0.6, 0.6, "ground gradient (dz/dx, dz/dy)"),
        ParamSpec("uphill_loss_per_grade", "1", 1, 0.0, 2.0, "speed lost per unit uphill grade"),
        ParamSpec(
            "side_slip_per_grade", "1", 1, 0.0, 3.0, "tan(side slip angle) per unit side grade"
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
    side_slip_per_grade: float = 0.6

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
            lat_drift_mps=-self.side_slip_per_grade * across * abs(speed_mps),
        )
