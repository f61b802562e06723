"""The landed state as PX4 reports it in EXTENDED_SYS_STATE: ON_GROUND while on the ground,
TAKEOFF for the whole of an automatic take-off (a mission's from the ground up to its first
NAV_TAKEOFF's or waypoint's altitude; a NAV_TAKEOFF begun in the air reads IN_AIR, as in PX4),
LANDING while landing, IN_AIR otherwise; never back and forth within a phase (it read TAKEOFF
on the ground, then IN_AIR and TAKEOFF again within 0.1 s whenever the climb slowed below
0.1 m/s)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from vehicle_sim import FlightMode, LandedState, Simulator, load_sim_config
from vehicle_sim.mission_plan import DO_CHANGE_SPEED, NAV_TAKEOFF, NAV_WAYPOINT, MissionItem

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


@pytest.mark.parametrize("seed", [9, 10])
def test_a_mission_whose_first_item_is_a_waypoint_climbs_straight_up_to_its_altitude(seed):
    # PX4 inserts a take-off to the first waypoint's altitude (calculate_takeoff_altitude); the
    # climb stopped at MIS_TAKEOFF_ALT (2.5 m) and went on diagonally, reading IN_AIR
    rng = np.random.default_rng(seed)
    alt_m, north_m = float(rng.uniform(3.5, 8.0)), float(rng.uniform(5.0, 10.0))
    sim = Simulator(load_sim_config("iris"), seed=seed)
    waypoint = MissionItem(NAV_WAYPOINT, (north_m, 0.0, -alt_m), (0.0, 1.0, 0.0, math.nan))
    sim.set_mission((waypoint,))
    assert sim.arm().accepted and sim.set_mode(FlightMode.MISSION).accepted
    states = fly_for(sim, 4.0 + alt_m / 1.5)  # MPC_TKO_SPEED 1.5 m/s
    assert phases(states)[:3] == [GROUND, TAKEOFF, IN_AIR]
    climbing = [s for s in states if s.landed_state is TAKEOFF]
    assert max(-s.pos_ned_m[2] for s in climbing) == pytest.approx(alt_m, abs=0.35)
    assert max(abs(s.pos_ned_m[0]) for s in climbing) < 0.3  # straight up, then across


def takeoff_mission(way: str, takeoff_alt_m: float) -> tuple[tuple[MissionItem, ...], int]:
    """A mission whose NAV_TAKEOFF to ``takeoff_alt_m`` comes first, after a speed change, or
    after a waypoint with the current item set to it; and that current item."""
    takeoff = MissionItem(NAV_TAKEOFF, (math.nan, math.nan, -takeoff_alt_m))
    then = MissionItem(NAV_WAYPOINT, (4.0, 0.0, -takeoff_alt_m), (0.0, 1.0, 0.0, math.nan))
    before = {
        "first": (),
        "after_a_speed_change": (MissionItem(DO_CHANGE_SPEED, params=(1.0, 2.0, -1.0, 0.0)),),
        "set_current": (MissionItem(NAV_WAYPOINT, (9.0, 9.0, -3.0)),),
    }[way]
    return (*before, takeoff, then), 1 if way == "set_current" else 0


@pytest.mark.parametrize("way", ["first", "after_a_speed_change", "set_current"])
@pytest.mark.parametrize("seed", [6, 7])
def test_a_nav_takeoff_from_the_ground_reads_takeoff_until_it_reaches_its_altitude(way, seed):
    # the climb read TAKEOFF only to MIS_TAKEOFF_ALT (2.5 m), then IN_AIR up to the item's own
    takeoff_alt_m = float(np.random.default_rng(seed).uniform(3.5, 8.0))
    sim = Simulator(load_sim_config("iris"), seed=seed)
    items, current = takeoff_mission(way, takeoff_alt_m)
    sim.set_mission(items)
    assert sim.set_mission_current(current).accepted
    assert sim.arm().accepted and sim.set_mode(FlightMode.MISSION).accepted
    states = fly_for(sim, 4.0 + takeoff_alt_m / 1.5)  # MPC_TKO_SPEED 1.5 m/s
    assert phases(states)[:3] == [GROUND, TAKEOFF, IN_AIR]
    climbing = [-s.pos_ned_m[2] for s in states if s.landed_state is TAKEOFF]
    assert max(climbing) == pytest.approx(takeoff_alt_m, abs=0.35)
    assert len(items) - 2 in sim.drain_mission_reached()  # the NAV_TAKEOFF, done


def test_a_nav_takeoff_that_becomes_current_in_the_air_reads_in_air_as_px4_reports_it():
    # PX4 flies a NAV_TAKEOFF item begun in the air as a position setpoint ([PX4-mission-takeoff])
    sim = Simulator(load_sim_config("iris"), seed=8)
    assert sim.arm().accepted and sim.takeoff(2.5).accepted
    fly_for(sim, 8.0)
    takeoff_alt_m = float(np.random.default_rng(8).uniform(4.0, 8.0))
    sim.set_mission((MissionItem(NAV_TAKEOFF, (math.nan, math.nan, -takeoff_alt_m)),))
    assert sim.set_mode(FlightMode.MISSION).accepted
    states = fly_for(sim, 8.0)
    assert phases(states) == [IN_AIR]
    assert -states[-1].pos_ned_m[2] == pytest.approx(takeoff_alt_m, abs=0.35)
