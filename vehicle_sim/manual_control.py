"""Stick input of a pilot (RC or a MAVLink joystick) and what PX4's manual modes make of it.

Sticks are normalised as PX4's manual_control_setpoint: ``x`` forward (pitch), ``y`` right
(roll), ``r`` yaw, each in [-1, 1]; ``z`` throttle in [0, 1] with 0.5 the centre. PX4's
FlightTaskManualAltitude / FlightTaskManualPosition (MPC_POS_MODE 0, sticks to velocity) turn
them into setpoints ([PX4-params]; Sticks.cpp of flight_mode_manager):

- each axis goes through ``expo(deadzone(v, MAN_DEADZONE), E)``, with
  ``deadzone(v, d) = (v - sign(v) d) / (1 - d)`` outside the deadzone and 0 inside, and
  ``expo(v, e) = (1 - e) v + e v^3``; E is MPC_XY_MAN_EXPO for x/y, MPC_Z_MAN_EXPO for the
  throttle (first rescaled to [-1, 1], up positive), MPC_YAW_EXPO for yaw;
- x/y times MPC_VEL_MANUAL [m/s] is the horizontal velocity in the heading frame (the pair
  limited to unit length first, so a diagonal stick is not faster);
- the throttle times MPC_Z_VEL_MAX_UP (up) or MPC_Z_VEL_MAX_DN (down) [m/s] is the vertical
  velocity;
- yaw times MPC_MAN_Y_MAX [deg/s] is the yaw rate.

A stick inside its deadzone commands nothing on its axis: the vehicle brakes and then holds
position / altitude / heading there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from vehicle_sim.params import Px4Params


@dataclass(frozen=True)
class Sticks:
    """One stick reading, normalised as PX4's manual_control_setpoint.

    Attributes:
        x: forward (pitch stick) in [-1, 1].
        y: right (roll stick) in [-1, 1].
        z: throttle in [0, 1]; 0.5 is the centre (hold altitude).
        r: yaw stick in [-1, 1], positive clockwise seen from above.
    """

    x: float
    y: float
    z: float
    r: float


CENTRED = Sticks(0.0, 0.0, 0.5, 0.0)


def check_sticks(sticks: Sticks) -> None:
    """ValueError naming the axis when a stick value is not finite or outside its range."""
    ranges = (("x", -1.0, 1.0), ("y", -1.0, 1.0), ("z", 0.0, 1.0), ("r", -1.0, 1.0))
    for name, lo, hi in ranges:
        value = getattr(sticks, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"stick {name} must be a number, got {value!r}")
        if not lo <= value <= hi:  # (False for NaN)
            raise ValueError(f"stick {name} = {value!r} must be within [{lo:g}, {hi:g}]")


def deadzone(value: float, zone: float) -> float:
    """PX4's math::deadzone: 0 within ``zone`` of 0, else rescaled so that +-1 stays +-1."""
    if abs(value) <= zone:
        return 0.0
    return (value - math.copysign(zone, value)) / (1.0 - zone)


def expo(value: float, e: float) -> float:
    """PX4's math::expo: ``(1 - e) v + e v^3`` on ``v`` limited to [-1, 1]."""
    v = min(max(value, -1.0), 1.0)
    return (1.0 - e) * v + e * v * v * v


def expo_deadzone(value: float, e: float, zone: float) -> float:
    """PX4's math::expo_deadzone: the deadzone first, then the expo."""
    return expo(deadzone(value, zone), e)


@dataclass(frozen=True)
class StickCommand:
    """What the sticks command in POSCTL / ALTCTL.

    Attributes:
        forward_mps, right_mps: horizontal velocity in the heading frame [m/s].
        down_mps: vertical velocity, NED (negative climbs) [m/s].
        yaw_rate_radps: yaw rate [rad/s].
    """

    forward_mps: float
    right_mps: float
    down_mps: float
    yaw_rate_radps: float

    @property
    def horizontal(self) -> bool:
        """Whether the horizontal sticks are out of their deadzone."""
        return self.forward_mps != 0.0 or self.right_mps != 0.0


def stick_command(sticks: Sticks, params: Px4Params) -> StickCommand:
    """The setpoint PX4's manual position / altitude task makes of ``sticks`` (see the module
    docstring for the formulas)."""
    p = params.get
    zone = p("MAN_DEADZONE")
    xy_e, z_e, yaw_e = p("MPC_XY_MAN_EXPO"), p("MPC_Z_MAN_EXPO"), p("MPC_YAW_EXPO")
    fwd = expo_deadzone(sticks.x, xy_e, zone)
    right = expo_deadzone(sticks.y, xy_e, zone)
    length = math.hypot(fwd, right)
    if length > 1.0:
        fwd, right = fwd / length, right / length
    up = expo_deadzone((sticks.z - 0.5) * 2.0, z_e, zone)
    climb_mps = up * (p("MPC_Z_VEL_MAX_UP") if up > 0.0 else p("MPC_Z_VEL_MAX_DN"))
    yaw = expo_deadzone(sticks.r, yaw_e, zone)
    speed = p("MPC_VEL_MANUAL")
    return StickCommand(
        forward_mps=fwd * speed,
        right_mps=right * speed,
        down_mps=-climb_mps + 0.0,  # (+0.0: no negative zero)
        yaw_rate_radps=math.radians(yaw * p("MPC_MAN_Y_MAX")),
    )


STICK_MOTION_TAU_S = 0.1  # time constant of PX4's MovingDiff low-pass [s]


class StickMotion:
    """How fast the sticks move, as PX4's stick-override check measures it (manual_control's
    MovingDiff per axis): each axis's rate of change [full travel per s; the throttle over
    [-1, 1], as PX4 scales it], low-passed with a time constant of STICK_MOTION_TAU_S.

    A stick held still, however far from centre, does not move: PX4 overrides an auto mode or
    OFFBOARD only when the pilot moves a stick faster than COM_RC_STICK_OV [%] of its travel
    per second. The first reading (also after :meth:`reset`) only says where the sticks are,
    as MovingDiff leaves its difference at 0 without a last value: a joystick that connects,
    or comes back after a loss, with a stick off centre moves nothing until that stick moves.
    """

    def __init__(self) -> None:
        self._last: tuple[float, float, float, float] | None = None
        self._rate = [0.0, 0.0, 0.0, 0.0]

    def reset(self) -> None:
        """Forget the sticks (they were lost): the next reading is a first one again."""
        self.__init__()

    def update(self, sticks: Sticks, dt_s: float) -> float:
        """Take a reading ``dt_s`` [s] (>= 0) after the previous one; return the largest
        filtered rate [1/s] over the axes. The low-pass step ``r += (d/dt - r) dt/(tau+dt)`` is
        written as ``r tau/(tau+dt) + d/(tau+dt)``, which also holds for dt = 0."""
        axes = _axes(sticks)
        tau = STICK_MOTION_TAU_S
        if self._last is not None:
            for i, (value, last) in enumerate(zip(axes, self._last, strict=True)):
                self._rate[i] = (self._rate[i] * tau + (value - last)) / (tau + dt_s)
        self._last = axes
        return max(abs(rate) for rate in self._rate)


def _axes(sticks: Sticks) -> tuple[float, float, float, float]:
    """x, y, r in [-1, 1] and the throttle rescaled to [-1, 1] (PX4's manual_control_setpoint)."""
    return (sticks.x, sticks.y, sticks.r, 2.0 * sticks.z - 1.0)
