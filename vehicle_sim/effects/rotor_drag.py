"""rotor_drag: force linear in the body-frame air-relative velocity (blade flapping, induced drag).

    F_body = -k * v_air_body        [N], per FRD axis, v_air = v - wind - gust

Default magnitudes: for a 1.5 kg quad with 10-inch rotors, Faessler et al. (2018) report about
0.3-0.5 N/(m/s) in the rotor plane and much less along the thrust axis.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class RotorDrag(Effect):
    """Linear rotor drag; ``k_n_per_mps`` per body axis (forward, right, down) in N/(m/s)."""

    name: ClassVar[str] = "rotor_drag"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "k_n_per_mps", "N/(m/s)", 3, 0.0, 50.0, "linear drag per body axis",
            Search(0.0, 10.0, start=(0.3, 0.3, 0.1), warm=True),
            typical=((0.2, 0.6), (0.2, 0.6), (0.05, 0.2)),
        ),
    )  # fmt: skip
    ROLE: ClassVar[str] = "force"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust", "speed_span")
    EXCITE: ClassVar[str] = "fly speed sweeps from hover to 8 m/s in several headings"
    k_n_per_mps: tuple[float, float, float] = (0.35, 0.35, 0.1)

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.ROTOR_DRAG_K : layout.ROTOR_DRAG_K + 3] = self.k_n_per_mps

    def drag_force_body(self, air_body_mps: np.ndarray) -> np.ndarray:
        return -np.asarray(self.k_n_per_mps) * air_body_mps
