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
from flightlog.schema import FlightLog
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


def _hold_alt_m(rng: np.random.Generator, low: bool, n: int) -> np.ndarray:
    """``n`` altitudes [m] drawn below (``low``) or above the ground-hold altitude."""
    band = (0.05, NEAR_GROUND_ALT_M - 0.05) if low else (NEAR_GROUND_ALT_M + 0.05, 3.0)
    return rng.uniform(*band, size=n)


def test_segments_split_at_the_ground_hold_altitude():
    """Two airborne runs (a 2 s dropout between them, on the same side of the ground-hold
    altitude) of holds drawn at random, alternating above and below it: each hold is one
    segment, flagged by its side, and none spans the dropout; a 2-row dip inside the first
    hold joins the piece before it."""
    rng = np.random.default_rng(17)
    alt, t, expected, row, t0_s = [], [], [], 0, 0.0
    low = bool(rng.integers(2))
    for run in [rng.integers(6, 40, size=n) for n in rng.integers(3, 7, size=2)]:
        for n in run:
            alt.append(_hold_alt_m(rng, low, n))
            expected.append((row, row + int(n), low))
            row, low = row + int(n), not low
        t.append(t0_s + 0.1 * np.arange(run.sum()))
        t0_s = t[-1][-1] + 2.0  # the dropout: no rows for 2 s
        low = not low  # the next run starts on the side this one ended
    first_stop, first_low = expected[0][1:]
    alt[0][1:3] = _hold_alt_m(rng, not first_low, 2)  # the dip: rows 1 and 2
    expected[0:1] = [(0, 3, first_low), (3, first_stop, first_low)]
    mode = np.full(row, "OFFBOARD")
    log = FlightLog({"t_s": np.concatenate(t), "pos_d_m": -np.concatenate(alt), "mode": mode})
    assert segments(log) == expected


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
