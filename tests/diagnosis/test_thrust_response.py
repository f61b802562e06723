"""Motor lag from the thrust response: the anchored follower's one-row-ahead thrust."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.replay import windows
from diagnosis.thrust_response import produced_thrust, track_thrust
from experiments.hidden_effects import draw, fly_hidden
from vehicle_sim import load_sim_config


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
