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
