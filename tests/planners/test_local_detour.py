"""The shortest detour keeps the clearance from what the map knows, is about as short as the
geometry allows, goes round on the side with room, and says so when there is no way through."""

from __future__ import annotations

import numpy as np
import pytest

from planners.local_detour import ShortestDetour, shortest_detour
from planners.obstacle_map import PointObstacleMap
from planners.path_reference import PolylinePath
from planners.replanner import ReplannerConfig, push_out, resample
from planners.stretch_replanner import BlockedStretch

ALT = -2.5


def _trunk(m: PointObstacleMap, centre_ne_m, radius_m: float) -> None:
    """A trunk's whole surface as map points."""
    th = np.linspace(0.0, 2 * np.pi, 60, endpoint=False)
    c = np.asarray(centre_ne_m, dtype=float)
    m.add_points(
        np.column_stack(
            [c[0] + radius_m * np.cos(th), c[1] + radius_m * np.sin(th), np.full(60, ALT)]
        )
    )


def _dense(vertices: np.ndarray) -> np.ndarray:
    path = PolylinePath(vertices)
    return path.at(np.arange(0.0, path.length_m, 0.02))[0]


@pytest.mark.parametrize("seed", range(5))
def test_the_detour_keeps_the_clearance_and_is_near_the_shortest(seed):
    rng = np.random.default_rng(seed)
    radius, clearance = rng.uniform(0.2, 0.5), rng.uniform(0.6, 1.0)
    offset = rng.uniform(-0.3, 0.3)  # the trunk stands on the line, a little to one side
    m = PointObstacleMap()
    _trunk(m, (5.0, offset), radius)
    a, b = np.array([0.0, 0.0, ALT]), np.array([10.0, 0.0, ALT])
    vertices = shortest_detour(a, b, m, clearance)
    assert vertices is not None
    np.testing.assert_allclose(vertices[[0, -1]], [a, b])
    # every point keeps the clearance, the corners (grid cells) to within half a cell
    # diagonal; the checks are 5 cm apart: a few mm may be lost between them
    assert m.clearance_m(_dense(vertices)).min() >= clearance - 0.2 / np.sqrt(2) - 0.01
    # tangent lines to the grown circle are the shortest way round: within a grid cell of it
    grown = radius + m.point_radius_m + clearance
    bound = 2 * np.hypot(5.0, grown - abs(offset)) + 0.1
    assert PolylinePath(vertices).length_m <= bound
    # round the side with more room: the centre is off the line to the other side
    passing = vertices[np.argmin(np.abs(vertices[:, 0] - 5.0))]
    assert np.sign(passing[1]) == -np.sign(offset) or abs(offset) < 0.05


def test_the_detour_is_shorter_than_the_pushed_out_reference():
    m = PointObstacleMap()
    _trunk(m, (5.0, 0.1), 0.4)
    _trunk(m, (9.0, -0.6), 0.3)
    a, b = np.array([0.0, 0.0, ALT]), np.array([14.0, 0.0, ALT])
    config = ReplannerConfig()
    pushed = push_out(resample(np.vstack([a, b]), 1.0), m, config)
    vertices = shortest_detour(a, b, m, config.clearance_m)
    assert pushed.ok and vertices is not None
    assert PolylinePath(vertices).length_m < pushed.path.length_m


def test_an_end_inside_the_clearance_may_leave_it():
    m = PointObstacleMap()
    _trunk(m, (0.0, 1.0), 0.3)  # the start is 0.6 m from the surface, inside 0.8
    vertices = shortest_detour(np.array([0.0, 0.0, ALT]), np.array([8.0, 0.0, ALT]), m, 0.8)
    assert vertices is not None
    assert m.clearance_m(_dense(vertices)).min() > 0.5


def test_no_detour_through_a_closed_wall():
    m = PointObstacleMap()
    for e in np.arange(-8.0, 8.01, 0.3):
        _trunk(m, (5.0, e), 0.2)
    assert shortest_detour(np.array([0.0, 0.0, ALT]), np.array([10.0, 0.0, ALT]), m, 0.8) is None


def test_the_splice_replaces_the_blocked_waypoints_up_to_the_first_clear_one_beyond_rejoin():
    m = PointObstacleMap()
    _trunk(m, (6.0, 0.1), 0.4)
    waypoints = resample(np.array([[0.0, 0.0, ALT], [20.0, 0.0, ALT]]), 1.0)
    replanner = ShortestDetour(clearance_m=0.8, spacing_m=1.0, rejoin_m=8.0)
    splice = replanner.splice(BlockedStretch(waypoints, 2, waypoints[-1]), m)
    assert splice is not None
    assert splice.end == 10  # 8 m ahead of waypoint 2, and clear
    spliced = np.vstack([waypoints[:3], splice.points_ned_m, waypoints[splice.end :]])
    assert m.clearance_m(_dense(spliced)).min() >= 0.8 - 0.2 / np.sqrt(2) - 1e-9
    assert np.abs(spliced[3:-10, 1]).max() > 0.5  # it goes round, not through


def test_no_splice_when_nothing_ahead_is_clear():
    m = PointObstacleMap()
    for north in np.arange(2.0, 21.0, 1.0):
        _trunk(m, (north, 0.0), 0.3)
    waypoints = resample(np.array([[0.0, 0.0, ALT], [20.0, 0.0, ALT]]), 1.0)
    replanner = ShortestDetour(clearance_m=0.8, spacing_m=1.0, rejoin_m=8.0)
    assert replanner.splice(BlockedStretch(waypoints, 0, waypoints[-1]), m) is None
