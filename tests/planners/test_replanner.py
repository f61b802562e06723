"""The replanner pushes a reference out of the known obstacles with the clearance; the
regeneration triggers beyond the documented distance; the path reference moves as promised."""

from __future__ import annotations

import numpy as np
import pytest

from planners.obstacle_map import PointObstacleMap
from planners.obstacles import Cylinder, ObstacleWorld
from planners.path_reference import PathReference, PolylinePath
from planners.replanner import ReplannerConfig, needs_regeneration, push_out, resample

ANGLES = np.arange(72) * (2 * np.pi / 72)
DIRS = np.column_stack([np.cos(ANGLES), np.sin(ANGLES), np.zeros(72)])


def _mapped(world: ObstacleWorld, along_n_m: np.ndarray, east_m: float) -> PointObstacleMap:
    m = PointObstacleMap()
    for n in along_n_m:
        o = np.array([n, east_m, -2.5])
        m.add_scan(o, ANGLES, world.ray_distance_m(o, DIRS, 5.0))
    return m


@pytest.mark.parametrize("offset_e_m", [0.0, 0.2, -0.35])
def test_a_reference_through_trunks_is_pushed_out_with_the_clearance(offset_e_m):
    world = ObstacleWorld([Cylinder((8.0, offset_e_m), 0.4), Cylinder((14.0, 1.2), 0.3)])
    # seen from both sides of the line, as a vehicle passing by would
    m = _mapped(world, np.arange(0.0, 22.0, 1.0), -2.0)
    for n in np.arange(0.0, 22.0, 1.0):
        o = np.array([n, 2.5, -2.5])
        m.add_scan(o, ANGLES, world.ray_distance_m(o, DIRS, 5.0))
    straight = resample(np.array([[0.0, 0.0, -2.5], [20.0, 0.0, -2.5]]), 1.0)
    config = ReplannerConfig(clearance_m=0.9)
    assert world.clearance_m(straight).min() < 0.0  # the line goes through a trunk
    replan = push_out(straight, m, config)
    assert replan.ok and replan.min_clearance_m >= config.clearance_m
    # the map knows the trunks' surfaces to within a point's radius and a voxel
    assert world.clearance_m(replan.path.points_ned_m).min() >= config.clearance_m - 0.3
    np.testing.assert_allclose(replan.path.points_ned_m[[0, -1]], straight[[0, -1]], atol=1e-9)
    assert replan.path.length_m < 1.2 * 20.0  # around, not away


def test_a_reference_already_clear_is_left_alone():
    m = PointObstacleMap()
    m.add_points([[5.0, 4.0, -2.5]])
    wp = resample(np.array([[0.0, 0.0, -2.5], [10.0, 0.0, -2.5]]), 1.0)
    np.testing.assert_allclose(push_out(wp, m, ReplannerConfig()).waypoints_ned_m, wp)


@pytest.mark.parametrize(("gap_m", "expected"), [(1.99, False), (2.01, True)])
def test_regeneration_triggers_beyond_two_metres(gap_m, expected):
    config = ReplannerConfig()
    assert config.regenerate_distance_m == 2.0  # [Kulathunga23] Fig. 7
    ref = np.array([3.0, 4.0, -2.5])
    direction = np.array([0.6, -0.8, 0.0])
    assert needs_regeneration(ref + gap_m * direction, ref, config) is expected


def test_path_reference_moves_at_the_speed_and_stops_at_the_end():
    path = PolylinePath(np.array([[0.0, 0.0, -2.0], [10.0, 0.0, -2.0], [10.0, 5.0, -2.0]]))
    ref = PathReference(path, s0_m=2.0, t0_s=1.0, max_speed_mps=1.5, max_acc_mps2=1.0)
    smp = ref.sample(np.array([0.0, 1.0, 2.0, ref.duration_s + 1.0]))
    np.testing.assert_allclose(smp.pos_ned_m[:3, 0], [2.0, 2.0, 3.5], atol=0.01)
    np.testing.assert_allclose(smp.vel_ned_mps[1], [1.5, 0.0, 0.0])
    np.testing.assert_allclose(smp.pos_ned_m[3], [10.0, 5.0, -2.0])
    np.testing.assert_allclose(smp.vel_ned_mps[3], 0.0)
    assert path.project(np.array([10.4, 2.0, -2.0]), 0.0, 15.0) == pytest.approx(12.0)
