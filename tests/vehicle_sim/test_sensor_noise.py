"""Sensor noise on a log: seeded, at the drawn levels and rate, commands left exact."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from diagnosis.noise_floor import white_noise_std
from flightlog.schema import FlightLog
from vehicle_sim.sensor_noise import SensorNoise, add_sensor_noise, draw_sensor_noise


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


def test_no_noise_gives_the_log_back_exact():
    log = _smooth_log()
    quiet = add_sensor_noise(log, SensorNoise.none(), seed=3)
    assert quiet.columns.keys() == log.columns.keys()
    assert all(np.array_equal(quiet[k], log[k]) for k in log.columns)


def test_the_acceleration_bias_is_a_random_walk_from_zero():
    """A walk of intensity w = 0.01 m/s^2/sqrt(s) sampled every 10 ms: increments of std
    w sqrt(0.01 s) = 0.001 m/s^2, independent, starting at zero."""
    log = _smooth_log(n=20000)
    noisy = add_sensor_noise(
        log, replace(SensorNoise.none(), acc_bias_walk_mps2_per_sqrt_s=0.01), seed=4
    )
    bias = noisy["acc_n_mps2"] - log["acc_n_mps2"]
    assert bias[0] == 0.0
    steps = np.diff(bias)
    assert np.std(steps) == pytest.approx(0.001, rel=0.03)
    assert abs(np.corrcoef(steps[1:], steps[:-1])[0, 1]) < 0.05


def test_attitude_noise_keeps_a_unit_quaternion_a_small_rotation_away():
    """On a tilted and yawed vehicle: each row's rotation from the exact attitude has about
    attitude_deg of std per axis (scipy's rotation vectors)."""
    log = _smooth_log()
    q = Rotation.from_euler("ZYX", [70.0, 20.0, -30.0], degrees=True).as_quat()  # x, y, z, w
    cols = dict(log.columns)
    cols.update({k: np.full(log.n_rows, q[i]) for i, k in enumerate(("q_x", "q_y", "q_z"))})
    cols["q_w"] = np.full(log.n_rows, q[3])
    noisy = add_sensor_noise(
        FlightLog(cols, log.metadata), replace(SensorNoise.none(), attitude_deg=0.8), 5
    )
    wxyz = noisy.stack("q_w", "q_x", "q_y", "q_z")
    assert np.allclose(np.linalg.norm(wxyz, axis=1), 1.0)
    exact = Rotation.from_quat(q)
    error = (exact.inv() * Rotation.from_quat(wxyz[:, [1, 2, 3, 0]])).as_rotvec()
    assert np.allclose(np.degrees(np.std(error, axis=0)), 0.8, rtol=0.1)


def test_time_jitter_larger_than_the_row_spacing_keeps_times_in_order():
    log = _smooth_log(n=2000)  # 10 ms apart
    noisy = add_sensor_noise(log, replace(SensorNoise.none(), time_jitter_s=0.05), seed=6)
    assert np.all(np.diff(noisy["t_s"]) > 0.0)
    two = add_sensor_noise(log.slice(0, 2), replace(SensorNoise.none(), time_jitter_s=0.05), seed=6)
    assert not np.array_equal(two["t_s"], log["t_s"][:2])  # two rows are jittered too


def test_thinning_to_half_the_rate_keeps_every_other_row():
    log = _smooth_log(n=1000)  # 100 Hz
    thinned = add_sensor_noise(log, replace(SensorNoise.none(), log_rate_hz=50.0), seed=0)
    assert np.array_equal(thinned["t_s"], log["t_s"][::2])


def test_a_noisy_log_keeps_its_metadata_and_says_it_is_simulated_noise():
    noisy = add_sensor_noise(_smooth_log(n=100), draw_sensor_noise(np.random.default_rng(1)), 1)
    assert noisy.metadata["source"] == "test" and noisy.metadata["sensor_noise"] == "simulated"


def test_a_fixed_imu_level_is_kept_when_the_others_are_drawn():
    assert draw_sensor_noise(np.random.default_rng(2), acc_mps2=0.7).acc_mps2 == 0.7
