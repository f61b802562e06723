"""The JSBSim-backed simulator sits behind the same MAVLink endpoint as the built-in one."""

import pytest

from tests.vehicle_sim_mavlink.mavlink_test_client import Client
from vehicle_sim import Simulator, load_sim_config
from vehicle_sim.mavlink import EndpointConfig, LinkConfig, MavlinkEndpoint

MAV_CMD_NAV_LAND, MAV_CMD_NAV_TAKEOFF, MAV_CMD_COMPONENT_ARM_DISARM = 21, 22, 400
MAV_LANDED_STATE_ON_GROUND = 1
MAV_MODE_FLAG_SAFETY_ARMED = 128


@pytest.mark.slow
@pytest.mark.usefixtures("flight_control_compiled")
def test_arm_takeoff_land_over_mavlink(capfd):
    sim = Simulator(load_sim_config("f450"), backend="jsbsim")
    endpoint = MavlinkEndpoint(sim, EndpointConfig(links=(LinkConfig("api"),), speed=5.0))
    with endpoint:
        client = Client(port=endpoint.local_port)
        try:
            client.hello()
            assert client.command(MAV_CMD_COMPONENT_ARM_DISARM, 1).result == 0
            assert client.command(MAV_CMD_NAV_TAKEOFF).result == 0
            climbed = client.recv("LOCAL_POSITION_NED", 20.0, lambda m: m.z < -2.3)
            assert climbed is not None
            assert client.command(MAV_CMD_NAV_LAND).result == 0
            landed = client.recv(
                "EXTENDED_SYS_STATE", 20.0, lambda m: m.landed_state == MAV_LANDED_STATE_ON_GROUND
            )
            assert landed is not None
            disarmed = client.recv(
                "HEARTBEAT", 10.0, lambda m: not m.base_mode & MAV_MODE_FLAG_SAFETY_ARMED
            )
            assert disarmed is not None
        finally:
            client.close()
    assert -0.01 < sim.state.pos_ned_m[2] < 0.01
    assert capfd.readouterr() == ("", "")
