"""parse_setpoint: PX4's frames and type_mask rules, and rejection of unusable values."""

from __future__ import annotations

import math

import pytest

from vehicle_sim.mavlink.geodetic import GeodeticOrigin
from vehicle_sim.mavlink.offboard import parse_global_setpoint, parse_setpoint
from vehicle_sim.vehicle_types import VelocitySetpoint

MASK_MAVSDK_VELOCITY_NED = 2503  # velocity + yaw
MASK_MAVSDK_VELOCITY_BODY = 1479  # velocity + yaw rate


def test_mavsdk_velocity_ned_uses_yaw_not_yaw_rate():
    result = parse_setpoint(1, MASK_MAVSDK_VELOCITY_NED, (1.0, -2.0, 0.5), 0.3, 9.0)
    assert result.setpoint == VelocitySetpoint((1.0, -2.0, 0.5), 0.0, 0.3, "ned")
    assert result.reason == ""


def test_mavsdk_velocity_body_uses_yaw_rate():
    result = parse_setpoint(8, MASK_MAVSDK_VELOCITY_BODY, (0.0, 1.0, 0.0), 123.0, 0.5)
    assert result.setpoint == VelocitySetpoint((0.0, 1.0, 0.0), 0.5, None, "body")


def test_velocity_only_mask_holds_yaw_rate_zero():
    result = parse_setpoint(1, 0b110111000111, (0.0, 0.0, -1.0), math.nan, math.nan)
    assert result.setpoint == VelocitySetpoint((0.0, 0.0, -1.0), 0.0, None, "ned")


@pytest.mark.parametrize(
    ("frame", "mask", "vel", "yaw", "yaw_rate", "reason"),
    [
        (0, 2503, (1, 0, 0), 0, 0, "frame 0 unsupported"),
        (9, 2503, (1, 0, 0), 0, 0, "frame 9 unsupported"),
        (1, 0b110000000111, (1, 0, 0), 0, 0, "acceleration setpoints unsupported"),
        (1, 0b110111111111, (1, 0, 0), 0, 0, "all 3 velocity components"),
        (1, 0b110111110111, (1, 0, 0), 0, 0, "all 3 velocity components"),
        (8, 0b110111111000, (0, 0, 0), 0, 0, "need frame 1"),
        (1, 2503, (math.nan, 0, 0), 0, 0, "invalid velocity"),
        (1, 2503, (1e9, 0, 0), 0, 0, "invalid velocity"),
        (1, 2503, (0, 0, -math.inf), 0, 0, "invalid velocity"),
        (1, 2503, (0, 0, 0), math.nan, 0, "invalid yaw setpoint"),
        (1, 2503, (0, 0, 0), 1e9, 0, "invalid yaw setpoint"),
        (8, 1479, (0, 0, 0), 0, 1e9, "invalid yaw rate"),
    ],
)
def test_unusable_setpoints_are_rejected_with_a_reason(frame, mask, vel, yaw, yaw_rate, reason):
    result = parse_setpoint(frame, mask, vel, yaw, yaw_rate)
    assert result.setpoint is None
    assert reason in result.reason
    assert "\n" not in result.reason  # one line; STATUSTEXT chunks what exceeds 50 characters


@pytest.mark.parametrize(
    ("mask", "vel_ff"),
    [(0b100111111000, (0.0, 0.0, 0.0)), (0b100111000000, (1.0, -0.5, 0.0))],
    ids=["position", "position+velocity"],
)
def test_position_setpoints_carry_the_position_and_the_feed_forward(mask, vel_ff):
    result = parse_setpoint(1, mask, (1.0, -0.5, 0.0), 0.3, 0.0, (4.0, -2.0, -3.0))
    assert result.reason == ""
    assert result.setpoint.pos_ned_m == (4.0, -2.0, -3.0)
    assert result.setpoint.vel_mps == vel_ff and result.setpoint.yaw_rad == 0.3


@pytest.mark.parametrize(("frame", "alt_m"), [(5, 491.0), (6, 3.0)], ids=["amsl", "relative"])
def test_global_int_position_maps_to_local_ned_around_home(frame, alt_m):
    home = GeodeticOrigin()
    lat, lon, _ = home.to_global((10.0, -5.0, 0.0))
    result = parse_global_setpoint(
        frame, 0b100111111000, round(lat * 1e7), round(lon * 1e7), alt_m, (0, 0, 0), 0.0, 0.0, home
    )
    assert result.reason == ""
    assert result.setpoint.pos_ned_m == pytest.approx((10.0, -5.0, -3.0), abs=0.02)


def test_global_int_terrain_frame_and_acceleration_are_rejected_with_a_reason():
    home = GeodeticOrigin()
    terrain = parse_global_setpoint(11, 0b100111111000, 0, 0, 3.0, (0, 0, 0), 0.0, 0.0, home)
    assert terrain.setpoint is None and "global frame 11 unsupported" in terrain.reason
    accel = parse_global_setpoint(6, 0b100000111000, 0, 0, 3.0, (0, 0, 0), 0.0, 0.0, home)
    assert accel.setpoint is None and "acceleration" in accel.reason


def test_global_int_relative_altitude_counts_from_home_not_the_origin():
    home = GeodeticOrigin()
    lat, lon = round(home.lat_deg * 1e7), round(home.lon_deg * 1e7)
    result = parse_global_setpoint(
        6, 0b100111111000, lat, lon, 3.0, (0, 0, 0), 0.0, 0.0, home, home_above_origin_m=1.0
    )
    assert result.setpoint.pos_ned_m == pytest.approx((0.0, 0.0, -4.0), abs=1e-6)
