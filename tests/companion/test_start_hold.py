"""The start hold: the reference's clock starts only once the vehicle has settled over the point
it took off to, whatever wind blew it off during the climb (real simulator, real runner)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from companion.flight_recorder import FlightRecorder
from companion.inprocess_link import InProcessLink
from companion.mission import Mission
from companion.planner_registry import make_planner
from companion.runner import RunnerConfig, fly_mission
from planners.bspline import BSplineReference
from vehicle_sim import Simulator, load_sim_config

START = np.array([0.0, 0.0, -3.0])


def _fly(wind_ned_mps: np.ndarray, seed: int, config: RunnerConfig) -> tuple[np.ndarray, str]:
    """Fly a short spline from START through a steady wind; the first OFFBOARD row's position
    and velocity (6,) and the outcome's status."""
    sim_config = load_sim_config(
        "iris_study", {"wind": {"vel_ned_mps": [float(w) for w in wind_ned_mps]}}
    )
    link = InProcessLink(Simulator(sim_config, seed=seed))
    points = START + np.array([[0.0, 0.0, 0.0], [3.0, 1.0, 0.0], [6.0, 0.0, 0.0]])
    reference = BSplineReference(points, 1.0, 1.0)
    mission = Mission(
        name="hold",
        altitude_m=3.0,
        speed_limit_mps=1.0,
        reference_kind="bspline",
        points_ned_m=tuple(tuple(float(c) for c in p) for p in points),
        goal_tolerance_m=0.5,
    )
    recorder = FlightRecorder(period_s=1.0 / config.rate_hz, wall_clock_columns=False)
    outcome = fly_mission(
        link, make_planner("pd", 2.0), reference, mission, config, recorder.record, lambda m: None
    )
    log = recorder.to_log({"source": "test"})
    first = int(np.flatnonzero(log["mode"] == "OFFBOARD")[0])
    pos = log.stack("pos_n_m", "pos_e_m", "pos_d_m")[first]
    vel = log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")[first]
    return np.concatenate([pos, vel]), outcome.status


def test_reference_starts_settled_in_a_drawn_wind_and_not_without_the_hold() -> None:
    rng = np.random.default_rng(2026)
    for _ in range(2):
        heading = rng.uniform(-np.pi, np.pi)
        speed = rng.uniform(4.0, 6.0)  # enough to blow the vehicle off during the climb
        wind = speed * np.array([np.cos(heading), np.sin(heading), 0.0])
        seed = int(rng.integers(0, 1000))
        tolerance_m = rng.uniform(0.08, 0.2)
        tolerance_mps = rng.uniform(0.08, 0.2)
        held = RunnerConfig(
            start_position_tolerance_m=tolerance_m, start_speed_tolerance_mps=tolerance_mps
        )
        state, status = _fly(wind, seed, held)
        assert status == "completed"
        assert np.linalg.norm(state[:3] - START) <= tolerance_m
        assert np.linalg.norm(state[3:]) <= tolerance_mps
        unheld, status = _fly(wind, seed, replace(held, start_settle_timeout_s=0.0))
        assert status == "completed"
        assert np.linalg.norm(unheld[:3] - START) > 2.0 * tolerance_m  # the hold mattered


def test_calm_takeoff_waits_no_longer_than_the_stream() -> None:
    """Without steady wind (the study vehicle's gusts only) the vehicle has settled when the
    setpoint stream ends: the switch to OFFBOARD comes at the same tick with and without the
    hold."""
    calm = np.zeros(3)
    held, _ = _fly(calm, 3, RunnerConfig())
    unheld, _ = _fly(calm, 3, RunnerConfig(start_settle_timeout_s=0.0))
    np.testing.assert_array_equal(held, unheld)


def test_bad_start_hold_settings_are_refused_in_one_line() -> None:
    with pytest.raises(ValueError, match="start_position_tolerance_m"):
        RunnerConfig(start_position_tolerance_m=0.0)
    with pytest.raises(ValueError, match="start_settle_timeout_s"):
        RunnerConfig(start_settle_timeout_s=-1.0)
