"""MAVSDK's NED velocity setpoint carries a yaw angle, so MavsdkLink turns the commanded yaw
rate into a yaw target; that target must not run away from a vehicle that turns slower than
commanded (a rover at its turn-rate limit), or the heading loop takes the short way round it
and the vehicle turns the other way."""

import socket
import time

import numpy as np
import pytest

from companion.link import ZERO_VELOCITY, VelocityCommand
from companion.mavsdk_link import MavsdkLink
from vehicle_sim.rover import RoverSim, rover_preset
from vehicle_sim.rover.mavlink_rover import RoverMavlinkEndpoint


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_a_yaw_rate_above_what_the_rover_turns_turns_it_one_way_only() -> None:
    preset = rover_preset("husky_50kg")  # turns in place at up to 1.5 rad/s
    command_radps, turn_s = 2.0 * preset.max_yaw_rate_radps, 4.0
    port = _free_port()
    sim = RoverSim(preset, seed=5)
    endpoint = RoverMavlinkEndpoint(sim, port, setpoint_timeout_s=2.0, mode="udpout")
    endpoint.start()
    link = MavsdkLink(f"udpin://127.0.0.1:{port}")
    headings = []
    try:
        link.connect(timeout_s=20.0)
        link.send_velocity(ZERO_VELOCITY)
        assert link.arm().accepted and link.start_offboard().accepted
        t_end = time.monotonic() + turn_s
        while time.monotonic() < t_end:
            link.send_velocity(VelocityCommand((0.0, 0.0, 0.0), command_radps))
            headings.append(sim.state.heading_rad)
            time.sleep(0.05)
        link.hold()
    finally:
        link.close()
        endpoint.close()
    steps = np.diff(np.unwrap(headings))
    # NED yaw rate > 0 is clockwise: the rover's counter-clockwise heading goes down, always.
    assert max(steps) < 0.02, "the rover turned back: the yaw target ran away from it"
    assert -float(np.sum(steps)) > 0.6 * preset.max_yaw_rate_radps * turn_s
