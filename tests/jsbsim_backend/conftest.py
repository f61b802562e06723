"""Fixtures for the JSBSim backend tests."""

from __future__ import annotations

import pytest

from tests.jsbsim_backend.jsbsim_helpers import f450_config
from vehicle_sim import Simulator


@pytest.fixture(scope="session")
def flight_control_compiled() -> None:
    """JSBSim's F450 flown a moment, so that the flight control it calls is compiled (or loaded
    from numba's cache) before a test of what a flight prints: its first build on a machine is
    said on stderr (vehicle_sim.compile_notice), by design; JSBSim's chatter is what is tested."""
    Simulator(f450_config(), backend="jsbsim").step(0.1)
