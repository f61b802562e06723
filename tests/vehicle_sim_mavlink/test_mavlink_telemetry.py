"""Telemetry builders: SI state -> wire units, as a MAVLink client decodes them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.codec import LinkCodec
from vehicle_sim.mavlink.geodetic import EARTH_RADIUS_M, GeodeticOrigin
from vehicle_sim.mavlink.telemetry import (
    TELEMETRY_BUILDERS,
    TelemetryContext,
    battery_cells_for,
    battery_remaining_pct,
)
from vehicle_sim.vehicle_types import FlightMode, LandedState, VehicleState

YAW_RAD = math.radians(100.0)


def make_state(**overrides) -> VehicleState:
    values = dict(
        t_s=12.345,
        pos_ned_m=np.array([10.0, -20.0, -5.0]),
        vel_ned_mps=np.array([1.25, -0.5, -0.75]),
        acc_ned_mps2=np.zeros(3),
        q_wxyz=np.array([math.cos(YAW_RAD / 2), 0.0, 0.0, math.sin(YAW_RAD / 2)]),
        rates_frd_radps=np.array([0.1, -0.2, 0.3]),
        thrust_n=14.7,
        motor_speeds_norm=np.full(4, 0.5),
        battery_v=15.4,
        armed=True,
        mode=FlightMode.OFFBOARD,
        landed_state=LandedState.IN_AIR,
    )
    values.update(overrides)
    return VehicleState(**values)


def on_the_wire(msg_id: int, state: VehicleState, ctx: TelemetryContext | None = None):
    data = LinkCodec().encode(TELEMETRY_BUILDERS[msg_id](state, ctx or TelemetryContext()))
    return mavlink2.MAVLink(None).parse_buffer(data)[0]


def test_heartbeat_px4_offboard_armed():
    hb = on_the_wire(mavlink2.MAVLINK_MSG_ID_HEARTBEAT, make_state())
    assert (hb.type, hb.autopilot, hb.custom_mode, hb.system_status) == (2, 12, 393216, 4)
    assert hb.base_mode == 29 + 128


def test_heartbeat_disarmed_hold_is_standby():
    hb = on_the_wire(
        mavlink2.MAVLINK_MSG_ID_HEARTBEAT, make_state(armed=False, mode=FlightMode.HOLD)
    )
    assert (hb.base_mode & 128, hb.custom_mode, hb.system_status) == (0, 50593792, 3)


def test_global_position_int_wire_units():
    origin = GeodeticOrigin()
    msg = on_the_wire(mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, make_state())
    assert msg.time_boot_ms == 12345
    assert (msg.vx, msg.vy, msg.vz) == (125, -50, -75)
    assert msg.relative_alt == 5000
    assert msg.alt == int((origin.alt_amsl_m + 5.0) * 1000)
    north_m = math.radians((msg.lat * 1e-7) - origin.lat_deg) * EARTH_RADIUS_M
    east_m = (
        math.radians((msg.lon * 1e-7) - origin.lon_deg)
        * EARTH_RADIUS_M
        * math.cos(math.radians(origin.lat_deg))
    )
    assert (north_m, east_m) == (pytest.approx(10.0, abs=0.02), pytest.approx(-20.0, abs=0.02))
    assert msg.hdg == 10000


def test_local_position_and_attitude_in_si():
    state = make_state()
    local = on_the_wire(mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED, state)
    assert (local.x, local.y, local.z, local.vz) == pytest.approx((10.0, -20.0, -5.0, -0.75))
    att = on_the_wire(mavlink2.MAVLINK_MSG_ID_ATTITUDE, state)
    assert (att.roll, att.pitch, att.yaw) == pytest.approx((0.0, 0.0, YAW_RAD), abs=1e-6)
    assert (att.rollspeed, att.pitchspeed, att.yawspeed) == pytest.approx((0.1, -0.2, 0.3))
    quat = on_the_wire(mavlink2.MAVLINK_MSG_ID_ATTITUDE_QUATERNION, state)
    assert (quat.q1, quat.q4) == pytest.approx((math.cos(YAW_RAD / 2), math.sin(YAW_RAD / 2)))


def test_sys_status_health_and_battery():
    ctx = TelemetryContext(battery_cells=4)
    msg = on_the_wire(mavlink2.MAVLINK_MSG_ID_SYS_STATUS, make_state(), ctx)
    gyro_accel_mag_baro_gps = 1 | 2 | 4 | 8 | 32
    for bits in (msg.onboard_control_sensors_present, msg.onboard_control_sensors_health):
        assert bits & gyro_accel_mag_baro_gps == gyro_accel_mag_baro_gps
    assert msg.onboard_control_sensors_health & (1 << 28)
    assert msg.voltage_battery == 15400
    assert msg.battery_remaining == battery_remaining_pct(15.4, 4) == 50


def test_extended_sys_state_and_gps():
    state = make_state(landed_state=LandedState.LANDING)
    assert on_the_wire(mavlink2.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, state).landed_state == 4
    gps = on_the_wire(mavlink2.MAVLINK_MSG_ID_GPS_RAW_INT, state)
    assert gps.fix_type == 3 and gps.satellites_visible >= 10
    assert gps.vel == round(math.hypot(1.25, -0.5) * 100)


@pytest.mark.parametrize(("full_v", "cells"), [(12.6, 3), (16.8, 4), (25.2, 6), (16.2, 4)])
def test_battery_cells_from_full_voltage(full_v, cells):
    assert battery_cells_for(full_v) == cells


def test_every_builder_encodes():
    state = make_state()
    for msg_id in TELEMETRY_BUILDERS:
        assert on_the_wire(msg_id, state).get_msgId() == msg_id


def test_home_position_is_where_the_vehicle_armed_and_relative_alt_counts_from_it():
    home_ned_m = np.array([12.0, -7.0, -1.5])
    state = make_state(home_ned_m=home_ned_m, pos_ned_m=np.array([12.0, -7.0, -4.0]))
    ctx = TelemetryContext()
    home = on_the_wire(mavlink2.MAVLINK_MSG_ID_HOME_POSITION, state, ctx)
    lat, lon, alt = ctx.origin.to_global(tuple(home_ned_m))
    assert (home.latitude, home.longitude) == (round(lat * 1e7), round(lon * 1e7))
    assert home.altitude == round(alt * 1000.0)
    assert (home.x, home.y, home.z) == pytest.approx(tuple(home_ned_m))
    position = on_the_wire(mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, state, ctx)
    assert position.relative_alt == 2500  # 2.5 m above home, 4 m above the origin
