"""PX4-named parameters of the simulated flight controller, with PX4's types, defaults, bounds.

Values are held as floats in PX4's own units (angles in degrees where PX4 uses degrees); INT32
parameters hold whole numbers. A setting outside PX4's bounds or of the wrong kind is refused,
as PX4 refuses it. The order of
:meth:`Px4Params.names` is stable (alphabetical, as PX4 lists them), so it can serve as the
PARAM_VALUE index.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Literal, TypeVar

import numpy as np

from vehicle_sim import flight_control as fc

T = TypeVar("T")

ParamType = Literal["FLOAT", "INT32"]


@dataclass(frozen=True)
class Px4ParamSpec:
    """One PX4 parameter as PX4's parameter metadata defines it ([PX4-params]).

    Attributes:
        default: PX4's default, in PX4's units.
        doc: what it is, with its unit.
        lo, hi: PX4's inclusive bounds (infinite where PX4 gives none).
        type: "FLOAT" (MAV_PARAM_TYPE_REAL32) or "INT32" (MAV_PARAM_TYPE_INT32).
    """

    default: float
    doc: str
    lo: float = -math.inf
    hi: float = math.inf
    type: ParamType = "FLOAT"

    def check(self, name: str, value: float) -> None:
        """ValueError naming the rule when ``value`` is not a valid setting."""
        if not math.isfinite(value):
            raise ValueError(f"parameter {name}: {value!r} is not finite; give a finite number")
        if self.type == "INT32" and value != int(value):
            raise ValueError(f"parameter {name} is INT32; {value!r} is not a whole number")
        if not self.lo <= value <= self.hi:
            raise ValueError(
                f"parameter {name}: {value:g} is outside PX4's range [{self.lo:g}, {self.hi:g}]"
            )


_F = Px4ParamSpec


def _i(default: int, doc: str, lo: float, hi: float) -> Px4ParamSpec:
    return Px4ParamSpec(float(default), doc, lo, hi, "INT32")


# PX4's names, types, defaults and bounds (PX4 v1.14 parameter metadata, [PX4-params]); the
# modules defining them: commander (COM_*), navigator (NAV_*, MIS_*, RTL_*), mc_pos_control
# (MPC_*), mc_att_control (MC_*_P, MC_*RATE_MAX), mc_rate_control (MC_*RATE_*), battery (BAT*),
# mavlink (MAV_*), manual_control (MAN_DEADZONE) and the airframe system (SYS_*). The stick
# parameters (COM_RC_*, NAV_RCL_ACT, MAN_DEADZONE, MPC_VEL_MANUAL, MPC_MAN_Y_MAX, MPC_*_EXPO)
# are those of PX4's parameter reference (docs.px4.io, "Parameter Reference") for v1.15.
PX4_PARAMS: dict[str, Px4ParamSpec] = {
    "BAT1_N_CELLS": _i(4, "cells in series of battery 1 (the simulated pack)", 0, 16),
    "BAT_CRIT_THR": _F(0.07, "critical battery level, fraction of capacity", 0.05, 0.5),
    "BAT_EMERGEN_THR": _F(0.05, "emergency battery level, fraction of capacity", 0.03, 0.5),
    "BAT_LOW_THR": _F(0.15, "low battery level, fraction of capacity", 0.12, 0.5),
    "COM_DISARM_LAND": _F(2.0, "disarm this long after landing [s], <= 0 disables", -1.0, 20.0),
    "COM_DISARM_PRFLT": _F(10.0, "disarm after arming without takeoff [s], <= 0 off", -1.0, 20.0),
    "COM_DL_LOSS_T": _i(10, "data-link loss time threshold [s]", 5, 300),
    "COM_FAIL_ACT_T": _F(5.0, "hold this long before a failsafe action [s]", 0.0, 25.0),
    "COM_LOW_BAT_ACT": _i(0, "battery failsafe: 0 warn, 2 land, 3 RTL then land", 0, 3),
    "COM_OBL_RC_ACT": _i(0, "offboard-loss action: 0-3, 5 hold, 4 land", 0, 7),
    "COM_OF_LOSS_T": _F(1.0, "offboard setpoint timeout [s]", 0.0, 60.0),
    "COM_RC_IN_MODE": _i(3, "manual control input: 0 RC, 1 joystick, 2-3 either, 4 none", 0, 4),
    "COM_RC_LOSS_T": _F(0.5, "manual control (RC or joystick) loss timeout [s]", 0.0, 35.0),
    "COM_RCL_EXCEPT": _i(
        0, "manual control loss ignored in: bit 0 mission, 1 hold/takeoff, 2 offboard", 0, 7
    ),
    "COM_RC_OVERRIDE": _i(1, "stick override bits: 0 auto modes, 1 offboard", 0, 3),
    "COM_RC_STICK_OV": _F(
        30.0, "stick motion that overrides auto/offboard [% of travel/s]", 5.0, 80.0
    ),
    "MAN_DEADZONE": _F(0.1, "stick deadzone around centre, fraction of full deflection", 0.0, 1.0),
    "MAV_SYS_ID": _i(1, "MAVLink system id", 1, 250),
    "MC_ORBIT_RAD_MAX": _F(1000.0, "max orbit radius (MAV_CMD_DO_ORBIT) [m]", 1.0, 10000.0),
    "MC_ORBIT_YAW_MOD": _i(
        0, "orbit yaw: 0 to centre, 1 initial, 2 free, 3 tangent, 4 stick", 0, 4
    ),
    "MC_PITCHRATE_D": _F(0.003, "pitch rate D [1/(rad/s^2)]", 0.0),
    "MC_PITCHRATE_I": _F(0.2, "pitch rate I", 0.0),
    "MC_PITCHRATE_MAX": _F(220.0, "max pitch rate [deg/s]", 0.0, 1800.0),
    "MC_PITCHRATE_P": _F(0.15, "pitch rate P", 0.01, 0.6),
    "MC_PITCH_P": _F(6.5, "pitch attitude P [1/s]", 0.0, 12.0),
    "MC_PR_INT_LIM": _F(0.3, "pitch rate integrator limit", 0.0),
    "MC_ROLLRATE_D": _F(0.003, "roll rate D", 0.0),
    "MC_ROLLRATE_I": _F(0.2, "roll rate I", 0.0),
    "MC_ROLLRATE_MAX": _F(220.0, "max roll rate [deg/s]", 0.0, 1800.0),
    "MC_ROLLRATE_P": _F(0.15, "roll rate P", 0.01, 0.5),
    "MC_ROLL_P": _F(6.5, "roll attitude P [1/s]", 0.0, 12.0),
    "MC_RR_INT_LIM": _F(0.3, "roll rate integrator limit", 0.0),
    "MC_YAWRATE_D": _F(0.0, "yaw rate D", 0.0),
    "MC_YAWRATE_I": _F(0.1, "yaw rate I", 0.0),
    "MC_YAWRATE_MAX": _F(200.0, "max yaw rate [deg/s]", 0.0, 1800.0),
    "MC_YAWRATE_P": _F(0.2, "yaw rate P", 0.0, 0.6),
    "MC_YR_INT_LIM": _F(0.3, "yaw rate integrator limit", 0.0),
    "MC_YAW_P": _F(2.8, "yaw attitude P [1/s]", 0.0, 5.0),
    "MC_YAW_WEIGHT": _F(0.4, "yaw weight in the attitude error", 0.0, 1.0),
    "MIS_TAKEOFF_ALT": _F(2.5, "takeoff altitude above home [m]", 0.0),
    "MPC_ACC_HOR": _F(3.0, "velocity setpoint slew in auto modes [m/s^2]", 2.0, 15.0),
    "MPC_LAND_ALT1": _F(
        10.0, "above this height the landing descends at MPC_Z_V_AUTO_DN [m]", 0.0, 122.0
    ),
    "MPC_LAND_ALT2": _F(
        5.0, "below this height the landing descends at MPC_LAND_SPEED [m]", 0.0, 122.0
    ),
    "MPC_LAND_SPEED": _F(0.7, "landing descent speed near the ground [m/s]", 0.6),
    "MPC_MAN_Y_MAX": _F(150.0, "max yaw rate from the yaw stick [deg/s]", 0.0, 400.0),
    "MPC_THR_HOVER": _F(0.5, "hover thrust, normalised (set from the preset)", 0.1, 0.8),
    "MPC_THR_MAX": _F(1.0, "max collective thrust, normalised", 0.0, 1.0),
    "MPC_THR_MIN": _F(0.12, "min collective thrust in flight, normalised", 0.05, 0.5),
    "MPC_TILTMAX_AIR": _F(45.0, "max tilt [deg]", 20.0, 89.0),
    "MPC_TKO_SPEED": _F(1.5, "takeoff climb speed [m/s]", 1.0, 5.0),
    "MPC_VEL_MANUAL": _F(10.0, "max horizontal speed from the sticks in POSCTL [m/s]", 3.0, 20.0),
    "MPC_XY_CRUISE": _F(5.0, "horizontal speed in auto modes [m/s]", 3.0, 20.0),
    "MPC_XY_MAN_EXPO": _F(0.6, "expo of the horizontal sticks [1]", 0.0, 1.0),
    "MPC_XY_P": _F(0.95, "horizontal position P [1/s]", 0.0, 2.0),
    "MPC_XY_VEL_D_ACC": _F(0.2, "horizontal velocity D [1]", 0.1, 2.0),
    "MPC_XY_VEL_I_ACC": _F(0.4, "horizontal velocity I [1/s]", 0.0, 60.0),
    "MPC_XY_VEL_MAX": _F(12.0, "max horizontal speed [m/s]", 0.0, 20.0),
    "MPC_XY_VEL_P_ACC": _F(1.8, "horizontal velocity P [1/s]", 1.2, 5.0),
    "MPC_Z_P": _F(1.0, "vertical position P [1/s]", 0.0, 1.5),
    "MPC_YAW_EXPO": _F(0.6, "expo of the yaw stick [1]", 0.0, 1.0),
    "MPC_Z_MAN_EXPO": _F(0.6, "expo of the throttle stick [1]", 0.0, 1.0),
    "MPC_Z_VEL_D_ACC": _F(0.0, "vertical velocity D [1]", 0.0, 2.0),
    "MPC_Z_VEL_I_ACC": _F(2.0, "vertical velocity I [1/s]", 0.2, 3.0),
    "MPC_Z_VEL_MAX_DN": _F(1.5, "max descent speed [m/s]", 0.5, 4.0),
    "MPC_Z_VEL_MAX_UP": _F(3.0, "max climb speed [m/s]", 0.5, 8.0),
    "MPC_Z_VEL_P_ACC": _F(4.0, "vertical velocity P [1/s]", 2.0, 15.0),
    "MPC_Z_V_AUTO_DN": _F(1.5, "descent speed in auto modes [m/s]", 0.5, 4.0),
    "MPC_Z_V_AUTO_UP": _F(3.0, "climb speed in auto modes [m/s]", 0.5, 8.0),
    "NAV_DLL_ACT": _i(0, "data-link loss action: 0 off, 1 hold, 2 RTL, 3 land, 5-6", 0, 6),
    "NAV_RCL_ACT": _i(2, "manual control loss action: 1 hold, 2 RTL, 3 land, 5-6 disarm", 1, 6),
    "RTL_RETURN_ALT": _F(60.0, "return altitude above home in RTL [m]", 0.0, 150.0),
    "SYS_AUTOCONFIG": _i(0, "reset parameters on next boot: 0 keep, 1-2 reset", 0, 2),
    "SYS_AUTOSTART": _i(4001, "airframe id (4001: generic quadcopter)", 0, 9999999),
}

IDLE_THRUST_NORM = 0.05  # motor thrust while armed on the ground (PX4 idle spin)


class Px4Params:
    """The parameter set of one simulated vehicle."""

    def __init__(self, overrides: Mapping[str, float] | None = None) -> None:
        self._values = {name: spec.default for name, spec in PX4_PARAMS.items()}
        self.version = 0  # increments on every set, so users of derived vectors can refresh
        self._derived: dict[Callable[[Px4Params], object], tuple[int, object]] = {}
        for name, value in (overrides or {}).items():
            self.set(name, value)

    def __deepcopy__(self, memo: dict[int, object]) -> Px4Params:
        """An independent copy (``copy.deepcopy``; the values are immutable numbers)."""
        clone = object.__new__(type(self))
        clone._values = dict(self._values)
        clone.version = self.version
        clone._derived = {}
        memo[id(self)] = clone
        return clone

    def names(self) -> tuple[str, ...]:
        """All parameter names in a stable order."""
        return tuple(sorted(self._values))

    def get(self, name: str) -> float:
        try:
            return self._values[name]
        except KeyError:
            raise ValueError(
                f"unknown parameter {name!r}; known: {', '.join(self.names())}"
            ) from None

    def spec(self, name: str) -> Px4ParamSpec:
        """The parameter's PX4 type, default and bounds."""
        self.get(name)
        return PX4_PARAMS[name]

    def derived(self, build: Callable[[Px4Params], T]) -> T:
        """``build(self)``, built again only after a parameter set: for values read from the
        parameters at every step of a loop (kept per ``build``)."""
        kept = self._derived.get(build)
        if kept is None or kept[0] != self.version:
            kept = self._derived[build] = (self.version, build(self))
        return kept[1]

    def set(self, name: str, value: float) -> None:
        """Set one parameter; unknown names, non-numbers, non-finite values, fractions for an
        INT32 parameter and values outside PX4's bounds raise ValueError (nothing changes)."""
        spec = self.spec(name)
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise ValueError(f"parameter {name}: expected a number, got {value!r}")
        spec.check(name, float(value))
        self._values[name] = float(value)
        self.version += 1

    def control_vector(self, gravity_mps2: float) -> np.ndarray:
        """The flight-control parameter vector ``cp`` (see :mod:`vehicle_sim.flight_control`)."""
        p = self._values
        cp = np.zeros(fc.N_CP)
        cp[fc.C_VEL_P_XY] = p["MPC_XY_VEL_P_ACC"]
        cp[fc.C_VEL_I_XY] = p["MPC_XY_VEL_I_ACC"]
        cp[fc.C_VEL_D_XY] = p["MPC_XY_VEL_D_ACC"]
        cp[fc.C_VEL_P_Z] = p["MPC_Z_VEL_P_ACC"]
        cp[fc.C_VEL_I_Z] = p["MPC_Z_VEL_I_ACC"]
        cp[fc.C_VEL_D_Z] = p["MPC_Z_VEL_D_ACC"]
        cp[fc.C_POS_P_XY] = p["MPC_XY_P"]
        cp[fc.C_POS_P_Z] = p["MPC_Z_P"]
        cp[fc.C_THR_HOVER] = p["MPC_THR_HOVER"]
        cp[fc.C_THR_MIN] = p["MPC_THR_MIN"]
        cp[fc.C_THR_MAX] = p["MPC_THR_MAX"]
        cp[fc.C_ATT_P : fc.C_ATT_P + 3] = (p["MC_ROLL_P"], p["MC_PITCH_P"], p["MC_YAW_P"])
        cp[fc.C_YAW_WEIGHT] = p["MC_YAW_WEIGHT"]
        for axis, prefix in enumerate(("MC_ROLLRATE", "MC_PITCHRATE", "MC_YAWRATE")):
            cp[fc.C_RATE_P + axis] = p[prefix + "_P"]
            cp[fc.C_RATE_I + axis] = p[prefix + "_I"]
            cp[fc.C_RATE_D + axis] = p[prefix + "_D"]
            cp[fc.C_RATE_MAX + axis] = math.radians(p[prefix + "_MAX"])
        cp[fc.C_RATE_INT_LIM : fc.C_RATE_INT_LIM + 3] = (
            p["MC_RR_INT_LIM"],
            p["MC_PR_INT_LIM"],
            p["MC_YR_INT_LIM"],
        )
        cp[fc.C_IDLE] = IDLE_THRUST_NORM
        cp[fc.C_G] = gravity_mps2
        return cp
