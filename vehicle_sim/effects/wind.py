"""wind: a steady wind in NED [m/s].

It has no force of its own: it changes the air-relative velocity v_air = v - wind - gust that
the drag effects act on, so it needs one of them enabled (the config checks that); without
one in the config the diagnosis fits it together with rotor_drag.
Default 3 m/s from the south (blowing north), a light breeze.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class Wind(Effect):
    """Steady wind velocity ``vel_ned_mps`` (the air's velocity over ground, NED, m/s)."""

    name: ClassVar[str] = "wind"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "vel_ned_mps", "m/s", 3, -40.0, 40.0, "air velocity over ground, NED",
            Search(-30.0, 30.0, start=0.0, free=2),
        ),
    )  # fmt: skip
    ROLE: ClassVar[str] = "force"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust", "crossing_headings")
    EXCITE: ClassVar[str] = (
        "fly out and back along at least two crossing headings at the same speed"
    )
    ACTS_THROUGH: ClassVar[tuple[str, ...]] = ("rotor_drag", "body_drag", "isotropic_drag")
    FIT_WITH: ClassVar[str | None] = "rotor_drag"
    vel_ned_mps: tuple[float, float, float] = (3.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.WIND_NED : layout.WIND_NED + 3] = self.vel_ned_mps

    @classmethod
    def draw_typical(cls, rng: np.random.Generator) -> dict[str, float | list[float]]:
        """A horizontal breeze of 2-6 m/s from a uniformly drawn direction."""
        speed, heading = rng.uniform(2.0, 6.0), rng.uniform(0.0, 2.0 * np.pi)
        return {"vel_ned_mps": [speed * np.cos(heading), speed * np.sin(heading), 0.0]}

    def air_velocity_ned(self, pos_ned_m: np.ndarray) -> np.ndarray:
        return np.broadcast_to(np.asarray(self.vel_ned_mps), pos_ned_m.shape)
