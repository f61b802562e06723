"""MAV_CMD_DO_ORBIT over a real UDP endpoint from pymavlink: ACK, HEARTBEAT mode (POSCTL sub
mode ORBIT, as PX4), ORBIT_EXECUTION_STATUS, and malformed orbits answered, not fatal."""

from __future__ import annotations

import math

import pytest
from mavlink_test_client import MAV_RESULT_ACCEPTED, wait_until

from vehicle_sim import FlightMode, Simulator, load_sim_config
from vehicle_sim.mavlink.geodetic import GeodeticOrigin
from vehicle_sim.mavlink.orbit import orbit_execution_status, start_orbit
from vehicle_sim.orbit import Orbit

MAV_CMD_DO_ORBIT = 34
MAV_RESULT_DENIED = 2
ORBIT_CUSTOM_MODE = 3 << 16 | 1 << 24
INT32_MAX = 2**31 - 1
NAN = float("nan")


@pytest.fixture
def hovering(endpoint, client):
    assert client.command(400, 1).result == MAV_RESULT_ACCEPTED
    assert client.command(22, *[NAN] * 7).result == MAV_RESULT_ACCEPTED
    wait_until(lambda: endpoint.state.mode is FlightMode.HOLD, 20.0, "takeoff complete")
    return endpoint


@pytest.mark.slow
def test_do_orbit_flies_reports_the_mode_and_streams_its_status(hovering, client) -> None:
    endpoint = hovering
    here = client.recv("GLOBAL_POSITION_INT", 3.0)
    lat = here.lat / 1e7
    lon = here.lon / 1e7 + math.degrees(5.0 / (6378137.0 * math.cos(math.radians(lat))))
    ack = client.command(MAV_CMD_DO_ORBIT, -5.0, 2.0, 0, NAN, lat, lon, NAN)
    assert ack is not None and ack.result == MAV_RESULT_ACCEPTED
    beat = client.recv("HEARTBEAT", 3.0, lambda m: m.custom_mode == ORBIT_CUSTOM_MODE)
    assert beat is not None and beat.base_mode & 1  # custom mode enabled
    status = client.recv("ORBIT_EXECUTION_STATUS", 3.0)
    assert status is not None and status.radius == -5.0 and status.frame == 0
    # (COMMAND_LONG's float32 parameters hold a latitude to about 0.5 m)
    assert abs(status.x - lat * 1e7) < 50 and abs(status.y - lon * 1e7) < 50
    start_s = endpoint.state.t_s
    wait_until(lambda: endpoint.state.t_s > start_s + 15.0, 60.0, "a while orbiting")
    state = endpoint.state
    assert state.mode is FlightMode.ORBIT
    assert abs(math.hypot(*state.vel_ned_mps[:2]) - 2.0) < 0.3
    assert abs(math.hypot(state.pos_ned_m[0], state.pos_ned_m[1] - 5.0) - 5.0) < 0.3


def test_do_orbit_as_command_int_without_a_centre_circles_here(hovering, client) -> None:
    ack = client.command(
        MAV_CMD_DO_ORBIT, 3.0, 1.0, NAN, NAN, INT32_MAX, INT32_MAX, NAN, use_int=True
    )
    assert ack is not None and ack.result == MAV_RESULT_ACCEPTED
    status = client.recv("ORBIT_EXECUTION_STATUS", 3.0)
    here = client.recv("GLOBAL_POSITION_INT", 3.0)
    assert status is not None and status.radius == 3.0
    assert abs(status.x - here.lat) < 100 and abs(status.y - here.lon) < 100  # within ~1 m


def test_malformed_orbits_are_denied_and_the_endpoint_keeps_serving(endpoint, client) -> None:
    on_ground = client.command(MAV_CMD_DO_ORBIT, 5.0, 1.0, NAN, NAN, NAN, NAN, NAN)
    assert on_ground is not None and on_ground.result == MAV_RESULT_DENIED
    notice = client.recv("STATUSTEXT", 3.0, lambda m: "Orbit" in m.text)
    assert notice is not None and "not flying" in notice.text
    bad = (
        (math.inf, 1.0, NAN, NAN, NAN, NAN, NAN),
        (5.0, 1.0, 0, 0, 95.0, 8.0, 500.0),  # latitude
        (5.0, 1.0, 0, 0, 47.0, 2000.0, 500.0),  # longitude
        (5.0, 1.0, 0, 0, 0.0, 0.0, 500.0),  # a centre 5000 km away
    )
    for params in bad:
        ack = client.command(MAV_CMD_DO_ORBIT, *params)
        assert ack is not None and ack.result == MAV_RESULT_DENIED
    assert endpoint.stats.handler_errors == 0 and endpoint.running


@pytest.mark.parametrize(
    ("lat", "lon", "named"), [(95.0, 8.0, "latitude"), (47.0, 188.5, "longitude")]
)
def test_an_orbit_centre_off_the_globe_is_refused_naming_the_coordinate(lat, lon, named) -> None:
    sim = Simulator(load_sim_config("iris"), seed=0)
    with pytest.raises(ValueError, match=named):
        start_orbit(sim, (5.0, 1.0, 0.0, NAN, lat, lon, 500.0), GeodeticOrigin())


@pytest.mark.parametrize(("velocity", "radius"), [(2.0, 5.0), (-2.0, -5.0)])
def test_orbit_execution_status_signs_the_radius_by_the_direction(velocity, radius) -> None:
    """[MAVLink] ORBIT_EXECUTION_STATUS.radius: positive clockwise, negative counter-clockwise;
    the centre in MAV_FRAME_GLOBAL (0) in degE7 and metres above mean sea level: an orbit
    around the origin 10 m up is at the origin's latitude/longitude and 488 + 10 m."""
    origin = GeodeticOrigin()
    orbit = Orbit((0.0, 0.0), -10.0, 5.0, velocity, 0, 0.0)
    status = orbit_execution_status(orbit, origin, 3.0)
    assert status.radius == radius and status.frame == 0
    assert (status.x, status.y) == (round(origin.lat_deg * 1e7), round(origin.lon_deg * 1e7))
    assert status.z == pytest.approx(498.0)
    assert status.time_usec == 3_000_000
