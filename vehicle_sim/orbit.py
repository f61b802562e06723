"""PX4's Orbit mode (FlightTaskOrbit, MAV_CMD_DO_ORBIT): circle a centre at a radius and speed.

The horizontal velocity setpoint is PX4's: the tangent at the orbit speed plus the radial error
(radius minus distance, [m] taken as [m/s], i.e. a gain of 1/s) towards the circle, the radial
part limited to MPC_XY_CRUISE so that a vehicle far from the circle approaches it at cruise
speed (PX4 flies a straight line to the circle first), with the centripetal acceleration
v^2/r fed forward. PX4 feeds the yaw rate v/r forward too; the simulated flight control takes
no yaw rate with a yaw setpoint, so the yaw setpoint leads by (v/r) / MC_YAW_P instead (the
lag of its yaw loop). The altitude is held. A positive radius
(or velocity) orbits clockwise seen from above. As PX4's setRadius/setVelocity: the radius is
kept within [1 m, MC_ORBIT_RAD_MAX], the speed below MPC_XY_VEL_MAX and below the speed whose
centripetal acceleration v^2/r reaches MPC_ACC_HOR ("small radius is more important than high
velocity"). Yaw (ORBIT_YAW_BEHAVIOUR, default MC_ORBIT_YAW_MOD): 0 front to the centre,
1 the heading when the orbit was commanded, 2 uncontrolled, 3 front along the tangent,
4 the yaw stick; 5 (UNCHANGED) in a command keeps the behaviour flown, as NaN does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from vehicle_sim.params import Px4Params

RADIUS_MIN_M = 1.0  # PX4's FlightTaskOrbit _radius_min
DEFAULT_VELOCITY_MPS = 1.0  # PX4's orbit speed before one is commanded
YAW_FRONT_TO_CENTRE, YAW_INITIAL, YAW_UNCONTROLLED, YAW_TANGENT, YAW_STICK = 0, 1, 2, 3, 4
YAW_UNCHANGED = 5  # ORBIT_YAW_BEHAVIOUR_UNCHANGED: a command keeps the behaviour flown
ACCEL_MARGIN = 0.99  # the limited speed sits just inside PX4's strict v^2 < a r


@dataclass(frozen=True)
class Orbit:
    """One orbit being flown.

    Attributes:
        centre_ne_m: (north, east) of the centre in local NED [m].
        down_m: the altitude held, local NED down [m].
        radius_m: radius [m], > 0.
        velocity_mps: tangential speed [m/s]; positive clockwise seen from above.
        yaw_behaviour: ORBIT_YAW_BEHAVIOUR 0-4.
        initial_yaw_rad: heading when the orbit was commanded [rad] (behaviour 1).
    """

    centre_ne_m: tuple[float, float]
    down_m: float
    radius_m: float
    velocity_mps: float
    yaw_behaviour: int
    initial_yaw_rad: float


def limit_orbit(
    radius_m: float, velocity_mps: float, params: Px4Params
) -> tuple[float, float, str]:
    """(radius [m], signed speed [m/s], a one-line note of what was limited, or "") within
    PX4's bounds (see the module docstring)."""
    notes = []
    radius_max = params.get("MC_ORBIT_RAD_MAX")
    radius = min(max(radius_m, RADIUS_MIN_M), radius_max)
    if radius != radius_m:
        notes.append(f"radius {radius_m:g} m limited to {radius:g} m")
    speed_max = min(
        params.get("MPC_XY_VEL_MAX"),
        ACCEL_MARGIN * math.sqrt(params.get("MPC_ACC_HOR") * radius),
    )
    speed = min(abs(velocity_mps), speed_max)
    if speed != abs(velocity_mps):
        notes.append(f"speed {abs(velocity_mps):g} m/s limited to {speed:.2f} m/s")
    note = f"Orbit: {', '.join(notes)}" if notes else ""
    return radius, math.copysign(speed, velocity_mps), note


@dataclass(frozen=True)
class OrbitSetpoint:
    """What the orbit commands now: horizontal velocity NED [m/s], acceleration feed-forward
    NED [m/s^2] and yaw [rad] (NaN: the yaw is not set by the orbit; hold it, or follow the yaw
    stick)."""

    vel_ne_mps: tuple[float, float]
    acc_ne_mps2: tuple[float, float]
    yaw_rad: float


def orbit_setpoint(orbit: Orbit, pos_ne_m: tuple[float, float], params: Px4Params) -> OrbitSetpoint:
    """The orbit's setpoint at horizontal position ``pos_ne_m`` [m] (see the module docstring
    for the formulas and the parameters read)."""
    dn = pos_ne_m[0] - orbit.centre_ne_m[0]
    de = pos_ne_m[1] - orbit.centre_ne_m[1]
    distance = math.hypot(dn, de)
    if distance < 1e-6:  # at the centre: leave north first
        dn, de, distance = 1e-6, 0.0, 1e-6
    un, ue = dn / distance, de / distance  # radial unit, outwards
    v = orbit.velocity_mps
    cruise = params.get("MPC_XY_CRUISE")
    radial = min(max(orbit.radius_m - distance, -cruise), cruise)
    vel = (-ue * v + un * radial, un * v + ue * radial)  # clockwise tangent of (n, e): (-e, n)
    centripetal = v * v / orbit.radius_m
    acc = (-un * centripetal, -ue * centripetal)
    lead = v / orbit.radius_m / params.get("MC_YAW_P")  # [rad], clockwise positive
    behaviour = orbit.yaw_behaviour
    if behaviour == YAW_INITIAL:
        yaw = orbit.initial_yaw_rad
    elif behaviour == YAW_TANGENT:
        yaw = math.atan2(math.copysign(1.0, v) * un, -math.copysign(1.0, v) * ue) + lead
    elif behaviour in (YAW_UNCONTROLLED, YAW_STICK):
        yaw = math.nan
    else:
        yaw = math.atan2(-ue, -un) + lead
    return OrbitSetpoint(vel, acc, yaw)
