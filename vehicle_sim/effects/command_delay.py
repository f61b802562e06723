"""command_delay: setpoints reach the flight controller late.

A velocity setpoint given at time t is acted on from t + ``delay_s`` (link and companion
latency). Proof of life for the offboard failsafe still counts from arrival. The delay is
rounded to whole physics steps. Default 0.1 s (a loaded companion over a telemetry link).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class CommandDelay(Effect):
    """Setpoint latency ``delay_s`` in s."""

    name: ClassVar[str] = "command_delay"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "delay_s",
            "s",
            1,
            0.0,
            2.0,
            "setpoint latency",
            Search(0.0, 1.2, grid=13),
            typical=(0.05, 0.3),
        ),
    )
    ROLE: ClassVar[str] = "command"
    NEEDS: ClassVar[tuple[str, ...]] = ("setpoint_steps",)
    EXCITE: ClassVar[str] = (
        "fly sharp velocity setpoint steps (e.g. 0 -> 3 m/s and back, several headings)"
    )
    delay_s: float = 0.1

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.COMMAND_DELAY] = self.delay_s
