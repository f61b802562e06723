"""wind_field: a spatially varying wind, a jet of air across the mission world.

The air velocity over ground at horizontal position p is

    w(p) = vel_ned_mps * exp(-(d(p) / half_width_m)^2)        [m/s, NED]

where d(p) is the horizontal distance [m] from the field's centre line, the line through
(center_n_m, center_e_m) with direction heading_rad (0 = north, pi/2 = east). It models the
wind funnelled between two buildings (a street canyon) or the shear layer at the edge of a
building's wake: a vehicle flying a path across the line meets a wind that rises and falls with
its position, the same on every pass: [Ostafew16]'s path-dependent disturbance. Like ``wind``
it adds to the air-relative velocity that rotor_drag and body_drag act on (it needs one of
them), on top of the steady ``wind`` and the ``gusts``. Default: a 4 m/s jet blowing east
along the line north = 10 m (heading pi/2), 3 m half-width.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, validate_effect


@dataclass(frozen=True)
class WindField(Effect):
    """A jet of wind ``vel_ned_mps`` [m/s] centred on a horizontal line (see module doc)."""

    name: ClassVar[str] = "wind_field"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("vel_ned_mps", "m/s", 3, -40.0, 40.0, "peak air velocity over ground, NED"),
        ParamSpec("center_n_m", "m", 1, -1e4, 1e4, "north of a point on the centre line"),
        ParamSpec("center_e_m", "m", 1, -1e4, 1e4, "east of a point on the centre line"),
        ParamSpec("heading_rad", "rad", 1, -math.pi, math.pi, "centre line direction (0 north)"),
        ParamSpec("half_width_m", "m", 1, 0.1, 1e3, "1/e half-width across the line"),
    )
    ROLE: ClassVar[str] = "disturbance"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust", "crossing_headings")
    EXCITE: ClassVar[str] = "fly repeated passes across the centre line at one speed"
    ACTS_THROUGH: ClassVar[tuple[str, ...]] = ("rotor_drag", "body_drag", "isotropic_drag")
    vel_ned_mps: tuple[float, float, float] = (0.0, 4.0, 0.0)
    center_n_m: float = 10.0
    center_e_m: float = 0.0
    heading_rad: float = math.pi / 2
    half_width_m: float = 3.0

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.FIELD_VEL_NED : layout.FIELD_VEL_NED + 3] = self.vel_ned_mps
        ep[layout.FIELD_CENTER_NE] = self.center_n_m
        ep[layout.FIELD_CENTER_NE + 1] = self.center_e_m
        ep[layout.FIELD_HEADING] = self.heading_rad
        ep[layout.FIELD_HALF_WIDTH] = self.half_width_m

    def air_velocity_ned(self, pos_ned_m: np.ndarray) -> np.ndarray:
        h = self.heading_rad
        d = -(pos_ned_m[:, 0] - self.center_n_m) * math.sin(h) + (
            pos_ned_m[:, 1] - self.center_e_m
        ) * math.cos(h)
        weight = np.exp(-(d / self.half_width_m) * (d / self.half_width_m))
        return weight[:, None] * np.asarray(self.vel_ned_mps)
