"""wind: a steady wind in NED [m/s].

It has no force of its own: it changes the air-relative velocity v_air = v - wind - gust that
rotor_drag and body_drag act on, so it needs one of them enabled (the config checks that).
Default 3 m/s from the south (blowing north), a light breeze.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import ParamSpec, validate_effect


@dataclass(frozen=True)
class Wind:
    """Steady wind velocity ``vel_ned_mps`` (the air's velocity over ground, NED, m/s)."""

    name: ClassVar[str] = "wind"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("vel_ned_mps", "m/s", 3, -40.0, 40.0, "air velocity over ground, NED"),
    )
    vel_ned_mps: tuple[float, float, float] = (3.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.WIND_NED : layout.WIND_NED + 3] = self.vel_ned_mps
