"""The same scripted MAVSDK mission flies on both backends behind the MAVLink endpoint:
connect, arm, takeoff, OFFBOARD NED velocity, land, automatic disarm."""

from __future__ import annotations

import pytest
from mavsdk import ComponentType, Configuration, Mavsdk
from mavsdk.plugins.action import Action
from mavsdk.plugins.offboard import Offboard, VelocityNedYaw
from mavsdk.plugins.telemetry import Telemetry

from tests.jsbsim_backend.jsbsim_helpers import f450_config
from tests.vehicle_sim_mavlink.mavlink_test_client import LOOPBACK, free_udp_port, wait_until
from vehicle_sim import FlightMode, Simulator
from vehicle_sim.mavlink import EndpointConfig, LinkConfig, MavlinkEndpoint

SPEED = 2.0
"""Simulated seconds per wall-clock second."""
TAKEOFF_ALT_M = 3.0
NORTH_MPS = 1.0


def f450_endpoint(backend: str, port: int) -> MavlinkEndpoint:
    """The F450 on ``backend`` behind one link sending to ``port`` on loopback (started)."""
    link = LinkConfig("api", remote=(LOOPBACK, port))
    sim = Simulator(f450_config(), seed=0, backend=backend)
    return MavlinkEndpoint(sim, EndpointConfig(links=(link,), speed=SPEED)).start()


def sim_wait(endpoint: MavlinkEndpoint, sim_s: float) -> None:
    """Let ``sim_s`` seconds of simulated time pass."""
    t_end_s = endpoint.state.t_s + sim_s
    wait_until(lambda: endpoint.state.t_s >= t_end_s, sim_s / SPEED * 4 + 5.0, f"{sim_s} s sim")


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["builtin", "jsbsim"])
def test_mavsdk_mission_flies_on_both_backends(backend):
    port = free_udp_port()
    endpoint = f450_endpoint(backend, port)
    mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        mavsdk.add_any_connection(f"udpin://{LOOPBACK}:{port}")
        system = mavsdk.first_autopilot(10.0)
        assert system is not None, "MAVSDK found no autopilot"
        telemetry, action, offboard = Telemetry(system), Action(system), Offboard(system)
        wait_until(telemetry.health_all_ok, 10.0, "MAVSDK health all ok")
        action.set_takeoff_altitude(TAKEOFF_ALT_M)

        action.arm()
        wait_until(telemetry.armed, 3.0, "MAVSDK to see the vehicle armed")
        action.takeoff()
        wait_until(
            lambda: (
                endpoint.state.mode == FlightMode.HOLD
                and -endpoint.state.pos_ned_m[2] > TAKEOFF_ALT_M - 0.2
            ),
            30.0,
            "takeoff",
        )
        wait_until(telemetry.in_air, 3.0, "MAVSDK in_air")
        assert telemetry.position().relative_altitude_m == pytest.approx(TAKEOFF_ALT_M, abs=0.3)

        offboard.set_velocity_ned(VelocityNedYaw(NORTH_MPS, 0.0, 0.0, 0.0))
        offboard.start()
        assert endpoint.state.mode == FlightMode.OFFBOARD
        north_before_m = float(endpoint.state.pos_ned_m[0])
        sim_wait(endpoint, 4.0)
        vel = endpoint.state.vel_ned_mps
        assert vel[0] == pytest.approx(NORTH_MPS, abs=0.15) and abs(vel[1]) < 0.15
        assert abs(vel[2]) < 0.15
        assert endpoint.state.pos_ned_m[0] - north_before_m > 2.5
        # MAVSDK's telemetry reports it too, once its next position message arrives (on a
        # loaded machine it read the 0.0 of before the first)
        wait_until(
            lambda: abs(telemetry.velocity_ned().north_m_s - NORTH_MPS) < 0.2,
            3.0,
            "MAVSDK telemetry's north velocity",
        )
        offboard.stop()
        wait_until(lambda: endpoint.state.mode == FlightMode.HOLD, 3.0, "HOLD after stop")

        action.land()
        wait_until(lambda: not endpoint.state.armed, 40.0, "landing and automatic disarm")
        wait_until(lambda: not telemetry.armed(), 3.0, "MAVSDK to see the vehicle disarmed")
        assert not telemetry.in_air()
        assert abs(endpoint.state.pos_ned_m[2]) < 0.1
        assert endpoint.stats.commands_unsupported == 0
    finally:
        mavsdk.destroy()
        endpoint.stop()
