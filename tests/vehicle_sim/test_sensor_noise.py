"""Sensor noise on a log: seeded, at the drawn levels and rate, commands left exact."""

from __future__ import annotations

import numpy as np

from diagnosis.noise_floor import white_noise_std
from flightlog.schema import FlightLog
from vehicle_sim.sensor_noise import add_sensor_noise, draw_sensor_noise


def _smooth_log(n: int = 6000, dt: float = 0.01) -> FlightLog:
    t = np.arange(n) * dt
    cols = {"t_s": t, "thrust_n": np.full(n, 15.0)}
    for i, a in enumerate("ned"):
        cols[f"pos_{a}_m"] = np.sin(0.1 * t + i)
        cols[f"vel_{a}_mps"] = 0.1 * np.cos(0.1 * t + i)
        cols[f"acc_{a}_mps2"] = -0.01 * np.sin(0.1 * t + i)
        cols[f"cmd_vel_{a}_mps"] = np.round(np.sin(0.05 * t + i))
    cols["cmd_yaw_rate_radps"] = np.zeros(n)
    cols.update(q_w=np.ones(n), q_x=np.zeros(n), q_y=np.zeros(n), q_z=np.zeros(n))
    return FlightLog(cols, {"source": "test"})


def test_noise_is_seeded_at_its_levels_and_leaves_commands_exact():
    noise = draw_sensor_noise(np.random.default_rng(9))
    log = _smooth_log()
    a, b = add_sensor_noise(log, noise, seed=1), add_sensor_noise(log, noise, seed=1)
    assert all(np.array_equal(a[k], b[k]) for k in a.columns)
    rate_hz = (a.n_rows - 1) / (a["t_s"][-1] - a["t_s"][0])
    assert abs(rate_hz / noise.log_rate_hz - 1.0) < 0.05
    assert np.all(np.diff(a["t_s"]) > 0.0)
    vel = white_noise_std(a.stack("vel_n_mps", "vel_e_mps", "vel_d_mps"))
    acc = white_noise_std(a.stack("acc_n_mps2", "acc_e_mps2", "acc_d_mps2"))
    assert np.allclose(vel, noise.vel_mps, rtol=0.15) and np.allclose(
        acc, noise.acc_mps2, rtol=0.15
    )
    thrust = np.std(a["thrust_n"] / 15.0 - 1.0)
    assert abs(thrust / noise.thrust_fraction - 1.0) < 0.15
    q = a.stack("q_w", "q_x", "q_y", "q_z")
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    tilt_deg = np.degrees(2.0 * np.std(q[:, 1]))
    assert abs(tilt_deg / noise.attitude_deg - 1.0) < 0.15
    keep = np.searchsorted(log["t_s"], np.round(a["t_s"], 2))
    assert np.array_equal(a["cmd_vel_n_mps"], log["cmd_vel_n_mps"][keep])
    assert not np.array_equal(add_sensor_noise(log, noise, seed=2)["vel_n_mps"], a["vel_n_mps"])


def test_drawn_levels_stay_in_the_realistic_ranges():
    rng = np.random.default_rng(0)
    for _ in range(50):
        n = draw_sensor_noise(rng)
        assert 0.2 <= n.acc_mps2 <= 0.4 and 0.03 <= n.vel_mps <= 0.08
        assert 0.3 <= n.attitude_deg <= 1.0 and 0.01 <= n.thrust_fraction <= 0.05
        assert 25.0 <= n.log_rate_hz <= 50.0
