"""motor_lag: the motors are slower than the preset says.

Each rotor speed follows its command with a first-order lag of time constant ``tau_s``, which
replaces the preset's ``motor_time_constant_s``. Default 0.05 s (large props on a tired ESC;
the presets use 0.02-0.03 s).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class MotorLag(Effect):
    """True motor time constant ``tau_s`` in s."""

    name: ClassVar[str] = "motor_lag"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "tau_s", "s", 1, 0.005, 0.5, "first-order motor time constant",
            Search(0.008, 0.5, grid=10, geometric=True),
            typical=(0.03, 0.08),
        ),
    )  # fmt: skip
    ROLE: ClassVar[str] = "command"
    NEEDS: ClassVar[tuple[str, ...]] = ("setpoint_steps",)
    EXCITE: ClassVar[str] = (
        "fly sharp velocity setpoint steps (e.g. 0 -> 3 m/s and back, several headings)"
    )
    tau_s: float = 0.05

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.MOTOR_TAU] = self.tau_s
