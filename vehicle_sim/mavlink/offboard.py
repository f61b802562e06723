"""SET_POSITION_TARGET_LOCAL_NED -> VelocitySetpoint, with PX4's frame and type_mask rules.

type_mask bits (1 = ignore): 0-2 position, 3-5 velocity, 6-8 acceleration, 9 force, 10 yaw,
11 yaw rate. Frames: 1 LOCAL_NED (as given), 8 BODY_NED (velocity in body axes, rotated by yaw).
Velocity setpoints, position setpoints and position + velocity feed-forward (each with yaw or
yaw rate) are flown; acceleration, force and partial setpoints are rejected with a reason a
STATUSTEXT can carry. The value limits are the vehicle's one set of setpoint
rules, :func:`vehicle_sim.vehicle_types.check_setpoint`. SET_POSITION_TARGET_GLOBAL_INT
(frames 5/6, and the float-named 0/3) is mapped to local NED around home and then follows the
same rules. Pure: no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.geodetic import GeodeticOrigin
from vehicle_sim.vehicle_types import VelocitySetpoint, check_setpoint

FRAME_LOCAL_NED = mavlink2.MAV_FRAME_LOCAL_NED
FRAME_BODY_NED = mavlink2.MAV_FRAME_BODY_NED
SUPPORTED_FRAMES: dict[int, str] = {FRAME_LOCAL_NED: "ned", FRAME_BODY_NED: "body"}

IGNORE_POSITION = (
    mavlink2.POSITION_TARGET_TYPEMASK_X_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_Y_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_Z_IGNORE
)
IGNORE_VELOCITY = (
    mavlink2.POSITION_TARGET_TYPEMASK_VX_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_VY_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_VZ_IGNORE
)
IGNORE_ACCELERATION = (
    mavlink2.POSITION_TARGET_TYPEMASK_AX_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_AY_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_AZ_IGNORE
)
IGNORE_YAW = mavlink2.POSITION_TARGET_TYPEMASK_YAW_IGNORE
IGNORE_YAW_RATE = mavlink2.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE


@dataclass(frozen=True)
class SetpointResult:
    """Outcome of parsing one setpoint message.

    Attributes:
        setpoint: the velocity setpoint to fly, or None when rejected.
        reason: why it was rejected ("" when accepted), short enough for a STATUSTEXT.
    """

    setpoint: VelocitySetpoint | None
    reason: str = ""


def parse_setpoint(
    coordinate_frame: int,
    type_mask: int,
    vel_mps: tuple[float, float, float],
    yaw_rad: float,
    yaw_rate_radps: float,
    pos_ned_m: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> SetpointResult:
    """Validate a SET_POSITION_TARGET_LOCAL_NED's fields (SI units) and build the setpoint:
    velocity, position, or position with velocity feed-forward ([PX4-PositionControl])."""
    if coordinate_frame not in SUPPORTED_FRAMES:
        return SetpointResult(None, f"Offboard: frame {coordinate_frame} unsupported, use 1 or 8")
    if (type_mask & IGNORE_ACCELERATION) != IGNORE_ACCELERATION:
        return SetpointResult(
            None, "Offboard: acceleration setpoints unsupported; send velocity or position"
        )
    position = (type_mask & IGNORE_POSITION) == 0
    velocity = (type_mask & IGNORE_VELOCITY) == 0
    partial = (type_mask & IGNORE_POSITION) not in (0, IGNORE_POSITION) or (
        type_mask & IGNORE_VELOCITY
    ) not in (0, IGNORE_VELOCITY)
    if partial or not (position or velocity):
        return SetpointResult(
            None, "Offboard: send all 3 velocity components, all 3 position ones, or both"
        )
    if position and SUPPORTED_FRAMES[coordinate_frame] != "ned":
        return SetpointResult(None, "Offboard: position setpoints need frame 1 (LOCAL_NED)")
    use_yaw = not type_mask & IGNORE_YAW
    use_yaw_rate = not type_mask & IGNORE_YAW_RATE
    setpoint = VelocitySetpoint(
        vel_mps=tuple(float(v) for v in vel_mps) if velocity else (0.0, 0.0, 0.0),  # type: ignore[arg-type]
        yaw_rate_radps=float(yaw_rate_radps) if use_yaw_rate else 0.0,
        yaw_rad=float(yaw_rad) if use_yaw else None,
        frame=SUPPORTED_FRAMES[coordinate_frame],  # type: ignore[arg-type]
        pos_ned_m=tuple(float(v) for v in pos_ned_m) if position else None,  # type: ignore[arg-type]
    )
    try:
        check_setpoint(setpoint)
    except ValueError as exc:
        return SetpointResult(None, f"Offboard: {exc}")
    return SetpointResult(setpoint)


# SET_POSITION_TARGET_GLOBAL_INT frames: value -> altitude is relative to home (True) or AMSL.
GLOBAL_FRAMES: dict[int, bool] = {
    mavlink2.MAV_FRAME_GLOBAL: False,
    mavlink2.MAV_FRAME_GLOBAL_INT: False,
    mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT: True,
    mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: True,
}


def parse_global_setpoint(
    coordinate_frame: int,
    type_mask: int,
    lat_e7: int,
    lon_e7: int,
    alt_m: float,
    vel_ned_mps: tuple[float, float, float],
    yaw_rad: float,
    yaw_rate_radps: float,
    origin: GeodeticOrigin,
    home_above_origin_m: float = 0.0,
) -> SetpointResult:
    """A SET_POSITION_TARGET_GLOBAL_INT as a local NED setpoint: latitude/longitude [degE7]
    and altitude [m] (AMSL, or above home in the relative frames) mapped around the local
    ``origin``, home being ``home_above_origin_m`` above it; velocity is NED [m/s]. Same
    type_mask rules as :func:`parse_setpoint`."""
    if coordinate_frame not in GLOBAL_FRAMES:
        return SetpointResult(
            None, f"Offboard: global frame {coordinate_frame} unsupported, use 5 or 6"
        )
    home_amsl_m = origin.alt_amsl_m + home_above_origin_m
    alt_amsl_m = float(alt_m) + (home_amsl_m if GLOBAL_FRAMES[coordinate_frame] else 0.0)
    pos_ned_m = (0.0, 0.0, 0.0)
    if (type_mask & IGNORE_POSITION) == 0:
        pos_ned_m = origin.to_local(lat_e7 / 1e7, lon_e7 / 1e7, alt_amsl_m)  # type: ignore[assignment]
    return parse_setpoint(
        FRAME_LOCAL_NED, type_mask, vel_ned_mps, yaw_rad, yaw_rate_radps, pos_ned_m
    )
