"""Shared helpers for the JSBSim F450 plant, backend and simulator tests."""

import numpy as np

from vehicle_sim import FlightMode, SimConfig, Simulator, VelocitySetpoint, load_sim_config
from vehicle_sim.jsbsim_backend import JsbsimF450Plant, PlantConfig

HOVER_CMD = 0.4166
"""Equal motor command whose static thrust (4 x 3.43 N) carries the F450's 1.4 kg (near the
default origin, 488 m above sea level)."""

STEP_S = 0.004


def fly(plant: JsbsimF450Plant, cmds: np.ndarray, duration_s: float) -> None:
    """Hold ``cmds`` (4,) for ``duration_s`` [s] in control-rate steps."""
    plant.set_motor_commands(np.asarray(cmds, dtype=float))
    for _ in range(round(duration_s / STEP_S)):
        plant.step(STEP_S)


def airborne_hovering(height_m: float = 30.0, yaw_rad: float = 0.0) -> JsbsimF450Plant:
    """A plant in the air whose motors have spun up to the hover command (0.5 s, falling)."""
    plant = JsbsimF450Plant(PlantConfig(height_m=height_m, yaw_rad=yaw_rad))
    fly(plant, np.full(4, HOVER_CMD), 0.5)
    return plant


def f450_config() -> SimConfig:
    """The built-in preset that claims to be JSBSim's F450."""
    return load_sim_config("f450")


def airborne_sim(backend: str, alt_m: float = 3.0) -> Simulator:
    """The F450 on ``backend`` ("jsbsim" or "builtin") taken off, settled, hovering in OFFBOARD."""
    sim = Simulator(f450_config(), backend=backend)
    assert sim.arm().accepted
    assert sim.takeoff(alt_m).accepted
    sim.step(8.0)
    stream(sim, (0.0, 0.0, 0.0), 0.1)
    assert sim.set_mode(FlightMode.OFFBOARD).accepted
    stream(sim, (0.0, 0.0, 0.0), 2.0)
    return sim


def stream(sim: Simulator, vel_ned_mps, duration_s: float, period_s: float = 0.05) -> list:
    """Send a velocity setpoint every ``period_s`` for ``duration_s``; returns the states."""
    states = []
    for _ in range(round(duration_s / period_s)):
        sim.set_velocity_setpoint(VelocitySetpoint(tuple(vel_ned_mps)))
        states.append(sim.step(period_s))
    return states
