"""PX4's velocity integrator rebuilt from a flight log, as the companion keeps it in flight.

planners.nominal_models.px4_velocity_pi carries the autopilot's velocity integrator I [m/s^2]
(relative to its value in the settled hover before the flight) as a state. In flight the
companion integrates it itself (companion.nmpc_planner.CompanionNmpc): 0 at the first plan (the
switch to OFFBOARD after the start hold), then between plans k-1 and k

    I_k = I_{k-1} + Ki (u_{k-1} - (v_{k-1} + v_k) / 2) (t_k - t_{k-1})

with u the command of plan k-1 and v the measured velocity. Here the same rule runs over a log
segment's rows (one row per plan), from 0 at the segment's first row, on the logged command
(``cmd_vel_*``: what was sent; the companion integrates the planner's command before the
loop's saturation, so the two differ only where that saturation cut the command) and the
logged velocity. A segment starts at a mode change (the switch to OFFBOARD) or a gap
(gp.datasets.split_segments), where the companion too restarts its integrator (after a gap
over INTEGRATOR_GAP_S; a shorter gap that splits a segment restarts it here only).

The gains Ki are the autopilot's MPC_*_VEL_I_ACC, recorded with the log (the sidecar's
``velocity_loop_gains``, written by the companion from what the autopilot reports,
companion.autopilot_gains, or a PX4 ULog's own parameters, under their names before v1.11
too: flightlog.velocity_loop_gains); :func:`logged_velocity_loop_gains` reads them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flightlog.schema import FlightLog
from flightlog.vehicle_identity import same_gains
from flightlog.velocity_loop_gains import VELOCITY_LOOP_PARAMS, velocity_loop_gains
from gp.errors import DatasetError

VELOCITY_LOOP_GAIN_NAMES: tuple[str, ...] = tuple(VELOCITY_LOOP_PARAMS)


def velocity_integrator(log: FlightLog, ki: Sequence[float]) -> np.ndarray:
    """The integrator [m/s^2] per row of ``log`` (one segment: 0 at its first row), (n, 3),
    for the I gains ``ki`` (3,) [1/s^2 per m/s] per NED axis."""
    ki = np.asarray(ki, dtype=float).reshape(3)
    t = log["t_s"]
    vel = log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")
    cmd = log.stack("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps")
    out = np.zeros((t.size, 3))
    if t.size > 1:
        steps = ki * (cmd[:-1] - 0.5 * (vel[:-1] + vel[1:])) * np.diff(t)[:, None]
        out[1:] = np.cumsum(steps, axis=0)
    return out


def logged_velocity_loop_gains(logs: Sequence[FlightLog]) -> dict[str, float]:
    """The autopilot's velocity-loop gains (px4_velocity_pi's parameter names) recorded with
    ``logs`` (flightlog.velocity_loop_gains: the sidecar's, else the PX4 parameters a ULog
    records, under their names since v1.11 or before); every log must carry them, and the same
    ones (flightlog.vehicle_identity.same_gains: a float32 read over MAVLink is the same gain
    as the float64 in process). The first log's are returned.

    Raises:
        DatasetError: a log without them, or logs with different gains (one line each).
    """
    gains: dict[str, float] | None = None
    for log in logs:
        logged = velocity_loop_gains(log)
        if logged.gains is None:
            raise DatasetError(
                f"{log.where}: {logged.source}; px4_velocity_pi needs the autopilot's "
                "MPC_*_VEL_*_ACC gains: fly with a companion that records them, or give them "
                "with --nominal-param vel_p_xy=... (all six)"
            )
        if gains is not None and not same_gains(logged.gains, gains):
            raise DatasetError(
                f"{log.where}: velocity-loop gains {logged.gains} differ from the other logs' "
                f"{gains}; fit logs flown with one tuning at a time"
            )
        gains = gains or logged.gains
    return gains or {}
