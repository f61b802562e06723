"""JSBSim's F450 quadcopter as a second, independent plant under our flight control."""

from vehicle_sim.jsbsim_backend.backend import JsbsimBackend
from vehicle_sim.jsbsim_backend.plant import JsbsimF450Plant, PlantConfig, PlantState

__all__ = ["JsbsimBackend", "JsbsimF450Plant", "PlantConfig", "PlantState"]
