"""Telemetry message builders: VehicleState (SI units) -> MAVLink messages in wire units.

Wire units (cm/s, degE7, mm, cdeg, mV) exist only here. Every builder is a pure function of the
state; ``TELEMETRY_BUILDERS`` maps a message id to its builder for streaming and REQUEST_MESSAGE.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.geodetic import GeodeticOrigin
from vehicle_sim.vehicle_types import FlightMode, VehicleState

_FACTORY = mavlink2.MAVLink(None)  # only its *_encode constructors are used (no I/O)

MAV_TYPE_QUADROTOR = mavlink2.MAV_TYPE_QUADROTOR
MAV_AUTOPILOT_PX4 = mavlink2.MAV_AUTOPILOT_PX4
MAV_STATE_STANDBY = mavlink2.MAV_STATE_STANDBY
MAV_STATE_ACTIVE = mavlink2.MAV_STATE_ACTIVE

MODE_FLAG_CUSTOM = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
MODE_FLAG_AUTO = mavlink2.MAV_MODE_FLAG_AUTO_ENABLED
MODE_FLAG_GUIDED = mavlink2.MAV_MODE_FLAG_GUIDED_ENABLED
MODE_FLAG_STABILIZE = mavlink2.MAV_MODE_FLAG_STABILIZE_ENABLED
MODE_FLAG_MANUAL_INPUT = mavlink2.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
MODE_FLAG_ARMED = mavlink2.MAV_MODE_FLAG_SAFETY_ARMED

_MODE_FLAGS: dict[FlightMode, int] = {
    FlightMode.POSCTL: MODE_FLAG_MANUAL_INPUT | MODE_FLAG_STABILIZE | MODE_FLAG_GUIDED,
    FlightMode.ALTCTL: MODE_FLAG_MANUAL_INPUT | MODE_FLAG_STABILIZE,
    FlightMode.ORBIT: MODE_FLAG_MANUAL_INPUT | MODE_FLAG_STABILIZE | MODE_FLAG_GUIDED,
}
_AUTO_FLAGS = MODE_FLAG_AUTO | MODE_FLAG_GUIDED | MODE_FLAG_STABILIZE

_SENSORS_PRESENT = (
    mavlink2.MAV_SYS_STATUS_SENSOR_3D_GYRO
    | mavlink2.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | mavlink2.MAV_SYS_STATUS_SENSOR_3D_MAG
    | mavlink2.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
    | mavlink2.MAV_SYS_STATUS_SENSOR_GPS
    | mavlink2.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
    | mavlink2.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
    | mavlink2.MAV_SYS_STATUS_SENSOR_YAW_POSITION
    | mavlink2.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
    | mavlink2.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
    | mavlink2.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
)
SENSOR_PREARM_CHECK = mavlink2.MAV_SYS_STATUS_PREARM_CHECK

# Only what the endpoint does: no SET_ATTITUDE_TARGET (attitude setpoints are rejected) and no
# MISSION_FLOAT (the float mission items are not served).
AUTOPILOT_CAPABILITIES = (
    mavlink2.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_MISSION_INT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
    | mavlink2.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
    | mavlink2.MAV_PROTOCOL_CAPABILITY_MAVLINK2
)
PX4_VERSION = (1 << 24) | (15 << 16) | (0 << 8) | 255  # v1.15.0, official release

UINT16_MAX = 65535
INT16_MAX = 32767

CELL_FULL_V = 4.2
CELL_EMPTY_V = 3.5


@dataclass(frozen=True)
class TelemetryContext:
    """What the builders need besides the state.

    Attributes:
        origin: geodetic position of the local NED origin (home).
        battery_cells: number of LiPo cells in series (for the remaining-charge estimate).
        armable: whether pre-arm checks pass (SYS_STATUS pre-arm bit).
    """

    origin: GeodeticOrigin = GeodeticOrigin()
    battery_cells: int = 4
    armable: bool = True


def battery_cells_for(voltage_v: float) -> int:
    """Cell count of a LiPo pack from its voltage when (nearly) full [V]."""
    return max(1, math.ceil(voltage_v / (CELL_FULL_V + 0.05)))


def battery_remaining_pct(voltage_v: float, cells: int) -> int:
    """Remaining charge estimate [%] from the per-cell voltage, linear 3.5 V..4.2 V."""
    frac = (voltage_v / cells - CELL_EMPTY_V) / (CELL_FULL_V - CELL_EMPTY_V)
    return int(round(100.0 * min(1.0, max(0.0, frac))))


def time_boot_ms(state: VehicleState) -> int:
    """Milliseconds since boot (= simulated time), wrapped to uint32."""
    return int(state.t_s * 1000.0) & 0xFFFFFFFF


def euler_rad(q_wxyz: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) [rad], ZYX convention, of a body-to-NED quaternion."""
    w, x, y, z = (float(v) for v in q_wxyz)
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


def base_mode(state: VehicleState) -> int:
    """HEARTBEAT base_mode bits for the state's mode and arming."""
    flags = MODE_FLAG_CUSTOM | _MODE_FLAGS.get(state.mode, _AUTO_FLAGS)
    return flags | (MODE_FLAG_ARMED if state.armed else 0)


def heartbeat(state: VehicleState, _ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    return _FACTORY.heartbeat_encode(
        type=MAV_TYPE_QUADROTOR,
        autopilot=MAV_AUTOPILOT_PX4,
        base_mode=base_mode(state),
        custom_mode=int(state.mode.value),
        system_status=MAV_STATE_ACTIVE if state.armed else MAV_STATE_STANDBY,
        mavlink_version=3,
    )


def sys_status(state: VehicleState, ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    health = _SENSORS_PRESENT | (SENSOR_PREARM_CHECK if ctx.armable else 0)
    return _FACTORY.sys_status_encode(
        onboard_control_sensors_present=_SENSORS_PRESENT | SENSOR_PREARM_CHECK,
        onboard_control_sensors_enabled=_SENSORS_PRESENT | SENSOR_PREARM_CHECK,
        onboard_control_sensors_health=health,
        load=200,
        voltage_battery=min(UINT16_MAX - 1, int(round(state.battery_v * 1000.0))),
        current_battery=-1,
        battery_remaining=battery_remaining_pct(state.battery_v, ctx.battery_cells),
        drop_rate_comm=0,
        errors_comm=0,
        errors_count1=0,
        errors_count2=0,
        errors_count3=0,
        errors_count4=0,
    )


def home_position(state: VehicleState, ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    lat_deg, lon_deg, alt_amsl_m = ctx.origin.to_global(tuple(state.home_ned_m))
    x, y, z = (float(v) for v in state.home_ned_m)
    return _FACTORY.home_position_encode(
        latitude=int(round(lat_deg * 1e7)),
        longitude=int(round(lon_deg * 1e7)),
        altitude=int(round(alt_amsl_m * 1000.0)),
        x=x,
        y=y,
        z=z,
        q=(1.0, 0.0, 0.0, 0.0),
        approach_x=0.0,
        approach_y=0.0,
        approach_z=0.0,
        time_usec=int(state.t_s * 1e6),
    )


def gps_global_origin(state: VehicleState, ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    """GPS_GLOBAL_ORIGIN: the geodetic position of local NED (0, 0, 0), which is home here,
    as PX4 SITL reports it (MAVSDK's Telemetry.get_gps_global_origin requests it)."""
    origin = ctx.origin
    return _FACTORY.gps_global_origin_encode(
        latitude=int(round(origin.lat_deg * 1e7)),
        longitude=int(round(origin.lon_deg * 1e7)),
        altitude=int(round(origin.alt_amsl_m * 1000.0)),
        time_usec=int(state.t_s * 1e6),
    )


def global_position_int(state: VehicleState, ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    lat_deg, lon_deg, alt_amsl_m = ctx.origin.to_global(tuple(state.pos_ned_m))
    vel_cmps = [int(round(float(v) * 100.0)) for v in state.vel_ned_mps]
    hdg_cdeg = int(round(math.degrees(state.yaw_rad) * 100.0)) % 36000
    return _FACTORY.global_position_int_encode(
        time_boot_ms=time_boot_ms(state),
        lat=int(round(lat_deg * 1e7)),
        lon=int(round(lon_deg * 1e7)),
        alt=int(round(alt_amsl_m * 1000.0)),
        relative_alt=int(round(-float(state.pos_ned_m[2] - state.home_ned_m[2]) * 1000.0)),
        vx=_clip_int16(vel_cmps[0]),
        vy=_clip_int16(vel_cmps[1]),
        vz=_clip_int16(vel_cmps[2]),
        hdg=hdg_cdeg,
    )


def local_position_ned(state: VehicleState, _ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    n, e, d = (float(v) for v in state.pos_ned_m)
    vn, ve, vd = (float(v) for v in state.vel_ned_mps)
    return _FACTORY.local_position_ned_encode(time_boot_ms(state), n, e, d, vn, ve, vd)


def attitude(state: VehicleState, _ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    roll, pitch, yaw = euler_rad(state.q_wxyz)
    p, q, r = (float(v) for v in state.rates_frd_radps)
    return _FACTORY.attitude_encode(time_boot_ms(state), roll, pitch, yaw, p, q, r)


def attitude_quaternion(state: VehicleState, _ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    w, x, y, z = (float(v) for v in state.q_wxyz)
    p, q, r = (float(v) for v in state.rates_frd_radps)
    return _FACTORY.attitude_quaternion_encode(time_boot_ms(state), w, x, y, z, p, q, r)


def extended_sys_state(state: VehicleState, _ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    return _FACTORY.extended_sys_state_encode(vtol_state=0, landed_state=int(state.landed_state))


def gps_raw_int(state: VehicleState, ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    lat_deg, lon_deg, alt_amsl_m = ctx.origin.to_global(tuple(state.pos_ned_m))
    vn, ve = float(state.vel_ned_mps[0]), float(state.vel_ned_mps[1])
    ground_speed_mps = math.hypot(vn, ve)
    cog_cdeg = int(round(math.degrees(math.atan2(ve, vn)) * 100.0)) % 36000
    return _FACTORY.gps_raw_int_encode(
        time_usec=int(state.t_s * 1e6),
        fix_type=3,
        lat=int(round(lat_deg * 1e7)),
        lon=int(round(lon_deg * 1e7)),
        alt=int(round(alt_amsl_m * 1000.0)),
        eph=80,
        epv=120,
        vel=min(UINT16_MAX - 1, int(round(ground_speed_mps * 100.0))),
        cog=cog_cdeg if ground_speed_mps > 0.2 else UINT16_MAX,
        satellites_visible=12,
    )


def battery_status(state: VehicleState, ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    voltages_mv = [min(UINT16_MAX - 1, int(round(state.battery_v * 1000.0)))]
    voltages_mv += [UINT16_MAX] * 9
    return _FACTORY.battery_status_encode(
        id=0,
        battery_function=1,
        type=1,
        temperature=INT16_MAX,
        voltages=voltages_mv,
        current_battery=-1,
        current_consumed=-1,
        energy_consumed=-1,
        battery_remaining=battery_remaining_pct(state.battery_v, ctx.battery_cells),
    )


def autopilot_version(_state: VehicleState, _ctx: TelemetryContext) -> mavlink2.MAVLink_message:
    return _FACTORY.autopilot_version_encode(
        capabilities=AUTOPILOT_CAPABILITIES,
        flight_sw_version=PX4_VERSION,
        middleware_sw_version=PX4_VERSION,
        os_sw_version=0,
        board_version=0,
        flight_custom_version=[0] * 8,
        middleware_custom_version=[0] * 8,
        os_custom_version=[0] * 8,
        vendor_id=0,
        product_id=0,
        uid=0x5349_4D00_0000_0001,
    )


def _clip_int16(value: int) -> int:
    return max(-INT16_MAX, min(INT16_MAX, value))


Builder = Callable[[VehicleState, TelemetryContext], mavlink2.MAVLink_message]

TELEMETRY_BUILDERS: dict[int, Builder] = {
    mavlink2.MAVLINK_MSG_ID_HEARTBEAT: heartbeat,
    mavlink2.MAVLINK_MSG_ID_SYS_STATUS: sys_status,
    mavlink2.MAVLINK_MSG_ID_HOME_POSITION: home_position,
    mavlink2.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN: gps_global_origin,
    mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: global_position_int,
    mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED: local_position_ned,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE: attitude,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: attitude_quaternion,
    mavlink2.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: extended_sys_state,
    mavlink2.MAVLINK_MSG_ID_GPS_RAW_INT: gps_raw_int,
    mavlink2.MAVLINK_MSG_ID_BATTERY_STATUS: battery_status,
    mavlink2.MAVLINK_MSG_ID_AUTOPILOT_VERSION: autopilot_version,
}
"""Message id -> builder, for every message the endpoint can stream or send on request."""

DEFAULT_RATES_HZ: dict[int, float] = {
    mavlink2.MAVLINK_MSG_ID_HEARTBEAT: 1.0,
    mavlink2.MAVLINK_MSG_ID_SYS_STATUS: 1.0,
    mavlink2.MAVLINK_MSG_ID_HOME_POSITION: 0.5,
    mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 50.0,
    mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED: 50.0,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE: 50.0,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: 50.0,
    mavlink2.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 5.0,
    mavlink2.MAVLINK_MSG_ID_GPS_RAW_INT: 1.0,
    mavlink2.MAVLINK_MSG_ID_BATTERY_STATUS: 1.0,
}
"""Nominal stream rates [Hz] of simulated time (docs/mavlink_protocol.md); heartbeat >= 1 Hz."""
