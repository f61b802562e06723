"""Obstacle worlds of spheres and vertical cylinders, and the N_o nearest as NMPC slots."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planners.nmpc_formulation import OBSTACLE_SLOT_SIZE, UNUSED_SLOT


@dataclass(frozen=True)
class Sphere:
    """A ball: centre NED [m] (3,), radius [m]."""

    center_ned_m: tuple[float, float, float]
    radius_m: float


@dataclass(frozen=True)
class Cylinder:
    """An infinite vertical cylinder (a tree, a pole): axis through (north, east) [m]."""

    center_ne_m: tuple[float, float]
    radius_m: float


Obstacle = Sphere | Cylinder


class ObstacleWorld:
    """A fixed set of obstacles with vectorised distance queries."""

    def __init__(self, obstacles: tuple[Obstacle, ...] | list[Obstacle]) -> None:
        self.obstacles = tuple(obstacles)
        rows = [_slot_of(o) for o in self.obstacles]
        self._slots = np.array(rows).reshape(len(rows), OBSTACLE_SLOT_SIZE)

    def surface_distance_m(self, points_ned_m: np.ndarray) -> np.ndarray:
        """Distance from each point to each obstacle surface [m], shape (n_points, n_obs).

        Negative inside an obstacle.
        """
        pts = np.atleast_2d(np.asarray(points_ned_m, dtype=float))
        diff = pts[:, None, :] - self._slots[None, :, 0:3]
        dist = np.sqrt(np.sum(self._slots[None, :, 3:6] * diff**2, axis=2))
        return dist - self._slots[None, :, 6]

    def clearance_m(self, points_ned_m: np.ndarray) -> np.ndarray:
        """Distance from each point to the nearest surface [m], shape (n,); inf if empty."""
        pts = np.atleast_2d(np.asarray(points_ned_m, dtype=float))
        if not self.obstacles:
            return np.full(pts.shape[0], np.inf)
        return np.min(self.surface_distance_m(pts), axis=1)

    def slots(self, points_ned_m: np.ndarray, count: int, safe_distance_m: float) -> np.ndarray:
        """The ``count`` obstacles nearest to any of the points as NMPC slots, (count, 7).

        The radius is inflated by ``safe_distance_m`` (d_o); missing slots are unused.
        """
        out = np.tile(UNUSED_SLOT, (count, 1))
        if not self.obstacles or count == 0:
            return out
        nearest = np.min(self.surface_distance_m(points_ned_m), axis=0)
        order = np.argsort(nearest, kind="stable")[:count]
        out[: order.size] = self._slots[order]
        out[: order.size, 6] += safe_distance_m
        return out


def _slot_of(obstacle: Obstacle) -> np.ndarray:
    if isinstance(obstacle, Sphere):
        return np.array([*obstacle.center_ned_m, 1.0, 1.0, 1.0, obstacle.radius_m])
    if isinstance(obstacle, Cylinder):
        return np.array([*obstacle.center_ne_m, 0.0, 1.0, 1.0, 0.0, obstacle.radius_m])
    raise TypeError(f"unknown obstacle type {type(obstacle).__name__}; use Sphere or Cylinder")


def random_forest(
    path_ned_m: np.ndarray,
    n_trees: int,
    seed: int,
    radius_range_m: tuple[float, float] = (0.2, 0.5),
    keep_out_m: float = 1.0,
    spread_m: float = 6.0,
) -> ObstacleWorld:
    """Vertical cylinders scattered within ``spread_m`` of a path (n, 3), every surface
    farther than ``keep_out_m`` from it: a positive value keeps the path free, a negative one
    lets trees stand on the path (up to -keep_out_m deep), so a planner must go around."""
    rng = np.random.default_rng(seed)
    path = np.asarray(path_ned_m, dtype=float)
    trees: list[Obstacle] = []
    while len(trees) < n_trees:
        anchor = path[rng.integers(path.shape[0])]
        ne = anchor[:2] + rng.uniform(-spread_m, spread_m, 2)
        radius = rng.uniform(*radius_range_m)
        if np.min(np.linalg.norm(path[:, :2] - ne, axis=1)) > keep_out_m + radius:
            trees.append(Cylinder((float(ne[0]), float(ne[1])), float(radius)))
    return ObstacleWorld(trees)
