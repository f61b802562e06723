"""Ground robots for [Ostafew16]'s experiments: presets, drive dynamics, terrain effects, control.

In-process API::

    from vehicle_sim.rover import RoverSim, rover_preset, SurfacePatch
    sim = RoverSim(rover_preset("husky_50kg"), effects=(SurfacePatch(centre_m=(5, 0)),), seed=0)
    sim.set_setpoint(speed_mps=0.4, yaw_rate_radps=0.1)
    sim.step(0.1); print(sim.state)
"""

from vehicle_sim.effects import (
    ROVER_EFFECT_NAMES,
    RoverPayload,
    Slope,
    SurfacePatch,
    WheelSlip,
    make_rover_effect,
)
from vehicle_sim.rover.presets import PRESETS, RoverPreset, rover_preset
from vehicle_sim.rover.simulator import RoverSim, RoverState

__all__ = [
    "PRESETS",
    "ROVER_EFFECT_NAMES",
    "RoverPayload",
    "RoverPreset",
    "RoverSim",
    "RoverState",
    "Slope",
    "SurfacePatch",
    "WheelSlip",
    "make_rover_effect",
    "rover_preset",
]
