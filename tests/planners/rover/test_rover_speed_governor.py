"""The within-trial safety governor: trips past trip_factor times the scheduler's thresholds,
holds v_init until both errors are back under the thresholds, counts its trips."""

import math

import pytest

from planners.rover.speed_governor import SpeedGovernor
from planners.rover.speed_scheduler import TABLE_I


def test_governor_trips_holds_and_releases_with_hysteresis() -> None:
    cfg = TABLE_I["experiment_3"]  # lambda_L 0.15 m, lambda_H 10 deg, v_init 0.5 m/s
    gov = SpeedGovernor(cfg, trip_factor=2.0)
    assert gov.cap_mps(0.29, 0.0) == math.inf  # under 2 x 0.15 m
    assert gov.cap_mps(-0.31, 0.0) == cfg.v_init_mps  # past it (either side)
    assert gov.cap_mps(0.2, 0.0) == cfg.v_init_mps  # back under the trip, not the threshold
    assert gov.cap_mps(0.1, math.radians(12.0)) == cfg.v_init_mps  # heading still over 10 deg
    assert gov.cap_mps(0.1, math.radians(5.0)) == math.inf  # both under: released
    assert gov.cap_mps(0.0, math.radians(21.0)) == cfg.v_init_mps  # heading alone trips it
    assert gov.trips == 2


def test_governor_refuses_a_trip_factor_at_or_under_one() -> None:
    with pytest.raises(ValueError, match="trip_factor"):
        SpeedGovernor(TABLE_I["experiment_2"], trip_factor=1.0)


def test_governor_trips_on_a_heading_error_to_either_side() -> None:
    cfg = TABLE_I["experiment_3"]  # lambda_H 10 deg: trips past 20 deg
    gov = SpeedGovernor(cfg, trip_factor=2.0)
    assert gov.cap_mps(0.0, math.radians(-21.0)) == cfg.v_init_mps
    assert gov.trips == 1


def test_governor_needs_errors_past_the_trip_and_strictly_under_the_thresholds() -> None:
    cfg = TABLE_I["experiment_3"]
    gov = SpeedGovernor(cfg, trip_factor=2.0)
    # Exactly at trip_factor x threshold is not past it.
    assert gov.cap_mps(2.0 * cfg.lambda_lat_m, 0.0) == math.inf
    assert gov.cap_mps(0.0, 2.0 * cfg.lambda_head_rad) == math.inf
    assert gov.trips == 0
    assert gov.cap_mps(1.0, 0.0) == cfg.v_init_mps
    # Exactly at a threshold is not back under it: the cap holds.
    assert gov.cap_mps(cfg.lambda_lat_m, 0.0) == cfg.v_init_mps
    assert gov.cap_mps(0.0, cfg.lambda_head_rad) == cfg.v_init_mps
    assert gov.cap_mps(0.0, 0.0) == math.inf
