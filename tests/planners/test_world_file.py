"""World files and the seeded forest: round trip, one-line errors, geometry of boxes and rays."""

from __future__ import annotations

import re

import numpy as np
import pytest

from planners.forest import ForestSpec, forest_world
from planners.obstacles import Box, Cylinder, ObstacleWorld, Sphere
from planners.world_file import WorldFileError, load_world, parse_world, save_world

WORLD = ObstacleWorld(
    [Cylinder((1.0, 2.0), 0.3), Sphere((5.0, 0.0, -2.0), 0.5), Box((9.0, 1.0, -1.0), (0.5, 2, 1))]
)


def test_round_trip_through_a_file(tmp_path):
    path = save_world(tmp_path / "w.toml", WORLD, name="three")
    assert load_world(path).obstacles == WORLD.obstacles


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[[tree]]\nradius_m = 1.0\n", "unknown key 'tree'"),
        (
            "[[cylinder]]\ncenter_ne_m = [1.0, 2.0]\n",
            "needs exactly the keys center_ne_m, radius_m",
        ),
        ("[[cylinder]]\ncenter_ne_m = [1.0]\nradius_m = 1.0\n", "center_ne_m = [1.0]"),
        ("[[sphere]]\ncenter_ned_m = [1, 2, 3]\nradius_m = -1\n", "(> 0)"),
        ("[[box]]\ncenter_ned_m = [0, 0, 0]\nhalf_extents_m = [1, 0, 1]\n", "half_extents_m"),
        ("cylinder = 3\n", "array of tables"),
        ("[[cylinder\n", "not valid TOML"),
    ],
)
def test_bad_worlds_are_one_line_errors(text, message):
    with pytest.raises(WorldFileError, match=re.escape(message)) as e:
        parse_world(text, source="w.toml")
    assert str(e.value).startswith("w.toml") and "\n" not in str(e.value)


def test_missing_world_file(tmp_path):
    with pytest.raises(WorldFileError, match="no such world file"):
        load_world(tmp_path / "none.toml")


def test_box_distance_inside_outside_and_corner():
    world = ObstacleWorld([Box((0.0, 0.0, 0.0), (1.0, 2.0, 3.0))])
    pts = np.array([[2.0, 0.0, 0.0], [0.5, 0.0, 0.0], [2.0, 3.0, 0.0], [0.0, 0.0, 4.0]])
    np.testing.assert_allclose(world.clearance_m(pts), [1.0, -0.5, np.sqrt(2.0), 1.0])


def test_rays_against_a_brute_force_march():
    rng = np.random.default_rng(4)
    origin = np.array([0.0, 0.0, -2.0])
    angles = rng.uniform(0, 2 * np.pi, 40)
    dirs = np.column_stack([np.cos(angles), np.sin(angles), rng.uniform(-0.2, 0.2, 40)])
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    world = ObstacleWorld(
        [Cylinder((3.0, 1.0), 0.5), Sphere((-2.0, 2.0, -2.0), 0.8), Box((0, -3, -2), (1, 0.3, 1))]
    )
    got = world.ray_distance_m(origin, dirs, 6.0)
    steps = np.arange(0.0, 6.0, 0.001)
    for d, g in zip(dirs, got, strict=True):
        inside = np.flatnonzero(world.clearance_m(origin + steps[:, None] * d) <= 0.0)
        expected = steps[inside[0]] if inside.size else np.inf
        assert g == pytest.approx(expected, abs=0.002)


def test_segment_clearance_finds_the_closest_point_between_ends():
    world = ObstacleWorld([Cylinder((5.0, 1.0), 0.5)])
    assert world.segment_clearance_m([0, 0, -2], [10, 0, -2]) == pytest.approx(0.5, abs=1e-3)


def test_forest_is_seeded_dense_as_asked_and_keeps_starts_free():
    spec = ForestSpec(seed=5, density_per_100m2=2.0)
    free = np.array([[5.0, 5.0], [55.0, 55.0]])
    a, b = forest_world(spec, free), forest_world(spec, free)
    assert a.obstacles == b.obstacles
    assert len(a.obstacles) == 72  # 2 per 100 m^2 over 60 m x 60 m
    pts = np.column_stack([free, np.full(2, -2.0)])
    assert np.all(a.clearance_m(pts) >= 2.0)
    centres = np.array([o.center_ne_m for o in a.obstacles])
    radii = np.array([o.radius_m for o in a.obstacles])
    gaps = np.linalg.norm(centres[:, None] - centres[None], axis=2) - radii[:, None] - radii
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min() >= spec.min_gap_m
    assert forest_world(ForestSpec(seed=6, density_per_100m2=2.0)).obstacles != a.obstacles
