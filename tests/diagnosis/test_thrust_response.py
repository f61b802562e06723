"""Motor lag and thrust curve from the thrust response: the anchored follower's one-row-ahead
thrust."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.noise_floor import white_noise_std
from diagnosis.replay import windows
from diagnosis.thrust_response import produced_thrust, select_thrust_response, track_thrust
from experiments.hidden_effects import draw, fly_hidden, main_parameter_errors
from vehicle_sim import load_sim_config
from vehicle_sim.sensor_noise import add_sensor_noise, draw_sensor_noise


def test_only_a_produced_thrust_shows_the_lag():
    assert produced_thrust(["thrust_n as logged", "ESC rotor speed x the config's (hover 1.0)"])
    assert not produced_thrust(["thrust_n as logged", "normalised thrust x max thrust"])
    assert not produced_thrust([])


@pytest.mark.slow
def test_the_true_lag_reproduces_the_logged_thrust(tmp_path):
    truth, base = draw("motor_lag", np.random.default_rng(23))
    logs = fly_hidden(truth, tmp_path, 23)
    wins = windows(logs)[::3]
    true_cfg = load_sim_config("iris", truth)
    preset = track_thrust(load_sim_config("iris", base), logs, wins)
    true = track_thrust(true_cfg, logs, wins)
    assert len(true.window) > 100
    np.testing.assert_allclose(true.meas_thrust_n, preset.meas_thrust_n)
    assert true.mse() < 0.05 * preset.mse(), (true.mse(), preset.mse(), truth)
    noisy = track_thrust(true_cfg, logs, wins, extra_vel_noise_mps=np.full(3, 0.05))
    assert noisy.mse() > 2.0 * true.mse()  # the follower's command carries the velocity noise


@pytest.mark.slow
@pytest.mark.parametrize("name", ["motor_lag", "thrust_curve"])
def test_the_thrust_response_tells_a_lag_from_a_thrust_curve_on_a_noisy_log(name, tmp_path):
    """Drawn effect and noise levels (seeded); the fit sees only the noisy log and the preset.
    The other is not named beside it, and the main parameter is within 15 %."""
    seed = 31 + ["motor_lag", "thrust_curve"].index(name)
    truth, base = draw(name, np.random.default_rng(seed))
    noise = draw_sensor_noise(np.random.default_rng(seed + 100))
    logs = [add_sensor_noise(log, noise, seed) for log in fly_hidden(truth, tmp_path, seed)]
    wins = windows(logs)
    test = [w for w in wins if (int(w.t_anchor_s // 4.0) + w.log_index) % 2 == 1]
    train = [w for w in wins if w not in test]
    config = load_sim_config("iris", base)
    (log,) = logs
    vel_noise = white_noise_std(log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps"))
    named, _ = select_thrust_response(config, logs, train, test, vel_noise)
    assert [c.name for c in named] == [name], (noise, named)
    errors = main_parameter_errors(name, truth, named[0].params)
    assert max(errors.values()) < 0.15, (noise, errors)
