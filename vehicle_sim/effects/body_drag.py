"""body_drag: quadratic parasitic drag of the airframe.

    F_body = -c * v_air_body * |v_air_body|        [N], per FRD axis

c = 0.5 * rho * C_d * A: with rho = 1.225 kg/m^3, C_d about 1 and a frontal area of about
0.03 m^2 (top area 0.06 m^2) an Iris-class quad has c of about 0.02 N/(m/s)^2 sideways and
0.04 N/(m/s)^2 vertically.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class BodyDrag(Effect):
    """Quadratic body drag; ``c_n_per_mps2`` per body axis in N/(m/s)^2."""

    name: ClassVar[str] = "body_drag"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "c_n_per_mps2", "N/(m/s)^2", 3, 0.0, 10.0, "quadratic drag per body axis",
            Search(0.0, 5.0, start=(0.02, 0.02, 0.04), warm=True),
            typical=((0.02, 0.08), (0.02, 0.08), (0.03, 0.1)),
        ),
    )  # fmt: skip
    ROLE: ClassVar[str] = "force"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust", "speed_span")
    EXCITE: ClassVar[str] = "fly speed sweeps from hover to 8 m/s in several headings"
    c_n_per_mps2: tuple[float, float, float] = (0.02, 0.02, 0.04)

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.BODY_DRAG_C : layout.BODY_DRAG_C + 3] = self.c_n_per_mps2

    def drag_force_body(self, air_body_mps: np.ndarray) -> np.ndarray:
        return -np.asarray(self.c_n_per_mps2) * air_body_mps * np.abs(air_body_mps)
