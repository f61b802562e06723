"""[Kulathunga23]'s random forest: vertical trees on a 60 m x 60 m x 10 m plot, seeded.

The paper gives the plot (60 x 60 x 10 m) and ten start/goal pairs, not the tree count or
sizes; the density (trees per 100 m^2) and trunk radii here are our choice, defaults giving
a forest where a straight line between far corners meets several trees. Trees are
:class:`~planners.obstacles.Cylinder` (vertical, taller than any flight below 10 m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planners.obstacles import Cylinder, ObstacleWorld


@dataclass(frozen=True)
class ForestSpec:
    """A seeded forest.

    Attributes:
        seed: random seed (same seed, same forest).
        size_ne_m: plot size north x east [m], from (0, 0).
        height_m: tree height [m] (flights stay below it).
        density_per_100m2: expected trees per 100 m^2 of plot.
        radius_range_m: trunk radii drawn uniformly in this range [m].
        min_gap_m: least free gap between two trunks [m] (a vehicle must pass between).
    """

    seed: int = 0
    size_ne_m: tuple[float, float] = (60.0, 60.0)
    height_m: float = 10.0
    density_per_100m2: float = 1.5
    radius_range_m: tuple[float, float] = (0.2, 0.5)
    min_gap_m: float = 1.5

    def __post_init__(self) -> None:
        if not self.density_per_100m2 >= 0:
            raise ValueError(f"density_per_100m2 must be >= 0, got {self.density_per_100m2}")
        if not all(s > 0 for s in self.size_ne_m):
            raise ValueError(f"size_ne_m must be positive, got {self.size_ne_m}")


def forest_world(
    spec: ForestSpec, keep_free_ne_m: np.ndarray | None = None, keep_free_radius_m: float = 2.0
) -> ObstacleWorld:
    """The forest of ``spec``; no trunk within ``keep_free_radius_m`` [m] of any point of
    ``keep_free_ne_m`` (k, 2) (starts and goals)."""
    rng = np.random.default_rng(spec.seed)
    area_100m2 = spec.size_ne_m[0] * spec.size_ne_m[1] / 100.0
    n_trees = int(round(spec.density_per_100m2 * area_100m2))
    free = np.zeros((0, 2)) if keep_free_ne_m is None else np.asarray(keep_free_ne_m, float)
    centres: list[np.ndarray] = []
    radii: list[float] = []
    for _ in range(50 * n_trees):
        if len(centres) >= n_trees:
            break
        ne = rng.uniform((0.0, 0.0), spec.size_ne_m)
        r = float(rng.uniform(*spec.radius_range_m))
        if free.size and np.min(np.linalg.norm(free - ne, axis=1)) < keep_free_radius_m + r:
            continue
        if centres:
            gaps = np.linalg.norm(np.array(centres) - ne, axis=1) - np.array(radii) - r
            if np.min(gaps) < spec.min_gap_m:
                continue
        centres.append(ne)
        radii.append(r)
    return ObstacleWorld(
        [Cylinder((float(c[0]), float(c[1])), r) for c, r in zip(centres, radii, strict=True)]
    )
