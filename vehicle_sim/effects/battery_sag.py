"""battery_sag: thrust falls as the battery discharges.

The discharge fraction d in [0, 1] grows with the rotor thrust actually produced:

    dd/dt = (nominal rotor thrust / nominal weight) / full_flight_time_s

so it empties after ``full_flight_time_s`` of hovering. The rotors then give the fraction
(1 - max_thrust_loss * d) of their nominal thrust, and the reported battery voltage falls
linearly from the preset's full to empty voltage. Without this effect the battery is ideal:
full voltage, no thrust loss. Defaults: 15 min hover endurance, 20 % thrust loss when empty
(a LiPo from 4.2 to 3.5 V per cell at fixed throttle).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class BatterySag(Effect):
    """``full_flight_time_s`` (hover endurance, s) and ``max_thrust_loss`` (fraction when empty)."""

    name: ClassVar[str] = "battery_sag"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "full_flight_time_s", "s", 1, 10.0, 36000.0, "hover time from full to empty",
            typical=(300.0, 900.0),
        ),
        ParamSpec(
            "max_thrust_loss", "fraction", 1, 0.0, 0.6, "fraction of thrust lost when empty",
            Search(0.0, 0.6, start=0.1), typical=(0.15, 0.35),
        ),
    )  # fmt: skip
    ROLE: ClassVar[str] = "force"
    NEEDS: ClassVar[tuple[str, ...]] = ("thrust", "voltage_drop")
    EXCITE: ClassVar[str] = "log battery voltage over a long flight (several minutes of hover)"
    full_flight_time_s: float = 900.0
    max_thrust_loss: float = 0.2

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.BATTERY_TIME] = self.full_flight_time_s
        ep[layout.BATTERY_LOSS] = self.max_thrust_loss

    def thrust_factor(self, alt_m: np.ndarray, discharge: np.ndarray) -> np.ndarray:
        return 1.0 - self.max_thrust_loss * discharge
