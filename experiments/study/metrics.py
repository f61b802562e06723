"""Figures of one flight log: residual of the model that flew, tracking error (pure).

Only the following phase counts: rows in OFFBOARD mode (after the setpoint stream, until the
vehicle is switched to HOLD for landing).

Residual ([Kulathunga23], Table 2): for consecutive following rows k, k+1,
    r_k = v_measured(t[k+1]) - pred_vel(t[k])        [m/s, NED]
where pred_vel is the velocity the planner's own model predicted one control period after the
command it sent (the command itself for the nominal kinematic model). Its RMSE is
sqrt(mean_k |r_k|^2) over all three axes, in m/s. Tracking error is the distance between the
vehicle and the reference position at each following row [m]; the settled tracking error
leaves out the first SETTLE_S seconds of following, where the vehicle takes up the reference
from the hover it started in. (The runner starts the reference only once the vehicle has
settled within 0.1 m of its start, companion.runner's start hold; before that hold, the
takeoff in the wind_field regime's jet left it 0.5-0.7 m off, and those 2 s held most of the
error.)
"""

from __future__ import annotations

import numpy as np

from flightlog.schema import FlightLog

_VEL = ("vel_n_mps", "vel_e_mps", "vel_d_mps")
_PRED = ("pred_vel_n_mps", "pred_vel_e_mps", "pred_vel_d_mps")
_POS = ("pos_n_m", "pos_e_m", "pos_d_m")
_REF = ("ref_pos_n_m", "ref_pos_e_m", "ref_pos_d_m")
SETTLE_S = 2.0  # following time left out of the settled tracking figure [s]


def following_rows(log: FlightLog) -> np.ndarray:
    """Boolean mask (n,) of the rows flown in OFFBOARD mode."""
    return np.asarray(log["mode"] == "OFFBOARD")


def residuals_mps(log: FlightLog) -> np.ndarray:
    """One-step velocity residuals r_k (n_pairs, 3) [m/s] of the model that flew."""
    if not log.has(*_PRED):
        raise ValueError(f"{log.path or 'log'} has no pred_vel_* columns; fly it with the NMPC")
    follow = following_rows(log)
    k = np.flatnonzero(follow[:-1] & follow[1:])
    return log.stack(*_VEL)[k + 1] - log.stack(*_PRED)[k]


def residual_rmse_mps(log: FlightLog) -> float:
    """RMSE [m/s] of the one-step velocity residual (norm over axes)."""
    r = residuals_mps(log)
    return float(np.sqrt(np.mean(np.sum(r**2, axis=1))))


def tracking_errors_m(log: FlightLog) -> np.ndarray:
    """Distance [m] (n_following,) from the reference position at each following row."""
    follow = following_rows(log)
    return np.linalg.norm(log.stack(*_POS)[follow] - log.stack(*_REF)[follow], axis=1)


def tracking_rmse_m(log: FlightLog) -> float:
    """Position tracking RMSE [m] over the following rows."""
    return float(np.sqrt(np.mean(tracking_errors_m(log) ** 2)))


def settled_tracking_rmse_m(log: FlightLog, settle_s: float = SETTLE_S) -> float:
    """Position tracking RMSE [m] over the following rows after the first ``settle_s`` [s]
    of following (NaN if none is left): without the first transient from the hover, the
    same for every planner (see the module docstring)."""
    follow = following_rows(log)
    t = log["t_s"][follow]
    if t.size == 0:
        return float("nan")
    late = t - t[0] >= settle_s
    if not np.any(late):
        return float("nan")
    errors = tracking_errors_m(log)[late]
    return float(np.sqrt(np.mean(errors**2)))


def pooled_rmse(values: list[float], weights: list[int] | None = None) -> float:
    """RMSE over several flights from their RMSEs (weighted by row counts if given)."""
    v = np.asarray(values, dtype=float)
    w = np.ones_like(v) if weights is None else np.asarray(weights, dtype=float)
    return float(np.sqrt(np.sum(w * v**2) / np.sum(w)))
