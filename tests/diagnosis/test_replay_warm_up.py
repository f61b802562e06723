"""The replay's warm-up restores the velocity-loop integral from all of its rows, past the
attitude lag: one noisy row's attitude does not stay in every window of the run as an
acceleration bias, and a vehicle already accelerating does not show its lag as an integral."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.replay import replay, windows
from diagnosis.warm_up import integral_offset
from flightlog.schema import FlightLog
from tests.vehicle_sim.sim_flying import hovering, record_offboard
from vehicle_sim import VelocitySetpoint, load_sim_config
from vehicle_sim.sensor_noise import SensorNoise, add_sensor_noise

ATTITUDE_ONLY = SensorNoise(
    acc_mps2=0.0,
    acc_bias_walk_mps2_per_sqrt_s=0.0,
    vel_mps=0.0,
    attitude_deg=1.0,
    thrust_fraction=0.0,
    time_jitter_s=0.0,
    log_rate_hz=0.0,
)


def hover_log(duration_s: float = 9.0, rate_hz: float = 20.0) -> FlightLog:
    """An exact log of an Iris hovering in OFFBOARD on a zero velocity setpoint."""
    cmd = VelocitySetpoint((0.0, 0.0, 0.0))
    return record_offboard(hovering(settle_s=2.0), lambda t: cmd, duration_s, rate_hz)


def test_the_warm_up_fit_reads_the_integral_past_the_attitude_lag():
    rng = np.random.default_rng(0)
    jerks = rng.normal(0.0, 1.0, (50, 3))
    c, lag = np.array([0.2, -0.1, 0.05]), 0.18
    diffs = c - lag * jerks + rng.normal(0.0, 0.01, (50, 3))
    diffs[:, 2] = c[2] + rng.normal(0.0, 0.01, 50)  # the tilt lags, the thrust does not
    offset, fitted = integral_offset(diffs, jerks)
    np.testing.assert_allclose(offset, c, atol=0.01)
    assert fitted == pytest.approx(lag, abs=0.01)
    # no jerk (a hover): the mean of the rows, as one noisy row must not decide
    still, no_lag = integral_offset(diffs, np.zeros((50, 3)))
    np.testing.assert_allclose(still, diffs.mean(axis=0), atol=1e-12)
    assert no_lag == 0.0
    assert integral_offset(c + lag * jerks, jerks)[1] == 0.0  # a lead is no lag: clipped at 0
    vertical = integral_offset(c - lag * jerks * [0.0, 0.0, 1.0], jerks)  # up/down: no lag fit
    np.testing.assert_allclose(vertical[0], c - lag * jerks.mean(axis=0) * [0.0, 0.0, 1.0])


@pytest.mark.parametrize(
    "command",
    [
        lambda t: VelocitySetpoint((min(t, 2.0), 0.5 * min(t, 1.0), 0.0)),  # a ramp
        lambda t: VelocitySetpoint((1.5, 0.0, 0.0)),  # a step as OFFBOARD starts
    ],
    ids=["ramp", "step"],
)
def test_a_run_that_starts_accelerating_replays_with_its_own_config(command):
    # a companion mission starts moving as OFFBOARD starts; read as if the attitude were the
    # command, the warm-up took the attitude's lag for an integral (replay error 0.115 m/s on
    # the ramp, 0.093 m/s on the step; past the lag 0.021 and 0.030)
    log = record_offboard(hovering(settle_s=2.0), command, 9.0, 50.0)
    assert replay(load_sim_config("iris"), [log], windows([log])).rmse_mps() < 0.04


def test_attitude_noise_leaves_no_drift_in_hover_windows():
    log = hover_log()
    config = load_sim_config("iris")
    exact = replay(config, [log], windows([log]))
    assert exact.rmse_mps() < 0.005
    drift = []
    for seed in range(4):
        noisy = add_sensor_noise(log, ATTITUDE_ONLY, seed)
        drift.append(replay(config, [noisy], windows([noisy])).rmse_mps())  # against the exact
    # the integral of the warm-up's last row alone: 0.044, 0.105, 0.061, 0.156 m/s (mean 0.092)
    # for these draws; the rest is each window's own start attitude
    assert np.mean(drift) < 0.05, drift
