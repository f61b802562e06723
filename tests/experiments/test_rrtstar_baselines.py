"""The two RRT* baselines plan round what they know: the known forest, or the sensed points,
with the clearance; a vehicle already inside the clearance may leave it."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("ompl")

from experiments.clutter.rrtstar import plan_rrtstar, plan_rrtstar_in_map  # noqa: E402
from planners.obstacles import Cylinder, ObstacleWorld  # noqa: E402
from planners.path_reference import PolylinePath  # noqa: E402

BOUNDS = (-5.0, 25.0, -10.0, 10.0)


def _dense(path_ne_m: np.ndarray) -> np.ndarray:
    pts = np.column_stack([path_ne_m, np.full(len(path_ne_m), -2.5)])
    line = PolylinePath(pts)
    return line.at(np.arange(0.0, line.length_m, 0.02))[0]


def _arc_points(centre_ne_m, radius_m: float) -> np.ndarray:
    th = np.linspace(0.0, 2 * np.pi, 48, endpoint=False)
    return np.column_stack(
        [centre_ne_m[0] + radius_m * np.cos(th), centre_ne_m[1] + radius_m * np.sin(th)]
    )


def test_rrtstar_in_the_known_forest_keeps_the_clearance():
    world = ObstacleWorld([Cylinder((10.0, 0.2), 0.5), Cylinder((14.0, -1.5), 0.4)])
    path = plan_rrtstar(world, np.zeros(2), np.array([20.0, 0.0]), BOUNDS, 0.8, 3000)
    assert path is not None
    np.testing.assert_allclose(path[[0, -1]], [[0.0, 0.0], [20.0, 0.0]])
    assert world.clearance_m(_dense(path)).min() >= 0.8 - 0.05  # the grid is conservative


def test_rrtstar_in_the_sensed_map_keeps_the_clearance_from_the_points():
    points = _arc_points((10.0, 0.0), 0.5)
    radius = 0.1
    path = plan_rrtstar_in_map(
        points, radius, np.zeros(2), np.array([20.0, 0.0]), BOUNDS, 0.8, 3000
    )
    assert path is not None
    dense = _dense(path)[:, :2]
    gaps = np.linalg.norm(dense[:, None, :] - points[None, :, :], axis=2).min(axis=1) - radius
    assert gaps.min() >= 0.8 - 0.05


def test_a_start_inside_the_clearance_may_leave_it_but_not_cross_the_obstacle():
    points = _arc_points((0.0, 1.0), 0.3)  # the start is 0.6 m from the surface, inside 0.8
    path = plan_rrtstar_in_map(points, 0.1, np.zeros(2), np.array([15.0, 0.0]), BOUNDS, 0.8, 3000)
    assert path is not None
    dense = _dense(path)[:, :2]
    gaps = np.linalg.norm(dense[:, None, :] - points[None, :, :], axis=2).min(axis=1) - 0.1
    assert gaps.min() > 0.5
