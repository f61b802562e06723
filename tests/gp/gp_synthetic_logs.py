"""Synthetic flight logs with a known residual, for the gp tests."""

import numpy as np

from flightlog.schema import FlightLogRecorder


def drag_residual(vel_mps):
    """The known residual [m/s^2]: -0.3 v - 0.08 v|v| per axis."""
    return -0.3 * vel_mps - 0.08 * vel_mps * np.abs(vel_mps)


def record_log(n_rows=400, dt_s=0.05, seed=0, noise_mps=0.0, gap_at=None, modes=None):
    """A log where v[k+1] = cmd[k] + dt * drag_residual(v[k]) (+ noise), so the residual
    against the kinematic model is exactly drag_residual(v[k]).

    gap_at: row index before which 2 s of time are skipped; modes: per-row mode strings.
    """
    rng = np.random.default_rng(seed)
    rec = FlightLogRecorder({"source": "synthetic"})
    vel = np.zeros(3)
    for k in range(n_rows):
        t = k * dt_s + (2.0 if gap_at is not None and k >= gap_at else 0.0)
        cmd = 2.0 * np.array([np.sin(0.05 * k + seed), np.cos(0.03 * k), 0.2 * np.sin(0.02 * k)])
        row = {
            "t_s": t,
            "pos_n_m": 0.0, "pos_e_m": 0.0, "pos_d_m": -5.0,
            "vel_n_mps": vel[0], "vel_e_mps": vel[1], "vel_d_mps": vel[2],
            "q_w": 1.0, "q_x": 0.0, "q_y": 0.0, "q_z": 0.0,
            "cmd_vel_n_mps": cmd[0], "cmd_vel_e_mps": cmd[1], "cmd_vel_d_mps": cmd[2],
            "cmd_yaw_rate_radps": 0.0,
        }  # fmt: skip
        if modes is not None:
            row["mode"] = modes[k]
        rec.append(row)
        vel = cmd + dt_s * drag_residual(vel) + noise_mps * rng.normal(size=3)
    return rec.to_log()
