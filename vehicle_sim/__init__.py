"""vehicle_sim: the simulated PX4-style multirotor that stands in for the flight controller.

In-process API::

    from vehicle_sim import Simulator, load_sim_config
    sim = Simulator(load_sim_config("iris", effects={"rotor_drag": {}}), seed=0)
    sim.arm(); sim.takeoff(); sim.step(5.0)
    sim.set_velocity_setpoint(VelocitySetpoint((2.0, 0.0, 0.0)))
    sim.set_mode(FlightMode.OFFBOARD); sim.step(0.05); row = sim.log_row(None)
    sim.set_mode(FlightMode.POSCTL); sim.set_sticks(Sticks(x=0.5, y=0.0, z=0.5, r=0.0))
    sim.anchor(AnchorState(pos_ned_m=..., vel_ned_mps=..., q_wxyz=...))  # replay from a log
    legs = sim.stream_setpoints(setpoints, durations_s)  # many legs, one compiled call
"""

from vehicle_sim.anchor import AnchorState
from vehicle_sim.commander import CommandResult
from vehicle_sim.config import SimConfig, VehicleSpec, load_sim_config
from vehicle_sim.effects import EFFECT_NAMES, SimConfigError
from vehicle_sim.manual_control import Sticks
from vehicle_sim.simulator import Simulator, StreamedLegs
from vehicle_sim.vehicle_types import (
    CheckedSetpoint,
    FlightMode,
    LandedState,
    VehicleState,
    VelocitySetpoint,
)

__all__ = [
    "EFFECT_NAMES",
    "AnchorState",
    "CheckedSetpoint",
    "CommandResult",
    "FlightMode",
    "LandedState",
    "SimConfig",
    "SimConfigError",
    "Simulator",
    "StreamedLegs",
    "Sticks",
    "VehicleSpec",
    "VehicleState",
    "VelocitySetpoint",
    "load_sim_config",
]
