"""PX4-named parameters of the simulated flight controller, with PX4's defaults.

Values are floats in PX4's own units (angles in degrees where PX4 uses degrees). The order of
:meth:`Px4Params.names` is stable (alphabetical, as PX4 lists them), so it can serve as the
PARAM_VALUE index.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from vehicle_sim import flight_control as fc

# name -> (default, what it is, with unit)
PX4_DEFAULTS: dict[str, tuple[float, str]] = {
    "COM_DISARM_LAND": (2.0, "disarm this long after landing [s], <= 0 disables"),
    "COM_DISARM_PRFLT": (10.0, "disarm this long after arming without takeoff [s], <= 0 disables"),
    "COM_OBL_RC_ACT": (0.0, "offboard-loss action: 0-3, 5 hold, 4 land"),
    "COM_OF_LOSS_T": (1.0, "offboard setpoint timeout [s]"),
    "MC_PITCHRATE_D": (0.003, "pitch rate D [1/(rad/s^2)]"),
    "MC_PITCHRATE_I": (0.2, "pitch rate I"),
    "MC_PITCHRATE_MAX": (220.0, "max pitch rate [deg/s]"),
    "MC_PITCHRATE_P": (0.15, "pitch rate P"),
    "MC_PITCH_P": (6.5, "pitch attitude P [1/s]"),
    "MC_PR_INT_LIM": (0.3, "pitch rate integrator limit"),
    "MC_ROLLRATE_D": (0.003, "roll rate D"),
    "MC_ROLLRATE_I": (0.2, "roll rate I"),
    "MC_ROLLRATE_MAX": (220.0, "max roll rate [deg/s]"),
    "MC_ROLLRATE_P": (0.15, "roll rate P"),
    "MC_ROLL_P": (6.5, "roll attitude P [1/s]"),
    "MC_RR_INT_LIM": (0.3, "roll rate integrator limit"),
    "MC_YAWRATE_D": (0.0, "yaw rate D"),
    "MC_YAWRATE_I": (0.1, "yaw rate I"),
    "MC_YAWRATE_MAX": (200.0, "max yaw rate [deg/s]"),
    "MC_YAWRATE_P": (0.2, "yaw rate P"),
    "MC_YR_INT_LIM": (0.3, "yaw rate integrator limit"),
    "MC_YAW_P": (2.8, "yaw attitude P [1/s]"),
    "MC_YAW_WEIGHT": (0.4, "yaw weight in the attitude error"),
    "MIS_TAKEOFF_ALT": (2.5, "takeoff altitude above home [m]"),
    "MPC_ACC_HOR": (3.0, "velocity setpoint slew in auto modes [m/s^2]"),
    "MPC_LAND_SPEED": (0.7, "landing descent speed [m/s]"),
    "MPC_THR_HOVER": (0.5, "hover thrust, normalised (set from the preset)"),
    "MPC_THR_MAX": (1.0, "max collective thrust, normalised"),
    "MPC_THR_MIN": (0.12, "min collective thrust in flight, normalised"),
    "MPC_TILTMAX_AIR": (45.0, "max tilt [deg]"),
    "MPC_TKO_SPEED": (1.5, "takeoff climb speed [m/s]"),
    "MPC_XY_CRUISE": (5.0, "horizontal speed in auto modes [m/s]"),
    "MPC_XY_P": (0.95, "horizontal position P [1/s]"),
    "MPC_XY_VEL_D_ACC": (0.2, "horizontal velocity D [1]"),
    "MPC_XY_VEL_I_ACC": (0.4, "horizontal velocity I [1/s]"),
    "MPC_XY_VEL_MAX": (12.0, "max horizontal speed [m/s]"),
    "MPC_XY_VEL_P_ACC": (1.8, "horizontal velocity P [1/s]"),
    "MPC_Z_P": (1.0, "vertical position P [1/s]"),
    "MPC_Z_VEL_D_ACC": (0.0, "vertical velocity D [1]"),
    "MPC_Z_VEL_I_ACC": (2.0, "vertical velocity I [1/s]"),
    "MPC_Z_VEL_MAX_DN": (1.5, "max descent speed [m/s]"),
    "MPC_Z_VEL_MAX_UP": (3.0, "max climb speed [m/s]"),
    "MPC_Z_VEL_P_ACC": (4.0, "vertical velocity P [1/s]"),
    "MPC_Z_V_AUTO_DN": (1.5, "descent speed in auto modes [m/s]"),
    "MPC_Z_V_AUTO_UP": (3.0, "climb speed in auto modes [m/s]"),
}

IDLE_THRUST_NORM = 0.05  # motor thrust while armed on the ground (PX4 idle spin)


class Px4Params:
    """The parameter set of one simulated vehicle."""

    def __init__(self, overrides: Mapping[str, float] | None = None) -> None:
        self._values = {name: default for name, (default, _) in PX4_DEFAULTS.items()}
        self.version = 0  # increments on every set, so users of derived vectors can refresh
        for name, value in (overrides or {}).items():
            self.set(name, value)

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

    def set(self, name: str, value: float) -> None:
        """Set one parameter; unknown names and non-finite values raise ValueError."""
        self.get(name)
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
            raise ValueError(f"parameter {name}: expected a float, got {value!r}")
        if not math.isfinite(float(value)):
            raise ValueError(f"parameter {name}: {value!r} is not finite; give a finite float")
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
