"""Truth logging: one schema-v1 row (flightlog.schema) of the simulated vehicle's state.

Only quantities a real vehicle could measure go into a row; effect parameters never do.
"""

from __future__ import annotations

from vehicle_sim.vehicle_types import VehicleState


def truth_row(
    state: VehicleState, cmd_vel_ned_mps: tuple[float, float, float], cmd_yaw_rate_radps: float
) -> dict[str, float | str]:
    """A flight-log row (column -> value) for ``state`` and the command that was in force."""
    p, v, a, q, r = (
        state.pos_ned_m,
        state.vel_ned_mps,
        state.acc_ned_mps2,
        state.q_wxyz,
        state.rates_frd_radps,
    )
    return {
        "t_s": float(state.t_s),
        "pos_n_m": float(p[0]), "pos_e_m": float(p[1]), "pos_d_m": float(p[2]),
        "vel_n_mps": float(v[0]), "vel_e_mps": float(v[1]), "vel_d_mps": float(v[2]),
        "q_w": float(q[0]), "q_x": float(q[1]), "q_y": float(q[2]), "q_z": float(q[3]),
        "cmd_vel_n_mps": float(cmd_vel_ned_mps[0]),
        "cmd_vel_e_mps": float(cmd_vel_ned_mps[1]),
        "cmd_vel_d_mps": float(cmd_vel_ned_mps[2]),
        "cmd_yaw_rate_radps": float(cmd_yaw_rate_radps),
        "acc_n_mps2": float(a[0]), "acc_e_mps2": float(a[1]), "acc_d_mps2": float(a[2]),
        "rate_x_radps": float(r[0]), "rate_y_radps": float(r[1]), "rate_z_radps": float(r[2]),
        "thrust_n": float(state.thrust_n),
        "battery_v": float(state.battery_v),
        "mode": state.mode.name,
        "armed": 1.0 if state.armed else 0.0,
    }  # fmt: skip
