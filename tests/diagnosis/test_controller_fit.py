"""The vertical velocity-loop I of flight_control: its integral regressor and its interval."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from diagnosis.controller_fit import _held_integral, refit_vertical_integral
from diagnosis.diagnosis import DiagnosisConfig
from diagnosis.fly_schedule import fly_schedule
from diagnosis.replay import windows
from experiments.hidden_effects import schedule
from vehicle_sim import load_sim_config
from vehicle_sim.sensor_noise import SensorNoise, add_sensor_noise


def test_held_integral_holds_each_command_for_the_step_after_it():
    dt = np.array([0.0, 0.05, 0.05, 0.05])
    cmd = np.column_stack([[1.0, 2.0, 3.0, 4.0], np.zeros(4), np.zeros(4)])
    still = np.zeros((4, 3))
    out = _held_integral(cmd, still, still, dt)
    assert out[:, 0] == pytest.approx([0.0, 0.05, 0.15, 0.30])


def test_held_integral_takes_the_flown_part_from_position_else_velocity():
    t = np.linspace(0.0, 2.0, 41)
    dt = np.diff(t, prepend=t[0])
    vel = np.column_stack([t, np.zeros_like(t), -0.5 * t])
    pos = 0.5 * t[:, None] ** 2 * np.array([1.0, 0.0, -0.5]) + np.array([3.0, 1.0, -2.0])
    cmd = np.zeros_like(vel)
    from_pos = _held_integral(cmd, vel, pos, dt)
    from_vel = _held_integral(cmd, vel, np.full_like(pos, np.nan), dt)
    assert from_pos == pytest.approx(-(pos - pos[0]))
    assert from_vel == pytest.approx(-(pos - pos[0]))  # trapezoidal: exact on a ramp


def _train(log):
    config = DiagnosisConfig()
    wins = windows([log], config.window_s)
    block = config.selection.block_s
    return [w for w in wins if int(w.t_anchor_s // block) % 2 == 0]


def test_vertical_integral_interval_holds_the_truth_and_widens_with_thrust_noise():
    """Other vertical gains than the config: the exact log's 95 % interval holds the true I;
    5 % thrust-telemetry noise (the top of issue 18's range) widens it."""
    gains = {"MPC_Z_VEL_P_ACC": 5.6, "MPC_Z_VEL_I_ACC": 1.1}
    log = fly_schedule(load_sim_config("iris"), schedule(), seed=3, params=gains)
    thrust_only = dataclasses.replace(SensorNoise.none(), thrust_fraction=0.05)
    noisy = add_sensor_noise(log, thrust_only, seed=3)
    config = load_sim_config("iris")
    exact = refit_vertical_integral([log], config, _train(log), gains)
    low, high = exact.interval()
    assert low <= gains["MPC_Z_VEL_I_ACC"] <= high, exact
    wide = refit_vertical_integral([noisy], config, _train(noisy), gains)
    assert wide.std_error > 1.5 * exact.std_error, (exact, wide)
