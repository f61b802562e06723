"""MAVSDK's action.do_orbit against vehicle-sim, as against PX4 SITL: the vehicle circles the
given centre at the given radius and speed, facing it, and MAVSDK's hold ends the orbit."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
from mavsdk.plugins.action import OrbitYawBehavior
from test_mavsdk_example_flows import Drone, _offset, land_and_disarm, take_off, wait

from vehicle_sim import FlightMode

pytestmark = pytest.mark.slow


@pytest.fixture
def drone() -> Iterator[Drone]:
    d = Drone()
    yield d
    d.close()


def test_do_orbit(drone: Drone) -> None:
    take_off(drone, 5.0)
    centre = drone.state.pos_ned_m[:2] + (6.0, 0.0)
    lat, lon = _offset(drone, north_m=6.0, east_m=0.0)
    altitude = drone.telemetry.position().absolute_altitude_m
    drone.action.do_orbit(
        6.0, 2.0, OrbitYawBehavior.HOLD_FRONT_TO_CIRCLE_CENTER, lat, lon, altitude
    )
    wait(lambda: drone.state.mode is FlightMode.ORBIT, 5.0, "ORBIT")
    start_s = drone.state.t_s
    wait(lambda: drone.state.t_s > start_s + 10.0, 40.0, "a while orbiting")  # settled in 6 s
    for _ in range(5):
        state = drone.state
        rel = state.pos_ned_m[:2] - centre
        assert np.hypot(*rel) == pytest.approx(6.0, abs=0.3)
        assert np.hypot(*state.vel_ned_mps[:2]) == pytest.approx(2.0, abs=0.2)
        to_centre = math.atan2(-rel[1], -rel[0])
        assert abs((state.yaw_rad - to_centre + math.pi) % (2 * math.pi) - math.pi) < 0.1
        assert -state.pos_ned_m[2] == pytest.approx(5.0, abs=0.3)
        wait(lambda s=state.t_s: drone.state.t_s > s + 1.0, 5.0, "a second")
    drone.action.hold()
    wait(lambda: drone.state.mode is FlightMode.HOLD, 5.0, "HOLD")
    land_and_disarm(drone)
