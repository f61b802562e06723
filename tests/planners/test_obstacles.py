import numpy as np
import pytest

from planners.nmpc_formulation import UNUSED_SLOT
from planners.obstacles import Cylinder, ObstacleWorld, Sphere, random_forest


def test_distances_sphere_and_cylinder():
    world = ObstacleWorld([Sphere((0.0, 0.0, -2.0), 1.0), Cylinder((10.0, 0.0), 0.5)])
    pts = np.array([[0.0, 3.0, -2.0], [10.0, 2.0, -50.0], [0.0, 0.5, -2.0]])
    d = world.surface_distance_m(pts)
    np.testing.assert_allclose(d[0], [2.0, np.hypot(10.0, 3.0) - 0.5])
    np.testing.assert_allclose(d[1, 1], 1.5)  # cylinder ignores altitude
    np.testing.assert_allclose(world.clearance_m(pts), [2.0, 1.5, -0.5])


def test_slots_pick_each_nodes_nearest_and_pad_unused():
    obstacles = [Sphere((float(k), 0.0, 0.0), 0.1) for k in (5, 1, 3)]
    world = ObstacleWorld(obstacles)
    nodes = np.array([[0.0, 0.0, 0.0], [6.0, 0.0, 0.0]])
    slots = world.slots(nodes, count=4, safe_distance_m=0.5)
    assert slots.shape == (2, 4, 7)
    np.testing.assert_allclose(slots[0, :3, 0], [1.0, 3.0, 5.0])
    np.testing.assert_allclose(slots[1, :3, 0], [5.0, 3.0, 1.0])  # its own order
    np.testing.assert_allclose(slots[:, :3, 6], 0.6)
    np.testing.assert_array_equal(slots[:, 3], np.tile(UNUSED_SLOT, (2, 1)))
    assert world.slots(nodes[:1], count=2, safe_distance_m=0.5).shape == (1, 2, 7)


def test_slots_from_a_distance_table_equal_slots_from_the_points():
    world = ObstacleWorld(
        [Sphere((2.0, 0.0, -1.0), 0.5), Cylinder((0.0, 3.0), 0.4), Cylinder((-1.0, -1.0), 0.2)]
    )
    points = np.random.default_rng(3).uniform(-4.0, 4.0, (6, 3))
    table = world.surface_distance_m(points)
    for count in (0, 2, 5):
        assert np.array_equal(world.slots_at(table, count, 0.3), world.slots(points, count, 0.3))
    empty = ObstacleWorld([])
    assert np.array_equal(
        empty.slots_at(empty.surface_distance_m(points), 2, 0.3), empty.slots(points, 2, 0.3)
    )


def test_random_forest_keeps_path_free():
    path = np.column_stack([np.linspace(0, 30, 100), np.zeros(100), np.full(100, -2.0)])
    world = random_forest(path, n_trees=40, seed=3, keep_out_m=1.0)
    assert len(world.obstacles) == 40
    assert world.clearance_m(path).min() > 1.0
    again = random_forest(path, n_trees=40, seed=3, keep_out_m=1.0)
    assert again.obstacles == world.obstacles


def test_unknown_obstacle_type_raises():
    with pytest.raises(TypeError, match="Sphere or Cylinder"):
        ObstacleWorld(["tree"])
