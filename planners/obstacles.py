"""Obstacle worlds of spheres, vertical cylinders and boxes; the N_o nearest as NMPC slots.

Exact signed surface distances (contact detection, clearance checks) and ray casting (the
simulated range sensor) are here; the NMPC sees a box as its circumscribed sphere (a
conservative slot, our choice: [Kulathunga23] eq. 4 has point obstacles with a safe distance).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planners.nmpc_formulation import OBSTACLE_SLOT_SIZE, UNUSED_SLOT, slot_clearance_m


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


@dataclass(frozen=True)
class Box:
    """An axis-aligned box (a wall, a building): centre NED [m] (3,), half extents [m] (3,)."""

    center_ned_m: tuple[float, float, float]
    half_extents_m: tuple[float, float, float]


Obstacle = Sphere | Cylinder | Box


class ObstacleWorld:
    """A fixed set of obstacles with vectorised distance queries."""

    def __init__(self, obstacles: tuple[Obstacle, ...] | list[Obstacle]) -> None:
        """Raises ValueError (one line) for an obstacle with a non-finite centre or size: its
        clearance would be NaN, which no constraint or plan check can compare."""
        self.obstacles = tuple(obstacles)
        rows = [_slot_of(o) for o in self.obstacles]
        self._slots = np.array(rows).reshape(len(rows), OBSTACLE_SLOT_SIZE)
        bad = np.flatnonzero(~np.isfinite(self._slots).all(axis=1))
        if bad.size:
            raise ValueError(
                f"obstacle {int(bad[0])} ({self.obstacles[bad[0]]}) has a non-finite centre or "
                "size; give finite metres"
            )
        is_box = np.array([isinstance(o, Box) for o in self.obstacles], dtype=bool)
        self._box_index = np.flatnonzero(is_box)
        self._round_index = np.flatnonzero(~is_box)
        self._round = self._slots[self._round_index]
        self._boxes = np.array(
            [[*o.center_ned_m, *o.half_extents_m] for o in self.obstacles if isinstance(o, Box)]
        ).reshape(-1, 6)

    def surface_distance_m(self, points_ned_m: np.ndarray) -> np.ndarray:
        """Distance from each point to each obstacle surface [m], shape (n_points, n_obs).

        Negative inside an obstacle.
        """
        pts = np.atleast_2d(np.asarray(points_ned_m, dtype=float))
        rounds = slot_clearance_m(pts[:, None, :], self._round)  # (n, n_round)
        if not self._box_index.size:
            return rounds
        out = np.empty((pts.shape[0], len(self.obstacles)))
        out[:, self._round_index] = rounds
        q = np.abs(pts[:, None, :] - self._boxes[None, :, 0:3]) - self._boxes[None, :, 3:6]
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=2)
        inside = np.minimum(np.max(q, axis=2), 0.0)
        out[:, self._box_index] = outside + inside
        return out

    def segment_clearance_m(
        self, start_ned_m: np.ndarray, end_ned_m: np.ndarray, step_m: float = 0.002
    ) -> float:
        """Smallest clearance [m] along the straight segment start -> end (3,) each, sampled
        every ``step_m`` [m] or finer (exact to within step_m / 2 for any obstacle)."""
        a = np.asarray(start_ned_m, dtype=float)
        b = np.asarray(end_ned_m, dtype=float)
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step_m)))
        s = np.linspace(0.0, 1.0, n + 1)[:, None]
        return float(np.min(self.clearance_m(a + s * (b - a))))

    def ray_distance_m(
        self, origin_ned_m: np.ndarray, directions_ned: np.ndarray, max_range_m: float
    ) -> np.ndarray:
        """Distance [m] along each unit direction (k, 3) from ``origin_ned_m`` (3,) to the
        first surface, shape (k,); inf when nothing is hit within ``max_range_m``; 0 from
        inside an obstacle."""
        o = np.asarray(origin_ned_m, dtype=float)
        d = np.atleast_2d(np.asarray(directions_ned, dtype=float))
        best = np.full(d.shape[0], np.inf)
        if not self.obstacles:
            return best
        in_range = np.flatnonzero(self.surface_distance_m(o[None, :])[0] <= max_range_m)
        for k in in_range:
            best = np.minimum(best, _ray_hit_m(self.obstacles[k], o, d))
        best[best > max_range_m] = np.inf
        return best

    def clearance_m(self, points_ned_m: np.ndarray) -> np.ndarray:
        """Distance from each point to the nearest surface [m], shape (n,); inf if empty."""
        pts = np.atleast_2d(np.asarray(points_ned_m, dtype=float))
        if not self.obstacles:
            return np.full(pts.shape[0], np.inf)
        return np.min(self.surface_distance_m(pts), axis=1)

    def slots(self, points_ned_m: np.ndarray, count: int, safe_distance_m: float) -> np.ndarray:
        """For each point (n, 3) (an NMPC node), the ``count`` obstacles nearest to it as NMPC
        slots, nearest first: (n, count, 7) ([Kulathunga23] eq. 4).

        The radius is inflated by ``safe_distance_m`` (d_o); missing slots are unused.
        """
        pts = np.atleast_2d(np.asarray(points_ned_m, dtype=float))
        if not self.obstacles or count == 0:
            return np.tile(UNUSED_SLOT, (pts.shape[0], count, 1))
        return self.slots_at(self.surface_distance_m(pts), count, safe_distance_m)

    def slots_at(self, distances_m: np.ndarray, count: int, safe_distance_m: float) -> np.ndarray:
        """:meth:`slots` from the points' :meth:`surface_distance_m` (n, n_obs) [m], for a
        caller that needs those distances too: (n, count, 7)."""
        if not self.obstacles or count == 0:
            return np.tile(UNUSED_SLOT, (distances_m.shape[0], count, 1))
        order = np.argsort(distances_m, axis=1, kind="stable")[:, :count]
        nearest = self._slots[order]  # a new array
        nearest[:, :, 6] += safe_distance_m
        if order.shape[1] == count:
            return nearest
        out = np.tile(UNUSED_SLOT, (distances_m.shape[0], count, 1))
        out[:, : order.shape[1]] = nearest
        return out


def _slot_of(obstacle: Obstacle) -> np.ndarray:
    if isinstance(obstacle, Sphere):
        return np.array([*obstacle.center_ned_m, 1.0, 1.0, 1.0, obstacle.radius_m])
    if isinstance(obstacle, Cylinder):
        return np.array([*obstacle.center_ne_m, 0.0, 1.0, 1.0, 0.0, obstacle.radius_m])
    if isinstance(obstacle, Box):  # the circumscribed sphere: conservative for the NMPC
        return np.array(
            [*obstacle.center_ned_m, 1.0, 1.0, 1.0, np.linalg.norm(obstacle.half_extents_m)]
        )
    raise TypeError(f"unknown obstacle type {type(obstacle).__name__}; use Box, Sphere or Cylinder")


def _ray_hit_m(obstacle: Obstacle, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """First-hit distance along unit rays d (k, 3) from o (3,), inf when missed."""
    if isinstance(obstacle, Box):
        lo = np.asarray(obstacle.center_ned_m) - np.asarray(obstacle.half_extents_m)
        hi = np.asarray(obstacle.center_ned_m) + np.asarray(obstacle.half_extents_m)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (lo - o) / d
            t2 = (hi - o) / d
        parallel = np.abs(d) < 1e-12
        inside_slab = (o >= lo) & (o <= hi)
        t1 = np.where(parallel, np.where(inside_slab, -np.inf, np.inf), t1)
        t2 = np.where(parallel, np.where(inside_slab, np.inf, np.inf), t2)
        near = np.max(np.minimum(t1, t2), axis=1)
        far = np.min(np.maximum(t1, t2), axis=1)
        hit = far >= np.maximum(near, 0.0)
        return np.where(hit, np.maximum(near, 0.0), np.inf)
    if isinstance(obstacle, Cylinder):
        c = np.array([*obstacle.center_ne_m, 0.0])
        w = np.array([1.0, 1.0, 0.0])
    else:
        c = np.asarray(obstacle.center_ned_m, dtype=float)
        w = np.ones(3)
    oc = (o - c) * w
    dw = d * w
    a = np.sum(dw * dw, axis=1)
    b = 2.0 * dw @ oc
    cc = float(oc @ oc) - obstacle.radius_m**2
    if cc <= 0.0:
        return np.zeros(d.shape[0])
    disc = b * b - 4.0 * a * cc
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a)
    return np.where((disc >= 0.0) & (a > 1e-12) & (t >= 0.0), t, np.inf)


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
