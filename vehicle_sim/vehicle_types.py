"""Public value types of the simulated vehicle: its state, the setpoints it takes, its modes.

Frames as PX4: world local NED, body FRD, quaternion (w, x, y, z) body-to-NED. SI units.
These are what the in-process API returns and what the MAVLink endpoint translates to wire units.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np


class FlightMode(enum.Enum):
    """PX4 flight modes the simulator implements; values are PX4's MAVLink custom_mode."""

    POSCTL = 196608
    ALTCTL = 131072
    ORBIT = 16973824  # PX4 reports Orbit as POSCTL (main 3) sub mode ORBIT (1)
    HOLD = 50593792
    TAKEOFF = 33816576
    LAND = 100925440
    RTL = 84148224
    MISSION = 67371008
    OFFBOARD = 393216

    @classmethod
    def parse(cls, name: str) -> FlightMode:
        """Mode by case-insensitive name; a bad name raises ValueError listing the valid ones."""
        try:
            return cls[name.upper()]
        except KeyError:
            raise ValueError(
                f"unknown flight mode {name!r}; choose one of {', '.join(m.name for m in cls)}"
            ) from None


class LandedState(enum.IntEnum):
    """MAVLink MAV_LANDED_STATE values."""

    ON_GROUND = 1
    IN_AIR = 2
    TAKEOFF = 3
    LANDING = 4


SetpointFrame = Literal["ned", "body"]


@dataclass(frozen=True)
class VelocitySetpoint:
    """An offboard setpoint as an offboard app streams it: a velocity (+ yaw or yaw rate), or a
    position with the velocity as feed-forward, as PX4's position controller takes them.

    Attributes:
        vel_mps: (3,) velocity; NED for frame "ned", FRD body axes for frame "body" (horizontal
            components rotated by yaw only, as PX4 does for BODY_NED). With a position, the
            feed-forward velocity (zeros for a pure position setpoint).
        yaw_rate_radps: yaw rate [rad/s]; ignored when ``yaw_rad`` is given.
        yaw_rad: absolute yaw [rad] (NED heading), or None to use the yaw rate.
        frame: "ned" or "body" (a position setpoint is always "ned").
        pos_ned_m: (3,) local NED position to go to [m], or None for a velocity setpoint.
    """

    vel_mps: tuple[float, float, float]
    yaw_rate_radps: float = 0.0
    yaw_rad: float | None = None
    frame: SetpointFrame = "ned"
    pos_ned_m: tuple[float, float, float] | None = None


MAX_SETPOINT_SPEED_MPS = 100.0
"""Velocity components beyond this are absurd (PX4 limits flight to MPC_XY_VEL_MAX anyway)."""
MAX_SETPOINT_YAW_RATE_RADPS = 50.0
"""Yaw rates beyond this are absurd for a multirotor (PX4's MC_YAWRATE_MAX is at most 1800
deg/s, about 31 rad/s)."""
MAX_SETPOINT_POS_M = 100_000.0
"""Positions beyond 100 km of home are not local setpoints."""
MAX_SETPOINT_YAW_RAD = 4.0 * math.pi
"""Yaw angles beyond two turns either way are not headings."""


def check_setpoint(sp: VelocitySetpoint) -> None:
    """The one home of the vehicle's setpoint rules (the simulator API and the MAVLink offboard
    parser both use it): ValueError saying what is wrong and what is valid."""
    if not isinstance(sp, VelocitySetpoint):
        raise ValueError(f"expected a VelocitySetpoint, got {type(sp).__name__}")
    if sp.frame not in ("ned", "body"):
        raise ValueError(f"setpoint frame {sp.frame!r} unknown; use 'ned' or 'body'")
    try:
        vel = [float(v) for v in sp.vel_mps]
        yaw_rate = float(sp.yaw_rate_radps)
        yaw = None if sp.yaw_rad is None else float(sp.yaw_rad)
    except (TypeError, ValueError):
        raise ValueError(f"setpoint {sp!r} has non-numeric fields; give floats") from None
    limit = MAX_SETPOINT_SPEED_MPS  # (abs(NaN) <= limit and abs(inf) <= limit are False)
    if len(vel) != 3 or not (
        abs(vel[0]) <= limit and abs(vel[1]) <= limit and abs(vel[2]) <= limit
    ):
        raise ValueError(
            f"invalid velocity setpoint {sp.vel_mps!r} rejected: need 3 finite values within "
            f"+-{MAX_SETPOINT_SPEED_MPS:g} m/s"
        )
    if not abs(yaw_rate) <= MAX_SETPOINT_YAW_RATE_RADPS:
        raise ValueError(
            f"invalid yaw rate setpoint {sp.yaw_rate_radps!r} rejected: need a finite value "
            f"within +-{MAX_SETPOINT_YAW_RATE_RADPS:g} rad/s"
        )
    if sp.pos_ned_m is not None and (
        sp.frame != "ned"
        or len(sp.pos_ned_m) != 3
        or not all(math.isfinite(float(v)) and abs(v) <= MAX_SETPOINT_POS_M for v in sp.pos_ned_m)
    ):
        raise ValueError(
            f"invalid position setpoint {sp.pos_ned_m!r} rejected: need 3 finite NED values "
            f"within +-{MAX_SETPOINT_POS_M:g} m of home"
        )
    if yaw is not None and not (math.isfinite(yaw) and abs(yaw) <= MAX_SETPOINT_YAW_RAD):
        raise ValueError(
            f"invalid yaw setpoint {sp.yaw_rad!r} rejected: need a finite angle within "
            f"+-{MAX_SETPOINT_YAW_RAD:.1f} rad"
        )


@dataclass(frozen=True)
class CheckedSetpoint(VelocitySetpoint):
    """A :class:`VelocitySetpoint` validated once, when built (:func:`check_setpoint`; invalid
    values raise ValueError then), its numbers stored as Python floats in tuples: it cannot
    change, so the simulator takes it without validating it again. For setpoints set many
    times, e.g. a replay's logged setpoints, set at every row of every replay of a log."""

    def __post_init__(self) -> None:
        check_setpoint(self)
        floats = tuple(float(v) for v in self.vel_mps)
        object.__setattr__(self, "vel_mps", floats)
        object.__setattr__(self, "yaw_rate_radps", float(self.yaw_rate_radps))
        if self.yaw_rad is not None:
            object.__setattr__(self, "yaw_rad", float(self.yaw_rad))
        object.__setattr__(self, "frame", "ned" if self.frame == "ned" else "body")
        if self.pos_ned_m is not None:
            object.__setattr__(self, "pos_ned_m", tuple(float(v) for v in self.pos_ned_m))


@dataclass(frozen=True)
class VehicleState:
    """True state of the simulated vehicle at time ``t_s``.

    Attributes:
        t_s: simulated time [s].
        pos_ned_m, vel_ned_mps, acc_ned_mps2: (3,) position, velocity, acceleration in NED;
            the acceleration is the measured kinematic one (includes gravity's effect, i.e. it is
            d(vel)/dt, not specific force).
        q_wxyz: (4,) attitude quaternion, body-to-NED.
        rates_frd_radps: (3,) body angular rates.
        thrust_n: total rotor thrust [N].
        motor_speeds_norm: (4,) normalised motor outputs in [0, 1].
        battery_v: battery voltage [V].
        armed, mode, landed_state: the flight controller's view.
        home_ned_m: (3,) home, where the vehicle last armed, in local NED [m] (the origin
            before the first arming), as PX4 reports it in HOME_POSITION.
    """

    t_s: float
    pos_ned_m: np.ndarray
    vel_ned_mps: np.ndarray
    acc_ned_mps2: np.ndarray
    q_wxyz: np.ndarray
    rates_frd_radps: np.ndarray
    thrust_n: float
    motor_speeds_norm: np.ndarray
    battery_v: float
    armed: bool
    mode: FlightMode
    landed_state: LandedState
    home_ned_m: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def home_alt_amsl_offset_m(self) -> float:
        """Height of home above the local origin [m]: add it to the origin's AMSL altitude to
        get home's (relative-altitude MAVLink frames count from home)."""
        return -float(self.home_ned_m[2])

    @property
    def yaw_rad(self) -> float:
        w, x, y, z = self.q_wxyz
        return float(np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))
