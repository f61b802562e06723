"""MAVSDK-Python 4.x (native API) flies a whole session against the endpoint over loopback UDP."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mavlink_test_client import free_udp_port, make_endpoint, wait_until
from mavsdk import ComponentType, Configuration, Mavsdk
from mavsdk.plugins.action import Action
from mavsdk.plugins.offboard import Offboard, VelocityBodyYawspeed, VelocityNedYaw
from mavsdk.plugins.param import Param
from mavsdk.plugins.telemetry import Telemetry

from vehicle_sim import FlightMode

SPEED = 2.0


def sim_wait(endpoint, sim_s: float) -> None:
    """Let ``sim_s`` seconds of simulated time pass."""
    t_end = endpoint.state.t_s + sim_s
    wait_until(lambda: endpoint.state.t_s >= t_end, sim_s / SPEED * 4 + 5.0, f"{sim_s} s of sim")


@pytest.mark.slow
def test_mavsdk_full_session():
    port = free_udp_port()
    endpoint = make_endpoint(speed=SPEED, remote_port=port).start()
    mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        mavsdk.add_any_connection(f"udpin://127.0.0.1:{port}")
        system = mavsdk.first_autopilot(10.0)
        assert system is not None, "MAVSDK found no autopilot"
        telemetry, action = Telemetry(system), Action(system)
        param, offboard = Param(system), Offboard(system)

        wait_until(telemetry.health_all_ok, 10.0, "MAVSDK health all ok")
        assert param.get_param_float("MIS_TAKEOFF_ALT") == pytest.approx(2.5)
        action.set_takeoff_altitude(3.0)  # a PARAM_SET of MIS_TAKEOFF_ALT
        assert param.get_param_float("MIS_TAKEOFF_ALT") == pytest.approx(3.0)

        action.arm()
        wait_until(telemetry.armed, 3.0, "MAVSDK to see the vehicle armed")
        action.takeoff()
        wait_until(
            lambda: endpoint.state.mode == FlightMode.HOLD and -endpoint.state.pos_ned_m[2] > 2.8,
            20.0,
            "takeoff to 3 m",
        )
        wait_until(telemetry.in_air, 3.0, "MAVSDK in_air")
        assert telemetry.position().relative_altitude_m == pytest.approx(3.0, abs=0.3)

        offboard.set_velocity_ned(VelocityNedYaw(1.0, 0.0, 0.0, 0.0))
        offboard.start()
        assert endpoint.state.mode == FlightMode.OFFBOARD
        north_before_m = float(endpoint.state.pos_ned_m[0])
        sim_wait(endpoint, 3.0)
        vel = endpoint.state.vel_ned_mps
        assert vel[0] == pytest.approx(1.0, abs=0.15) and abs(vel[1]) < 0.15
        assert endpoint.state.pos_ned_m[0] - north_before_m > 2.0
        assert telemetry.velocity_ned().north_m_s == pytest.approx(1.0, abs=0.2)

        yaw_before_rad = endpoint.state.yaw_rad
        offboard.set_velocity_body(VelocityBodyYawspeed(1.0, 0.0, 0.0, 30.0))
        sim_wait(endpoint, 2.0)
        turned_rad = (endpoint.state.yaw_rad - yaw_before_rad) % (2 * math.pi)
        assert turned_rad == pytest.approx(math.radians(60.0), abs=math.radians(15.0))
        speed_mps = float(np.linalg.norm(endpoint.state.vel_ned_mps[:2]))
        heading_rad = math.atan2(endpoint.state.vel_ned_mps[1], endpoint.state.vel_ned_mps[0])
        assert speed_mps == pytest.approx(1.0, abs=0.25)  # forward in the body frame ...
        assert abs(math.remainder(heading_rad - endpoint.state.yaw_rad, 2 * math.pi)) < 0.5

        offboard.stop()
        wait_until(lambda: endpoint.state.mode == FlightMode.HOLD, 3.0, "HOLD after stop")
        assert endpoint.state.armed

        action.land()
        wait_until(lambda: not endpoint.state.armed, 30.0, "landing and automatic disarm")
        wait_until(lambda: not telemetry.armed(), 3.0, "MAVSDK to see the vehicle disarmed")
        assert not telemetry.in_air()
        assert abs(endpoint.state.pos_ned_m[2]) < 0.1
        assert endpoint.stats.commands_unsupported == 0
    finally:
        mavsdk.destroy()
        endpoint.stop()
