"""Closed-loop scoring: flight segments and ground holds apart, and a simulated vehicle that
touches down where the logged one flew is re-anchored and its segment left out."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from diagnosis.closed_loop import NEAR_GROUND_ALT_M, closed_loop, segments
from diagnosis.excitation import schedule_from_mapping
from diagnosis.fly_schedule import fly_schedule
from diagnosis.replay import windows
from vehicle_sim import load_sim_config

SCHEDULE = schedule_from_mapping(
    {
        "takeoff_alt_m": 2.0,
        "segment": [
            {"kind": "hover", "duration_s": 3.0},
            {"kind": "velocity", "duration_s": 3.0, "speed_mps": 2.0, "heading_deg": 0.0},
            {"kind": "hover", "duration_s": 3.0},
        ],
    }
)


@pytest.fixture(scope="module")
def flight():
    return fly_schedule(load_sim_config("iris"), SCHEDULE)


def test_segments_split_at_the_ground_hold_altitude(flight):
    alt = -flight["pos_d_m"]
    for start, stop, near_ground in segments(flight):
        assert np.all((alt[start:stop] < NEAR_GROUND_ALT_M) == near_ground)


def test_a_vehicle_that_cannot_fly_the_segment_is_reanchored_and_not_scored(flight):
    wins = windows([flight])
    heavy = replace(  # needs 0.78 of the thrust to hover, may use 0.6
        load_sim_config("iris", {"payload": {"mass_ratio": 1.5}}),
        px4_params=(("MPC_THR_MAX", 0.6),),
    )
    result = closed_loop(load_sim_config("iris"), heavy, [flight], wins)
    assert result.segments >= 1 and result.reanchored == result.segments
    assert not result.scored.any()
    assert np.isnan(result.gain())
    same = closed_loop(load_sim_config("iris"), load_sim_config("iris"), [flight], wins)
    assert same.reanchored == 0 and same.scored.all()
    assert same.baseline_rmse_mps() < 0.01
