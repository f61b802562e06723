"""A log's PX4 velocity-loop gains in the units PX4 has used since v1.11, under whichever names
the log records them.

Where they come from, the first that holds them:

- a companion log's sidecar ``velocity_loop_gains``: what the autopilot reported before arming,
  under px4_velocity_pi's names (:data:`VELOCITY_LOOP_PARAMS`);
- a ULog's PX4 parameters (``px4_params``, kept in a converted CSV's sidecar too):
  MPC_XY_VEL_P/I/D_ACC and MPC_Z_VEL_P/I/D_ACC ([PX4-params]; P in 1/s, I in 1/s^2, D
  dimensionless: acceleration [m/s^2] per velocity error [m/s], its integral, its derivative);
- their names up to v1.10, MPC_XY_VEL_P/I/D and MPC_Z_VEL_P/I/D, which scaled the velocity
  error to normalised thrust. v1.11 replaced them with the _ACC gains, which scale it to
  acceleration, the thrust then following as acceleration / g x hover thrust ([PX4-vel-acc]).
  An old gain is the same loop as the new gain old x g / hover thrust, the scale PX4's
  position controller applied to the old gains while both existed (PX4's migration of stored
  values multiplied by 20: g over a hover thrust of about 0.5).

The hover thrust of that scale is the log's MPC_THR_HOVER, what PX4 scaled by (a parameter:
every log flown with one tuning gives the same gains), else the hover thrust estimated from the
flight (:func:`estimated_hover_thrust`). A log with neither gives no gains, and one line says
why.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from flightlog.schema import GRAVITY_MPS2, FlightLog

HOVER_SPEED_MPS = 0.3  # rows slower than this (and not landed) count as hovering
MIN_HOVER_ROWS = 10  # hovering rows a hover thrust is read from, at least
HOVER_PARAMETER = "MPC_THR_HOVER parameter"  # the hover thrust's source, when a parameter
HOVER_ESTIMATED = "median produced thrust in hover"  # its source, when estimated from the flight

GAINS_METADATA_KEY = "velocity_loop_gains"

# px4_velocity_pi's parameter -> PX4's parameter ([PX4-params] MPC_XY_VEL_*_ACC, MPC_Z_VEL_*_ACC)
VELOCITY_LOOP_PARAMS: dict[str, str] = {
    "vel_p_xy": "MPC_XY_VEL_P_ACC",
    "vel_i_xy": "MPC_XY_VEL_I_ACC",
    "vel_d_xy": "MPC_XY_VEL_D_ACC",
    "vel_p_z": "MPC_Z_VEL_P_ACC",
    "vel_i_z": "MPC_Z_VEL_I_ACC",
    "vel_d_z": "MPC_Z_VEL_D_ACC",
}

# PX4's name up to v1.10 (normalised thrust per m/s) -> its name since v1.11 ([PX4-vel-acc])
OLD_TO_ACC: dict[str, str] = {
    "MPC_XY_VEL_P": "MPC_XY_VEL_P_ACC",
    "MPC_XY_VEL_I": "MPC_XY_VEL_I_ACC",
    "MPC_XY_VEL_D": "MPC_XY_VEL_D_ACC",
    "MPC_Z_VEL_P": "MPC_Z_VEL_P_ACC",
    "MPC_Z_VEL_I": "MPC_Z_VEL_I_ACC",
    "MPC_Z_VEL_D": "MPC_Z_VEL_D_ACC",
}


@dataclass(frozen=True)
class LoggedGains:
    """A log's velocity-loop gains: ``gains`` (px4_velocity_pi's names -> value in PX4's _ACC
    units, all six) and ``source``, where they came from in words; or ``gains`` None and
    ``source`` the one-line reason why the log gives none."""

    gains: dict[str, float] | None
    source: str


def estimated_hover_thrust(log: FlightLog) -> float | None:
    """The hover thrust (normalised, 0-1) the flight shows: the median produced thrust
    (``thrust_norm`` of a ``produced`` thrust source) over the rows slower than
    HOVER_SPEED_MPS and not landed, when there are MIN_HOVER_ROWS or more and it is a thrust
    a vehicle hovers at (:func:`is_hover_thrust`: not the zero of motors idle on the ground in
    a log that does not say it landed); else None."""
    source = log.metadata.get("thrust_source")
    produced = isinstance(source, Mapping) and source.get("kind") == "produced"
    if not (produced and log.has("thrust_norm")):
        return None
    speed = np.linalg.norm(log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps"), axis=1)
    rows = speed < HOVER_SPEED_MPS
    if log.has("landed"):
        rows &= log["landed"] == 0
    if rows.sum() < MIN_HOVER_ROWS:
        return None
    hover = float(np.median(log["thrust_norm"][rows]))
    return hover if is_hover_thrust(hover) else None


def is_hover_thrust(value: float) -> bool:
    """A normalised thrust in (0, 1]: one a hover thrust can be (0 would make every gain
    scaled by it infinite)."""
    return 0.0 < value <= 1.0


def hover_thrust_for_gains(
    params: Mapping[str, float], estimated: float | None
) -> tuple[float | None, str]:
    """(hover thrust, its source) that scales old gains: MPC_THR_HOVER in ``params`` when
    a hover thrust (:func:`is_hover_thrust`), else ``estimated`` (the flight's,
    :func:`estimated_hover_thrust`) when one; (None, "") with neither."""
    if "MPC_THR_HOVER" in params and is_hover_thrust(float(params["MPC_THR_HOVER"])):
        return float(params["MPC_THR_HOVER"]), HOVER_PARAMETER
    if estimated is not None and is_hover_thrust(estimated):
        return estimated, HOVER_ESTIMATED
    return None, ""


def acceleration_gains(params: Mapping[str, float], hover_thrust: float) -> dict[str, float]:
    """The MPC_*_VEL_*_ACC gains (PX4 name -> value) that ``params``' old gains stand for at
    ``hover_thrust`` (normalised, 0-1); only those whose new name ``params`` lacks."""
    return {
        new: float(params[old]) * GRAVITY_MPS2 / hover_thrust
        for old, new in OLD_TO_ACC.items()
        if old in params and new not in params
    }


def velocity_loop_gains(log: FlightLog) -> LoggedGains:
    """``log``'s velocity-loop gains and where they came from (module docstring), or the
    reason it gives none: no record of some gain, a sidecar record that is not all numbers,
    or old gains and no hover thrust."""
    record = log.metadata.get(GAINS_METADATA_KEY)
    if isinstance(record, Mapping):
        missing = [n for n in VELOCITY_LOOP_PARAMS if not is_number(record.get(n))]
        if missing:
            why = f"its sidecar's {GAINS_METADATA_KEY} has no number for {missing}"
            return LoggedGains(None, why)
        gains = {n: float(record[n]) for n in VELOCITY_LOOP_PARAMS}
        return LoggedGains(gains, f"its sidecar's {GAINS_METADATA_KEY}")
    params = log.metadata.get("px4_params")
    params = (
        {k: v for k, v in params.items() if is_number(v)} if isinstance(params, Mapping) else {}
    )
    old = [o for o, new in OLD_TO_ACC.items() if o in params and new not in params]
    hover, how = hover_thrust_for_gains(params, estimated_hover_thrust(log) if old else None)
    if old and hover is None:
        return LoggedGains(
            None,
            f"it records {', '.join(old)} under their names before PX4 v1.11 (normalised thrust "
            "per m/s) and no hover thrust to scale them by (no MPC_THR_HOVER parameter in (0, 1], "
            "no produced thrust while hovering)",
        )
    acc = {**params, **(acceleration_gains(params, hover) if old else {})}
    missing = [n for n in VELOCITY_LOOP_PARAMS if VELOCITY_LOOP_PARAMS[n] not in acc]
    if missing:
        return LoggedGains(
            None,
            f"neither its sidecar's {GAINS_METADATA_KEY} nor its PX4 parameters hold {missing} "
            "(MPC_*_VEL_*_ACC, or MPC_*_VEL_P/I/D before PX4 v1.11)",
        )
    gains = {n: float(acc[p]) for n, p in VELOCITY_LOOP_PARAMS.items()}
    if not old:
        return LoggedGains(gains, "its PX4 parameters MPC_*_VEL_*_ACC")
    return LoggedGains(
        gains,
        f"its PX4 parameters {', '.join(old)} (before v1.11, normalised thrust per m/s) x g / "
        f"hover thrust {hover:.3f} ({how})",
    )


def is_number(value: object) -> bool:
    """A finite int or float (not a bool, a string or NaN: a sidecar may hold anything)."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
