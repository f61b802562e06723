"""The replay's warm-up fits the velocity-loop integral a run starts with by output error: a
vehicle hovering against a force, or already accelerating as OFFBOARD starts, replays with its
own config, and noise on one row's attitude or velocity does not stay in every window of the
run as an acceleration bias."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from diagnosis.replay import replay, replay_sse, windows
from flightlog.schema import FlightLog
from tests.vehicle_sim.sim_flying import hovering, record_offboard
from vehicle_sim import VelocitySetpoint, load_sim_config
from vehicle_sim.sensor_noise import SensorNoise, add_sensor_noise

ATTITUDE_ONLY = dataclasses.replace(SensorNoise.none(), attitude_deg=1.0)


def hover_log(duration_s: float = 9.0, rate_hz: float = 20.0) -> FlightLog:
    """An exact log of an Iris hovering in OFFBOARD on a zero velocity setpoint."""
    cmd = VelocitySetpoint((0.0, 0.0, 0.0))
    return record_offboard(hovering(settle_s=2.0), lambda t: cmd, duration_s, rate_hz)


@pytest.mark.parametrize(
    "effects",
    [
        {"payload": {"mass_ratio": 1.3}},
        {"wind": {"vel_ned_mps": (4.0, -3.0, 0.0)}, "isotropic_drag": {"k_n_per_mps2": 0.05}},
    ],
    ids=["payload", "wind"],
)
def test_a_run_that_starts_with_a_wound_up_integral_replays_with_its_own_config(effects):
    # the vehicle hovered against the force before the log starts: its integral holds it
    log = record_offboard(
        hovering(effects, settle_s=8.0), lambda t: VelocitySetpoint((min(t, 1.5), 0.0, 0.0)),
        6.0, 50.0,
    )  # fmt: skip
    config = load_sim_config("iris", effects)
    assert replay(config, [log], windows([log])).rmse_mps() < 0.002


@pytest.mark.parametrize(
    "command",
    [
        lambda t: VelocitySetpoint((min(t, 2.0), 0.5 * min(t, 1.0), 0.0)),  # a ramp
        lambda t: VelocitySetpoint((1.5, 0.0, 0.0)),  # a step as OFFBOARD starts
    ],
    ids=["ramp", "step"],
)
def test_a_run_that_starts_accelerating_replays_with_its_own_config(command):
    # a companion mission starts moving as OFFBOARD starts; read off the thrust vector as if the
    # attitude were the command, the warm-up took the attitude's lag for an integral (replay
    # error 0.115 m/s on the ramp, 0.093 m/s on the step; with a lag term fitted 0.021 and 0.030)
    log = record_offboard(hovering(settle_s=2.0), command, 9.0, 50.0)
    assert replay(load_sim_config("iris"), [log], windows([log])).rmse_mps() < 0.002


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


def test_a_search_stops_a_replay_only_when_its_error_exceeds_the_bound():
    """replay_sse is the replay's summed squared error; a bound equal to it is not exceeded
    (a config exactly as good as the best so far is replayed to the end), one just under it is."""
    log = hover_log()
    config, wins = load_sim_config("iris"), windows([log])
    result = replay(config, [log], wins)
    err = result.sim_vel_ned_mps - result.meas_vel_ned_mps
    sse = replay_sse(config, [log], wins, math.inf)
    assert sse > 0.0 and np.isclose(sse, np.sum(err * err), rtol=1e-12)
    assert replay_sse(config, [log], wins, sse) == sse
    assert replay_sse(config, [log], wins, 0.999 * sse) == math.inf
