"""PX4's velocity-loop gains as logged before v1.11, in the units PX4 has used since.

Up to v1.10 the multicopter velocity PID's gains MPC_XY_VEL_P/I/D and MPC_Z_VEL_P/I/D scaled a
velocity error (its integral, its derivative) to normalised thrust. v1.11 replaced them with
MPC_*_VEL_*_ACC, which scale it to acceleration [m/s^2], the thrust then following as
acceleration / g x hover thrust ([PX4-vel-acc]). A logged old gain is the same loop as the new
gain old x g / hover thrust, the scale PX4's position controller applied to the old gains while
both existed: for a simulated vehicle hovering at that thrust, its controller commands the
thrust the vehicle's did. (PX4's migration of stored values multiplied by 20, g over a hover
thrust of about 0.5.)
"""

from __future__ import annotations

from collections.abc import Mapping

from vehicle_sim.config import GRAVITY_MPS2

OLD_TO_ACC = {
    "MPC_XY_VEL_P": "MPC_XY_VEL_P_ACC",
    "MPC_XY_VEL_I": "MPC_XY_VEL_I_ACC",
    "MPC_XY_VEL_D": "MPC_XY_VEL_D_ACC",
    "MPC_Z_VEL_P": "MPC_Z_VEL_P_ACC",
    "MPC_Z_VEL_I": "MPC_Z_VEL_I_ACC",
    "MPC_Z_VEL_D": "MPC_Z_VEL_D_ACC",
}


def acceleration_gains(params: Mapping[str, float], hover_thrust: float) -> dict[str, float]:
    """The MPC_*_VEL_*_ACC gains (name -> value) that ``params``' old-style gains stand for at
    ``hover_thrust`` (normalised, 0-1); only those whose new name ``params`` lacks."""
    return {
        new: float(params[old]) * GRAVITY_MPS2 / hover_thrust
        for old, new in OLD_TO_ACC.items()
        if old in params and new not in params
    }
