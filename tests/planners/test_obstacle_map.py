"""The KD-tree map: built from scans within range, de-duplicated, nearest per node as slots."""

from __future__ import annotations

import numpy as np
import pytest

from planners.nmpc_formulation import UNUSED_SLOT
from planners.obstacle_map import PointObstacleMap
from planners.obstacles import Cylinder, ObstacleWorld

ANGLES = np.arange(72) * (2 * np.pi / 72)
DIRS = np.column_stack([np.cos(ANGLES), np.sin(ANGLES), np.zeros(72)])


def _scan(world, origin, max_range=8.0):
    return world.ray_distance_m(np.asarray(origin, float), DIRS, max_range)


def test_only_hits_within_the_update_range_enter_and_only_once():
    world = ObstacleWorld([Cylinder((3.0, 0.0), 0.4), Cylinder((0.0, 7.0), 0.4)])
    m = PointObstacleMap(update_range_m=5.0)
    first = m.add_scan([0, 0, -2], ANGLES, _scan(world, [0, 0, -2]))
    assert first > 0 and np.all(np.abs(m.points_ned_m[:, 0] - 3.0) < 0.5)  # not the far trunk
    assert m.add_scan([0, 0, -2], ANGLES, _scan(world, [0, 0, -2])) == 0
    assert m.version == 1


def test_clearance_is_close_to_the_true_one_on_the_seen_side():
    world = ObstacleWorld([Cylinder((3.0, 0.0), 0.4)])
    m = PointObstacleMap(point_radius_m=0.0)
    m.add_scan([0, 0, -2], ANGLES, _scan(world, [0, 0, -2]))
    q = np.array([[1.0, 0.0, -2.0], [2.0, -0.3, -2.0]])
    np.testing.assert_allclose(m.clearance_m(q), world.clearance_m(q), atol=0.1)


def test_each_node_gets_its_own_nearest_points():
    m = PointObstacleMap(voxel_m=0.01, point_radius_m=0.1)
    # a cluster of 5 points near node A, one point near node B far away
    m.add_points([[1.0 + 0.05 * k, 0.0, 0.0] for k in range(5)] + [[20.0, 3.0, 0.0]])
    nodes = np.array([[0.0, 0.0, 0.0], [20.0, 0.0, 0.0]])
    slots = m.slots(nodes, count=3, safe_distance_m=0.5)
    assert slots.shape == (2, 3, 7)
    np.testing.assert_allclose(slots[0, :, :2], [[1.0, 0.0], [1.05, 0.0], [1.1, 0.0]])
    np.testing.assert_allclose(slots[1, 0, :2], [20.0, 3.0])  # B's own, nearest first
    np.testing.assert_allclose(slots[..., 3:], np.tile([1, 1, 0, 0.6], (2, 3, 1)))
    padded = m.slots(nodes, 8, 0.5)
    np.testing.assert_array_equal(padded[:, 6:], np.tile(UNUSED_SLOT, (2, 2, 1)))


def test_an_empty_map_is_free_space():
    m = PointObstacleMap()
    assert np.isinf(m.clearance_m(np.zeros((2, 3)))).all()
    np.testing.assert_array_equal(
        m.slots(np.zeros((1, 3)), 2, 0.5), np.tile(UNUSED_SLOT, (1, 2, 1))
    )


@pytest.mark.parametrize(
    "obstacle",
    [Cylinder((float("nan"), 0.0), 0.4), Cylinder((3.0, 0.0), float("inf"))],
)
def test_a_world_refuses_an_obstacle_it_could_not_measure_a_clearance_to(obstacle):
    """A NaN clearance passes every comparison; the world says which obstacle, in one line."""
    with pytest.raises(ValueError, match=r"^obstacle 1 \(Cylinder.*non-finite") as err:
        ObstacleWorld([Cylinder((0.0, 7.0), 0.4), obstacle])
    assert "\n" not in str(err.value)
