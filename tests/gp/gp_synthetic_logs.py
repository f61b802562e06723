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


def lag_plant_log(seed, tau_s, drag_per_m, n_rows=900, dt_s=0.02, noise_mps=0.005):
    """A velocity loop with lag ``tau_s`` and quadratic drag, positions integrated: what the
    check must predict. Commands: random smooth sweeps up to about 3 m/s."""
    rng = np.random.default_rng(seed)
    amp, freq, phase = rng.uniform(1.0, 3.0, 3), rng.uniform(0.2, 0.6, 3), rng.uniform(0, 6, 3)
    amp[2] *= 0.2
    rec = FlightLogRecorder({"source": "synthetic-lag"})
    pos, vel = np.array([0.0, 0.0, -5.0]), np.zeros(3)
    decay = np.exp(-dt_s / tau_s)
    for k in range(n_rows):
        cmd = amp * np.sin(freq * k * dt_s + phase)
        rec.append(level_flight_row(k * dt_s, pos, vel, cmd))
        new = cmd + (vel - cmd) * decay - dt_s * drag_per_m * vel * np.abs(vel)
        pos = pos + dt_s * 0.5 * (vel + new)
        vel = new + noise_mps * rng.normal(size=3)
    return rec.to_log()


def level_flight_row(t_s, pos, vel, cmd, mode=None):
    """One log row of a level vehicle facing north: position [m], velocity and velocity
    command [m/s], each (3,) NED; ``mode`` (e.g. "OFFBOARD") when given."""
    row = {
        "t_s": t_s,
        "pos_n_m": pos[0], "pos_e_m": pos[1], "pos_d_m": pos[2],
        "vel_n_mps": vel[0], "vel_e_mps": vel[1], "vel_d_mps": vel[2],
        "q_w": 1.0, "q_x": 0.0, "q_y": 0.0, "q_z": 0.0,
        "cmd_vel_n_mps": cmd[0], "cmd_vel_e_mps": cmd[1], "cmd_vel_d_mps": cmd[2],
        "cmd_yaw_rate_radps": 0.0,
    }  # fmt: skip
    return row if mode is None else {**row, "mode": mode}
