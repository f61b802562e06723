"""thrust_curve: the motors change thrust by another amount per command than the preset says.

The flight control turns a thrust command into normalised rotor speeds n_cmd = sqrt(thrust
fraction) (the preset's thrust curve T = T_max n^2). A real ESC, motor and propeller map the
command to thrust along their own curve (PX4 describes it by THR_MDL_FAC; propeller inflow and
motor saturation bend it further). Around hover the difference is a gain: the rotors settle at

    n^2 = n_h^2 + gain * (n_cmd^2 - n_h^2)

with n_h^2 = m_nom g / (4 T_max) the nominal hover fraction, so the hover thrust is unchanged and
every commanded change of thrust (and of the rotors' differential thrust, hence torque) is
scaled by ``gain``. Default 0.87: JSBSim's F450 changes its thrust 13 % less per command than
the f450 preset (`python -m experiments.thrust_mismatch`, BENCHMARKS.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from vehicle_sim.effects import layout
from vehicle_sim.effects.base import Effect, ParamSpec, Search, validate_effect


@dataclass(frozen=True)
class ThrustCurve(Effect):
    """``gain``: true / assumed change of rotor thrust per change of command around hover."""

    name: ClassVar[str] = "thrust_curve"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            "gain", "fraction", 1, 0.3, 2.0, "thrust change per commanded change, true / assumed",
            Search(0.5, 1.6, grid=12),
            typical=(0.75, 0.9),
        ),
    )  # fmt: skip
    ROLE: ClassVar[str] = "command"
    NEEDS: ClassVar[tuple[str, ...]] = ("setpoint_steps",)
    EXCITE: ClassVar[str] = (
        "fly vertical steps (climb and descend at 1-2 m/s) and sharp horizontal accelerations,"
        " so that the thrust swings well above and below hover"
    )
    gain: float = 0.87

    def __post_init__(self) -> None:
        validate_effect(self)

    def pack(self, ep: np.ndarray) -> None:
        ep[layout.THRUST_CURVE_GAIN] = self.gain
