"""The replay's warm-up restores the velocity-loop integral from the mean of its rows, so one
noisy row's attitude does not stay in every window of the run as an acceleration bias."""

from __future__ import annotations

import numpy as np

from diagnosis import sim_anchor
from diagnosis.replay import replay, windows
from flightlog.schema import FlightLog
from tests.vehicle_sim.sim_flying import hovering, record_offboard
from vehicle_sim import AnchorState, VelocitySetpoint, load_sim_config
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


def test_the_warm_up_integral_is_the_running_mean_of_the_rows_matched():
    config = load_sim_config("iris")
    template = sim_anchor.hovering_template(config)
    rng = np.random.default_rng(0)
    hover_n = config.mass_kg * 9.80665
    states = []
    for _ in range(8):
        tilt = 0.5 * np.radians(1.0) * rng.normal(size=3)
        q = np.r_[1.0, tilt] / np.linalg.norm(np.r_[1.0, tilt])
        states.append(
            AnchorState((0.0, 0.0, -5.0), (0.0, 0.0, 0.0), q, (0.0,) * 3, hover_n, (0.0,) * 3)
        )
    single = []
    for s in states:
        one = sim_anchor.fresh_copy(template)
        one.anchor(s, integral="match_thrust")
        single.append(one.velocity_integral_mps2)
    averaged = sim_anchor.fresh_copy(template)
    for k, s in enumerate(states, start=1):
        sim_anchor.anchor_matching_thrust(averaged, s, k)
    np.testing.assert_allclose(averaged.velocity_integral_mps2, np.mean(single, axis=0), atol=1e-12)
    assert np.ptp(np.array(single)[:, 0]) > 0.1  # the rows' own integrals differ by the noise


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
