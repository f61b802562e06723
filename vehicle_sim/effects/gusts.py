"""gusts: Dryden-type turbulence added to the wind, seeded.

Each NED axis is the first-order (longitudinal) Dryden form, discretised exactly:

    g[k+1] = a g[k] + sigma sqrt(1 - a^2) w[k],   a = exp(-dt V / L),  w ~ N(0, 1)

with V = max(air speed, 1 m/s). The process is zero-mean with standard deviation
``intensity_mps`` per axis whatever the step; ``length_scale_m`` sets how fast it varies.
It starts from its stationary distribution. The white noise comes from the simulator's own
seeded generator, so the same seed gives the same gusts. Like wind it acts through the drag
terms. Defaults: light turbulence at a few metres height (MIL-F-8785C low altitude:
sigma about 1 m/s, L about 20 m).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, validate_effect


@dataclass(frozen=True)
class Gusts(Effect):
    """Dryden turbulence: ``intensity_mps`` (std per axis), ``length_scale_m``."""

    name: ClassVar[str] = "gusts"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "intensity_mps",
            "m/s",
            1,
            0.0,
            20.0,
            "turbulence std per NED axis",
            typical=(1.0, 2.5),
        ),
        ParamSpec("length_scale_m", "m", 1, 0.5, 2000.0, "Dryden turbulence length scale"),
    )
    ROLE: ClassVar[str] = "disturbance"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust", "speed_span")
    EXCITE: ClassVar[str] = "hover and fly slow legs for minutes in the disturbed air"
    ACTS_THROUGH: ClassVar[tuple[str, ...]] = ("rotor_drag", "body_drag", "isotropic_drag")
    intensity_mps: float = 1.0
    length_scale_m: float = 20.0

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.GUST_SIGMA] = self.intensity_mps
        ep[layout.GUST_LENGTH] = self.length_scale_m
