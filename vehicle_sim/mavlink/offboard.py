"""SET_POSITION_TARGET_LOCAL_NED -> VelocitySetpoint, with PX4's frame and type_mask rules.

type_mask bits (1 = ignore): 0-2 position, 3-5 velocity, 6-8 acceleration, 9 force, 10 yaw,
11 yaw rate. Frames: 1 LOCAL_NED (as given), 8 BODY_NED (velocity in body axes, rotated by yaw).
Only velocity setpoints (optionally with yaw or yaw rate) are flown; anything else is rejected
with a reason a STATUSTEXT can carry. The value limits are the vehicle's one set of setpoint
rules, :func:`vehicle_sim.vehicle_types.check_setpoint`. Pure: no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink2

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
) -> SetpointResult:
    """Validate a SET_POSITION_TARGET_LOCAL_NED's fields (SI units) and build the setpoint."""
    if coordinate_frame not in SUPPORTED_FRAMES:
        return SetpointResult(None, f"Offboard: frame {coordinate_frame} unsupported, use 1 or 8")
    if type_mask & IGNORE_VELOCITY:
        return SetpointResult(None, "Offboard: only velocity setpoints supported")
    if (type_mask & IGNORE_POSITION) != IGNORE_POSITION or (
        type_mask & IGNORE_ACCELERATION
    ) != IGNORE_ACCELERATION:
        return SetpointResult(None, "Offboard: position/accel setpoints unsupported")
    use_yaw = not type_mask & IGNORE_YAW
    use_yaw_rate = not type_mask & IGNORE_YAW_RATE
    setpoint = VelocitySetpoint(
        vel_mps=tuple(float(v) for v in vel_mps),  # type: ignore[arg-type]
        yaw_rate_radps=float(yaw_rate_radps) if use_yaw_rate else 0.0,
        yaw_rad=float(yaw_rad) if use_yaw else None,
        frame=SUPPORTED_FRAMES[coordinate_frame],  # type: ignore[arg-type]
    )
    try:
        check_setpoint(setpoint)
    except ValueError as exc:
        return SetpointResult(None, f"Offboard: {exc}")
    return SetpointResult(setpoint)
