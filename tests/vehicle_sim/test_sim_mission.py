"""AUTO.MISSION in process: items flown in order by the position control, then RTL."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vehicle_sim import FlightMode, LandedState, Simulator, load_sim_config
from vehicle_sim.mission_plan import (
    DO_CHANGE_SPEED,
    NAV_LAND,
    NAV_RETURN_TO_LAUNCH,
    NAV_TAKEOFF,
    NAV_WAYPOINT,
    MissionItem,
)

NAN = math.nan


def fly_until(sim: Simulator, predicate, limit_s: float) -> list:
    states = []
    for _ in range(round(limit_s / 0.1)):
        states.append(sim.step(0.1))
        if predicate(states[-1]):
            return states
    raise AssertionError(f"not reached within {limit_s} s; mode {sim.state.mode}")


def test_a_mission_from_the_ground_flies_its_items_in_order_then_returns_and_lands():
    sim = Simulator(load_sim_config("iris"), seed=2)
    sim.set_param("RTL_RETURN_ALT", 6.0)
    sim.set_mission(
        (
            MissionItem(NAV_TAKEOFF, (NAN, NAN, -4.0)),
            MissionItem(NAV_WAYPOINT, (10.0, 0.0, -4.0), (1.0, 1.0, 0.0, NAN)),
            MissionItem(DO_CHANGE_SPEED, params=(1.0, 2.0, -1.0, 0.0)),
            MissionItem(NAV_WAYPOINT, (10.0, 8.0, -5.0), (0.0, 1.0, 0.0, NAN)),
            MissionItem(NAV_RETURN_TO_LAUNCH),
        )
    )
    assert sim.set_mode(FlightMode.MISSION).result == "denied"  # not armed
    assert sim.arm().accepted and sim.set_mode(FlightMode.MISSION).accepted
    reached: list[int] = []
    states = fly_until(
        sim,
        lambda s: reached.extend(sim.drain_mission_reached()) or (not s.armed and s.t_s > 5.0),
        120.0,
    )
    assert reached == [0, 1, 2, 3, 4]
    modes = [s.mode for s in states]
    assert (
        modes.index(FlightMode.MISSION) < modes.index(FlightMode.RTL) < modes.index(FlightMode.LAND)
    )
    in_mission = np.array([s.pos_ned_m for s in states if s.mode is FlightMode.MISSION])
    assert np.min(np.linalg.norm(in_mission[:, :2] - (10.0, 0.0), axis=1)) < 1.0
    assert np.min(np.linalg.norm(in_mission - (10.0, 8.0, -5.0), axis=1)) < 1.2
    speeds = [np.hypot(*s.vel_ned_mps[:2]) for s in states if s.mode is FlightMode.MISSION]
    assert max(speeds) < 5.3  # MPC_XY_CRUISE, then the mission's 2 m/s
    final = states[-1]
    assert final.landed_state is LandedState.ON_GROUND and np.hypot(*final.pos_ned_m[:2]) < 0.8
    assert sim.mission_current == 5


def test_mission_current_can_be_set_and_an_empty_mission_is_refused():
    sim = Simulator(load_sim_config("iris"))
    assert sim.arm().accepted
    assert sim.set_mode(FlightMode.MISSION).result == "denied"
    sim.set_mission((MissionItem(NAV_TAKEOFF, (NAN, NAN, -3.0)), MissionItem(NAV_LAND)))
    assert sim.set_mission_current(1).accepted and sim.mission_current == 1
    assert sim.set_mission_current(2).result == "denied"
    assert sim.set_mode(FlightMode.MISSION).accepted
    states = fly_until(sim, lambda s: s.mode is FlightMode.LAND, 30.0)
    assert -states[-1].pos_ned_m[2] == pytest.approx(2.5, abs=0.4)  # took off, then landed
