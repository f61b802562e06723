"""PX4 topics for mapping tests: a schema-v1 log re-expressed as the uORB topics PX4 logs,
at PX4-like rates with PX4-like estimator noise (the truth stays with the caller)."""

from __future__ import annotations

import numpy as np

from flightlog.schema import FlightLog


def topics_of(
    log: FlightLog,
    rng: np.random.Generator | None = None,
    setpoint_hz: float | None = None,
    nav_state: int = 14,
) -> dict[str, dict[str, np.ndarray]]:
    """The topics a PX4 vehicle flying ``log`` would log. With ``rng``: position noise 0.02 m,
    velocity noise 0.05 m/s (EKF2-like), attitude sampled 3 ms off the position times; with
    ``setpoint_hz``: vehicle_local_position_setpoint published at that rate only."""
    t_us = np.round(log["t_s"] * 1e6) + 1_000_000
    n = len(t_us)
    noise = (lambda s: rng.normal(0.0, s, n)) if rng is not None else (lambda s: np.zeros(n))
    att_us = t_us - 3_000
    q = log.stack("q_w", "q_x", "q_y", "q_z")
    q_att = np.column_stack([np.interp(att_us, t_us, q[:, i]) for i in range(4)])
    sp_rows = np.arange(n)
    if setpoint_hz is not None:
        step = max(1, int(round(1.0 / setpoint_hz / np.median(np.diff(log["t_s"])))))
        sp_rows = sp_rows[::step]
    ones = np.ones(n)
    return {
        "vehicle_local_position": {
            "timestamp": t_us,
            "x": log["pos_n_m"] + noise(0.02), "y": log["pos_e_m"] + noise(0.02),
            "z": log["pos_d_m"] + noise(0.02),
            "vx": log["vel_n_mps"] + noise(0.05), "vy": log["vel_e_mps"] + noise(0.05),
            "vz": log["vel_d_mps"] + noise(0.05),
            "ax": log["acc_n_mps2"], "ay": log["acc_e_mps2"], "az": log["acc_d_mps2"],
            "xy_valid": ones, "z_valid": ones, "v_xy_valid": ones, "v_z_valid": ones,
        },
        "vehicle_attitude": {"timestamp": att_us, **{f"q[{i}]": q_att[:, i] for i in range(4)}},
        "vehicle_local_position_setpoint": {
            "timestamp": t_us[sp_rows],
            "vx": log["cmd_vel_n_mps"][sp_rows], "vy": log["cmd_vel_e_mps"][sp_rows],
            "vz": log["cmd_vel_d_mps"][sp_rows], "yawspeed": log["cmd_yaw_rate_radps"][sp_rows],
        },
        "vehicle_status": {
            "timestamp": t_us[:1], "nav_state": np.array([nav_state]),
            "arming_state": np.array([2]), "is_vtol": np.array([0]),
            "vehicle_type": np.array([1]),
        },
        "battery_status": {"timestamp": t_us, "voltage_v": log["battery_v"]},
        "vehicle_thrust_setpoint": {"timestamp": t_us, "xyz[2]": -log["thrust_n"] / 28.27},
    }  # fmt: skip
