"""A vehicle the companion keeps braking and hovering says why in its progress lines: a
clutter flight whose autopilot sends no OBSTACLE_DISTANCE (no lidar wired to PX4, a simulator
started without --world) hovered at the start for its whole follow time, its lines saying
only 't= 2.0 s   26.91 m to goal', until 'follow deadline passed'."""

from __future__ import annotations

from pathlib import Path

from companion.inprocess_link import InProcessLink
from companion.mission import load_mission
from companion.mission_reference import reference_of
from companion.planner_registry import make_planner
from companion.runner import RunnerConfig, fly_mission
from vehicle_sim import Simulator, load_sim_config

FOREST = Path(__file__).resolve().parents[2] / "missions" / "forest_short.toml"


def test_a_clutter_flight_without_range_scans_says_it_brakes_for_want_of_them():
    mission = load_mission(FOREST)
    link = InProcessLink(Simulator(load_sim_config("iris"), seed=0))  # no world: no scans
    config = RunnerConfig(rate_hz=20.0)
    planner = make_planner("nmpc_clutter", mission.horizontal_command_limit_mps, rate_hz=20.0)
    lines: list[str] = []
    try:
        outcome = fly_mission(
            link, planner, reference_of(mission), mission, config, lambda _t: None, lines.append
        )
    finally:
        link.close()
    assert outcome.status == "goal_not_reached", outcome.detail
    reports = [line for line in lines if "m to goal" in line]
    assert len(reports) > 5
    for line in reports[1:]:  # the first is said before the first step
        assert line.endswith(
            "; braked in 40 of 40 steps (planner failed: no range scan (last never): flying blind)"
        ), line
