"""MAVSDK-Python drives the rover endpoint: arm, offboard body velocity + yaw rate, telemetry."""

import time

import pytest
from mavsdk import ComponentType, Configuration, Mavsdk
from mavsdk.plugins.action import Action
from mavsdk.plugins.offboard import Offboard, VelocityBodyYawspeed
from mavsdk.plugins.telemetry import Telemetry

from tests.free_port import free_udp_port
from vehicle_sim.rover import RoverSim, rover_preset
from vehicle_sim.rover.mavlink_rover import RoverMavlinkEndpoint


@pytest.mark.slow
def test_mavsdk_arm_offboard_and_telemetry() -> None:
    port = free_udp_port()
    ep = RoverMavlinkEndpoint(RoverSim(rover_preset("husky_50kg")), port)
    ep.start()
    mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        mavsdk.add_any_connection(f"udpout://127.0.0.1:{port}")
        system = mavsdk.first_autopilot(20.0)
        assert system is not None, "MAVSDK found no autopilot"
        telemetry, action, offboard = Telemetry(system), Action(system), Offboard(system)
        action.arm()
        assert ep.sim.armed
        offboard.set_velocity_body(VelocityBodyYawspeed(0.5, 0.0, 0.0, -20.0))
        offboard.start()
        assert ep.offboard
        time.sleep(3.0)
        assert ep.sim.state.speed_mps > 0.3
        assert ep.sim.state.heading_rad > 0.3  # -20 deg/s in NED turns left (CCW)
        t_end = time.monotonic() + 10.0
        while telemetry.position_velocity_ned().position.north_m < 0.5:
            assert time.monotonic() < t_end, "telemetry never showed the rover moving north"
            time.sleep(0.1)
        offboard.stop()  # PX4 goes to hold
        assert not ep.offboard
        action.disarm()
        assert not ep.sim.armed
    finally:
        ep.close()
