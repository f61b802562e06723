"""When following is over: at the goal, after the reference, and slow enough to count as stopped."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from companion.link import LinkState
from companion.mission import load_mission
from companion.runner import RunnerConfig, _FollowMonitor
from tests.companion.test_companion_mission_on_every_link import LINE
from tests.companion.test_companion_planner_policy import state


def _state(t_s: float, pos_ned_m, vel_ned_mps) -> LinkState:
    return replace(state(pos_ned_m, vel_ned_mps), t_s=t_s)


def test_a_vehicle_at_the_goal_arrives_only_once_slower_than_arrive_speed() -> None:
    """LINE's goal is 20 m north at 2.5 m (tolerance 0.3 m); with a 10 s reference and the
    default arrive_speed_mps 0.3 m/s: 0.1 m from the goal after 12 s at 0.5 m/s is passing
    through, not arrived; at 0.2 m/s it has arrived; at 5 s (reference still running) not."""
    mission = load_mission(LINE)
    goal = np.array(mission.goal_ned_m)
    monitor = _FollowMonitor(0.0, goal, 10.0, mission, RunnerConfig(), lambda _m: None)
    near = goal + [0.1, 0.0, 0.0]
    assert not monitor.finished(_state(5.0, near, [0.2, 0.0, 0.0]), 5.0)
    assert not monitor.finished(_state(12.0, near, [0.5, 0.0, 0.0]), 12.0)
    assert monitor.finished(_state(12.1, near, [0.2, 0.0, 0.0]), 12.1)
    assert monitor.taken_over is None
