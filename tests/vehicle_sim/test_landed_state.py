"""The landed state as PX4 reports it in EXTENDED_SYS_STATE: ON_GROUND while on the ground,
TAKEOFF for the whole of an automatic take-off, LANDING while landing, IN_AIR otherwise; never
back and forth within a phase (it read TAKEOFF on the ground, then IN_AIR and TAKEOFF again
within 0.1 s whenever the climb slowed below 0.1 m/s)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from vehicle_sim import FlightMode, LandedState, Simulator, load_sim_config
from vehicle_sim.mission_plan import NAV_WAYPOINT, MissionItem

GROUND, TAKEOFF = LandedState.ON_GROUND, LandedState.TAKEOFF
IN_AIR, LANDING = LandedState.IN_AIR, LandedState.LANDING


def phases(states) -> list[LandedState]:
    """The landed states in the order they came, each run of equal ones once."""
    return [state for state, _ in itertools.groupby(s.landed_state for s in states)]


def fly_for(sim: Simulator, duration_s: float, period_s: float = 0.02) -> list:
    return [sim.step(period_s) for _ in range(round(duration_s / period_s))]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_takeoff_reads_on_ground_then_takeoff_until_it_holds_then_in_air(seed):
    rng = np.random.default_rng(seed)
    sim = Simulator(load_sim_config("iris"), seed=seed)
    assert sim.arm().accepted and sim.takeoff(float(rng.uniform(1.5, 6.0))).accepted
    states = fly_for(sim, 14.0)
    assert phases(states) == [GROUND, TAKEOFF, IN_AIR]
    airborne = [s for s in states if s.landed_state is not GROUND]
    assert all((s.landed_state is TAKEOFF) == (s.mode is FlightMode.TAKEOFF) for s in airborne)


def test_a_landing_reads_landing_until_touchdown_then_on_ground():
    sim = Simulator(load_sim_config("iris"), seed=4)
    assert sim.arm().accepted and sim.takeoff(3.0).accepted
    fly_for(sim, 12.0)
    assert sim.set_mode(FlightMode.LAND).accepted
    assert phases(fly_for(sim, 15.0)) == [LANDING, GROUND]


def test_a_mission_from_the_ground_reads_takeoff_for_its_first_climb():
    sim = Simulator(load_sim_config("iris"), seed=5)
    sim.set_mission((MissionItem(NAV_WAYPOINT, (5.0, 0.0, -3.0), (0.0, 1.0, 0.0, math.nan)),))
    assert sim.arm().accepted and sim.set_mode(FlightMode.MISSION).accepted
    assert phases(fly_for(sim, 10.0))[:3] == [GROUND, TAKEOFF, IN_AIR]
