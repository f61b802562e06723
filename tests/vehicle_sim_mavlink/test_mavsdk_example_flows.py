"""MAVSDK's own example flows against vehicle-sim, as against PX4 SITL.

Each test does what one of MAVSDK-Python's example scripts does, through MAVSDK's documented
API (the native 4.x binding): takeoff_and_land (reads RTL_RETURN_ALT), goto (DO_REPOSITION),
return to launch, mission (upload, start, progress, RTL at the end), offboard_position_ned (and
its global variant, set_position_global) and
offboard_velocity_body. Real time, a real UDP
endpoint, MAVSDK's own mavlink stack; deadlines are generous so a busy CPU does not matter.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator

import numpy as np
import pytest
from mavsdk import ComponentType, Configuration, ConnectionResult, Mavsdk, log_subscribe
from mavsdk.plugins.action import Action
from mavsdk.plugins.mission import Mission, MissionItem, MissionPlan
from mavsdk.plugins.offboard import (
    Offboard,
    PositionGlobalYaw,
    PositionNedYaw,
    VelocityBodyYawspeed,
    VelocityNedYaw,
)
from mavsdk.plugins.param import Param
from mavsdk.plugins.telemetry import Telemetry

from tests.free_port import free_udp_port
from vehicle_sim import FlightMode, LandedState, Simulator, load_sim_config
from vehicle_sim.mavlink import EndpointConfig, LinkConfig, MavlinkEndpoint

pytestmark = pytest.mark.slow


class Drone:
    """vehicle-sim's endpoint sending to a MAVSDK instance listening on a free port."""

    def __init__(self) -> None:
        port = free_udp_port()
        link = LinkConfig("offboard", remote=("127.0.0.1", port))
        self.endpoint = MavlinkEndpoint(
            Simulator(load_sim_config("iris"), seed=11), EndpointConfig(links=(link,))
        ).start()
        log_subscribe(lambda *_args: True)  # MAVSDK's own log lines stay out of the test output
        self.mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        assert self.mavsdk.add_any_connection(f"udpin://127.0.0.1:{port}") == (
            ConnectionResult.SUCCESS
        )
        system = self.mavsdk.first_autopilot(30.0)
        assert system is not None, "no autopilot discovered"
        self.action, self.telemetry = Action(system), Telemetry(system)
        self.offboard, self.param = Offboard(system), Param(system)
        self.mission = Mission(system)
        wait(lambda: self.telemetry.health_all_ok(), 30.0, "health all ok")

    @property
    def state(self):
        return self.endpoint.state

    def close(self) -> None:
        self.mavsdk.destroy()
        self.endpoint.stop()


def wait(predicate: Callable[[], bool], timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"no {what} within {timeout_s} s")
        time.sleep(0.1)


@pytest.fixture
def drone() -> Iterator[Drone]:
    d = Drone()
    yield d
    d.close()


def take_off(drone: Drone, alt_m: float = 2.5) -> None:
    drone.action.set_takeoff_altitude(alt_m)
    drone.action.arm()
    drone.action.takeoff()
    wait(lambda: drone.telemetry.in_air(), 20.0, "in air")
    wait(lambda: drone.state.mode is FlightMode.HOLD, 30.0, "takeoff to end in HOLD")


def land_and_disarm(drone: Drone) -> None:
    drone.action.land()
    wait(lambda: not drone.state.armed, 60.0, "landing and disarm")
    assert drone.state.landed_state is LandedState.ON_GROUND


def test_takeoff_and_land(drone: Drone) -> None:
    assert drone.param.get_param_float("RTL_RETURN_ALT") == pytest.approx(60.0)
    take_off(drone)
    assert -drone.state.pos_ned_m[2] == pytest.approx(2.5, abs=0.3)
    land_and_disarm(drone)


def test_goto_flies_to_the_location_and_holds(drone: Drone) -> None:
    take_off(drone)
    here = drone.telemetry.position()
    north_m = 10.0
    lat = here.latitude_deg + math.degrees(north_m / 6378137.0)
    drone.action.goto_location(lat, here.longitude_deg, here.absolute_altitude_m + 1.0, 0.0)
    wait(lambda: abs(drone.state.pos_ned_m[0] - north_m) < 0.3, 40.0, "arrival 10 m north")
    assert drone.state.mode is FlightMode.HOLD
    assert -drone.state.pos_ned_m[2] == pytest.approx(3.5, abs=0.3)
    land_and_disarm(drone)


def test_return_to_launch_climbs_returns_and_lands(drone: Drone) -> None:
    drone.param.set_param_float("RTL_RETURN_ALT", 5.0)
    take_off(drone)
    drone.action.goto_location(
        *_offset(drone, north_m=8.0, east_m=4.0), drone.telemetry.position().absolute_altitude_m, 0
    )
    wait(lambda: abs(drone.state.pos_ned_m[0] - 8.0) < 0.5, 40.0, "arrival away from home")
    drone.action.return_to_launch()
    wait(lambda: drone.state.mode is FlightMode.RTL, 5.0, "RTL mode")
    wait(lambda: -drone.state.pos_ned_m[2] > 4.7, 20.0, "the climb to RTL_RETURN_ALT")
    wait(lambda: not drone.state.armed, 90.0, "landing at home and disarm")
    assert math.hypot(*drone.state.pos_ned_m[:2]) < 0.8


def _offset(drone: Drone, north_m: float, east_m: float) -> tuple[float, float]:
    here = drone.telemetry.position()
    lat = here.latitude_deg + math.degrees(north_m / 6378137.0)
    lon = here.longitude_deg + math.degrees(
        east_m / (6378137.0 * math.cos(math.radians(here.latitude_deg)))
    )
    return lat, lon


def test_offboard_position_ned(drone: Drone) -> None:
    take_off(drone)
    drone.offboard.set_position_ned(PositionNedYaw(0.0, 0.0, -2.5, 0.0))
    drone.offboard.start()
    for north, east, down, yaw in ((5.0, 0.0, -3.0, 0.0), (5.0, 5.0, -3.0, 90.0)):
        drone.offboard.set_position_ned(PositionNedYaw(north, east, down, yaw))
        wait(
            lambda n=north, e=east: math.hypot(*(drone.state.pos_ned_m[:2] - (n, e))) < 0.3,
            30.0,
            f"position ({north}, {east})",
        )
    assert drone.state.mode is FlightMode.OFFBOARD
    drone.offboard.stop()
    land_and_disarm(drone)


def test_offboard_position_global_relative_to_home(drone: Drone) -> None:
    take_off(drone)
    lat, lon = _offset(drone, north_m=-6.0, east_m=3.0)
    target = PositionGlobalYaw(lat, lon, 4.0, 0.0, PositionGlobalYaw.AltitudeType.REL_HOME)
    drone.offboard.set_position_global(target)
    drone.offboard.start()
    wait(
        lambda: bool(np.linalg.norm(drone.state.pos_ned_m - (-6.0, 3.0, -4.0)) < 0.3),
        30.0,
        "position 6 m south, 3 m east, 4 m up",
    )
    assert drone.state.mode is FlightMode.OFFBOARD
    drone.offboard.stop()
    land_and_disarm(drone)


def test_offboard_velocity_body(drone: Drone) -> None:
    take_off(drone)
    drone.offboard.set_velocity_ned(VelocityNedYaw(0.0, 0.0, 0.0, 0.0))
    drone.offboard.start()
    start = drone.state.pos_ned_m.copy()
    drone.offboard.set_velocity_body(VelocityBodyYawspeed(2.0, 0.0, 0.0, 0.0))
    time.sleep(3.0)
    drone.offboard.set_velocity_body(VelocityBodyYawspeed(0.0, 0.0, 0.0, 0.0))
    time.sleep(2.0)
    moved = drone.state.pos_ned_m - start
    assert math.hypot(*moved[:2]) > 3.0  # flew forward
    drone.offboard.stop()
    land_and_disarm(drone)


def test_mission_upload_start_progress_and_rtl_at_the_end(drone: Drone) -> None:
    drone.param.set_param_float("RTL_RETURN_ALT", 5.0)
    points = [(10.0, 0.0), (10.0, 8.0), (0.0, 8.0)]
    items = [
        MissionItem(
            *_offset(drone, north, east),
            relative_altitude_m=4.0,
            speed_m_s=3.0,
            is_fly_through=True,
            acceptance_radius_m=1.0,
        )
        for north, east in points
    ]
    drone.mission.set_return_to_launch_after_mission(True)
    drone.mission.upload_mission(MissionPlan(items))
    drone.action.arm()
    drone.mission.start_mission()
    seen = set()

    def progress() -> bool:
        seen.add(drone.mission.mission_progress().current)
        return drone.mission.is_mission_finished()

    wait(progress, 90.0, "the mission to finish")
    assert {1, 2, 3} <= seen
    wait(lambda: not drone.state.armed, 90.0, "RTL at the end: landing at home and disarm")
    assert math.hypot(*drone.state.pos_ned_m[:2]) < 0.8
