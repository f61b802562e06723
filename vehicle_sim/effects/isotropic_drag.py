"""isotropic_drag: quadratic drag along the airspeed vector, the same in every direction.

    F = -k * |v_air| * v_air        [N], v_air = v - wind - gust

This is how JSBSim's multirotor models (and a sphere-like airframe) see drag: the force points
against the air-relative velocity, its size grows with the dynamic pressure. Unlike body_drag
(per body axis, -c v_i |v_i|) it couples the axes: at 45 deg between two body axes it is
sqrt(2) times body_drag's value with the same coefficient. k = 0.5 rho C_d A: about 0.01-0.05
N/(m/s)^2 for an F450/Iris-class quad. Identifiable from fast legs in several headings (speed
sweeps); fly missions/excite_speed.toml.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class IsotropicDrag(Effect):
    """Drag along the airspeed; ``k_n_per_mps2`` in N/(m/s)^2."""

    name: ClassVar[str] = "isotropic_drag"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "k_n_per_mps2", "N/(m/s)^2", 1, 0.0, 10.0, "drag along the airspeed",
            Search(0.0, 10.0, start=0.03, warm=True),
            typical=(0.02, 0.08),
        ),
    )  # fmt: skip
    ROLE: ClassVar[str] = "force"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust", "speed_span")
    EXCITE: ClassVar[str] = "fly speed sweeps from hover to 8 m/s in several headings"
    k_n_per_mps2: float = 0.03

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.ISO_DRAG_K] = self.k_n_per_mps2

    def drag_force_body(self, air_body_mps: np.ndarray) -> np.ndarray:
        speed = np.linalg.norm(air_body_mps, axis=1, keepdims=True)
        return -self.k_n_per_mps2 * speed * air_body_mps
