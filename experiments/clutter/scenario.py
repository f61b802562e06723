"""The forest and its start/goal pairs ([Kulathunga23] Table 3: one random forest of
60 m x 60 m x 10 m, ten start and goal poses).

Our choices (the paper gives neither): pairs run corner to opposite corner (start drawn in a
8 m x 8 m square 2 m inside one corner, goal in the opposite one: 70-80 m apart, the paper's
distances are 80-85 m), at 2.5 m altitude; starts and goals are kept 2 m clear of trunks.
Everything is drawn from the seeds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planners.forest import ForestSpec, forest_world
from planners.obstacles import Box, Cylinder, Obstacle, ObstacleWorld, Sphere

ALTITUDE_M = 2.5


@dataclass(frozen=True)
class ClutterScenario:
    """A forest and its pairs.

    Attributes:
        forest: the forest's spec (seed, size, density).
        starts_ne_m, goals_ne_m: (k, 2) start and goal positions north-east [m].
        world: the forest (trunks as vertical cylinders).
    """

    forest: ForestSpec
    starts_ne_m: np.ndarray
    goals_ne_m: np.ndarray
    world: ObstacleWorld


def make_scenario(forest: ForestSpec, n_pairs: int, pair_seed: int) -> ClutterScenario:
    """``n_pairs`` seeded corner-to-corner pairs in the forest of ``forest``."""
    rng = np.random.default_rng(pair_seed)
    size = np.asarray(forest.size_ne_m, dtype=float)
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    starts, goals = [], []
    for _ in range(n_pairs):
        c = corners[rng.integers(4)]
        inset = 2.0 + rng.uniform(0.0, 8.0, size=2)
        starts.append(np.where(c > 0, size - inset, inset))
        inset = 2.0 + rng.uniform(0.0, 8.0, size=2)
        goals.append(np.where(c > 0, inset, size - inset))
    s, g = np.array(starts), np.array(goals)
    world = forest_world(forest, keep_free_ne_m=np.vstack([s, g]), keep_free_radius_m=2.0)
    return ClutterScenario(forest, s, g, world)


def shifted(world: ObstacleWorld, offset_ne_m: np.ndarray) -> ObstacleWorld:
    """``world`` moved by ``-offset_ne_m`` (so a start there is the simulator's origin)."""
    dn, de = (float(v) for v in offset_ne_m)
    moved: list[Obstacle] = []
    for o in world.obstacles:
        if isinstance(o, Cylinder):
            moved.append(Cylinder((o.center_ne_m[0] - dn, o.center_ne_m[1] - de), o.radius_m))
        elif isinstance(o, Sphere):
            c = o.center_ned_m
            moved.append(Sphere((c[0] - dn, c[1] - de, c[2]), o.radius_m))
        else:
            c = o.center_ned_m
            moved.append(Box((c[0] - dn, c[1] - de, c[2]), o.half_extents_m))
    return ObstacleWorld(moved)
