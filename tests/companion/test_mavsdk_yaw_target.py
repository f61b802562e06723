"""MAVSDK's NED velocity setpoint carries a yaw angle, so MavsdkLink turns the commanded yaw
rate into a yaw target; that target must not run away from a vehicle that turns slower than
commanded (a rover at its turn-rate limit), or the heading loop takes the short way round it
and the vehicle turns the other way. A rover is sent its yaw rate itself (body velocity)."""

import math
import time

import numpy as np
import pytest

from companion.link import ZERO_VELOCITY, VelocityCommand
from companion.mavsdk_link import (
    MAX_YAW_LEAD_RAD,
    YAW_HOLD_RAD,
    MavsdkLink,
    body_velocity,
    next_yaw_target_rad,
)
from tests.free_port import free_udp_port
from vehicle_sim.rover import RoverSim, rover_preset
from vehicle_sim.rover.mavlink_rover import RoverMavlinkEndpoint


@pytest.mark.slow
def test_a_yaw_rate_above_what_the_rover_turns_turns_it_one_way_only() -> None:
    preset = rover_preset("husky_50kg")  # turns in place at up to 1.5 rad/s
    command_radps, turn_s = 2.0 * preset.max_yaw_rate_radps, 4.0
    port = free_udp_port()
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


def test_the_yaw_target_stays_near_a_vehicle_that_does_not_turn_and_follows_the_command() -> None:
    """A vehicle stuck at yaw 0 commanded 3 rad/s for 2 s: the target leads it by at most
    MAX_YAW_LEAD_RAD, well short of half a turn; the command reversed, the target is at once
    no more than YAW_HOLD_RAD on the old side; at zero rate it holds the heading within it."""
    target = 0.0
    for _ in range(40):
        target = next_yaw_target_rad(target, 0.0, 3.0, 0.05)
    assert target == pytest.approx(MAX_YAW_LEAD_RAD)
    target = next_yaw_target_rad(target, 0.0, -0.3, 0.05)
    assert target <= YAW_HOLD_RAD
    assert next_yaw_target_rad(0.1, 0.0, 0.0, 0.05) == pytest.approx(0.1)  # held, not reset
    assert next_yaw_target_rad(0.4, 0.0, 0.0, 0.05) == pytest.approx(YAW_HOLD_RAD)
    # a turning vehicle that keeps up gets the plain integral
    assert next_yaw_target_rad(1.0, 0.9, 0.5, 0.1) == pytest.approx(1.05)


@pytest.mark.slow
def test_a_rover_is_sent_its_yaw_rate_not_a_yaw_target() -> None:
    """At once the rover's setpoint is the commanded forward speed and turn rate (NED yaw
    rate 0.3 rad/s clockwise: -0.3 counter-clockwise), not a heading loop's catching up."""
    port = free_udp_port()
    sim = RoverSim(rover_preset("husky_50kg"), seed=6)
    endpoint = RoverMavlinkEndpoint(sim, port, setpoint_timeout_s=2.0, mode="udpout")
    endpoint.start()
    link = MavsdkLink(f"udpin://127.0.0.1:{port}")
    try:
        link.connect(timeout_s=20.0)
        assert link.read_state().vehicle_kind == "rover"
        link.send_velocity(ZERO_VELOCITY)
        assert link.arm().accepted and link.start_offboard().accepted
        for _ in range(5):
            link.send_velocity(VelocityCommand((0.4, 0.0, 0.0), 0.3))
            time.sleep(0.05)
        time.sleep(0.1)
        speed_mps, yaw_rate_radps = sim._sp
        link.hold()
    finally:
        link.close()
        endpoint.close()
    assert yaw_rate_radps == pytest.approx(-0.3, abs=1e-3)
    assert speed_mps == pytest.approx(0.4, abs=0.01)


def test_a_stop_is_a_stop_whatever_the_heading() -> None:
    """The rover's body velocity: north at heading 90 deg is to its left; a zero velocity stays
    zero when the attitude is not finite (an estimator reset): the stop a drive sends on a
    non-finite state went out as a NaN forward speed, which the rover refuses, driving on."""
    assert body_velocity(1.0, 0.0, math.pi / 2) == pytest.approx((0.0, -1.0), abs=1e-12)
    assert body_velocity(0.0, 0.0, math.nan) == (0.0, 0.0)


def test_a_yaw_target_made_of_a_nan_attitude_starts_again_at_the_heading() -> None:
    """One non-finite attitude (an estimator reset) made the target NaN, and every later target
    was made from it: a multicopter was sent a NaN yaw for the rest of the flight."""
    target = next_yaw_target_rad(0.0, math.nan, 0.5, 0.1)
    assert math.isnan(target)
    assert next_yaw_target_rad(target, 0.3, 0.5, 0.1) == 0.3
    assert next_yaw_target_rad(0.3, 0.3, 0.5, 0.1) == pytest.approx(0.35)
