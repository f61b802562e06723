"""The companion's incremental obstacle map: range-sensor hits in a KD-tree.

[Kulathunga23] builds its map incrementally within about 5 m of the vehicle (u_r 4-6 m) and
feeds each NMPC node the N_o obstacles nearest to it (eq. 4). Our choice of structure: the
hit points, de-duplicated on a voxel grid, in a ``scipy.spatial.cKDTree``. Why a KD-tree and
not an OctoMap: the sensor here is a horizontal ring (OBSTACLE_DISTANCE), so the map is a set
of points, not occupancy in 3-D; nearest-neighbour queries over a few thousand points take
microseconds; scipy is already a dependency, while the OctoMap Python bindings need a C++
build. The tree is rebuilt (O(n log n), ~1 ms for 10^4 points) only after a scan added points.

A point stands for a vertical column (the sensor sees a slice at flight height; trees, poles
and walls are vertical), so it becomes a vertical-cylinder NMPC slot of radius
``point_radius_m`` + d_o. Pure: no I/O.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from planners.nmpc_formulation import UNUSED_SLOT


class PointObstacleMap:
    """Obstacle points learnt from range scans.

    Args:
        voxel_m: grid size for de-duplication [m] (one point per voxel).
        point_radius_m: radius each point is given as an obstacle [m].
        update_range_m: only hits closer than this to the sensor enter the map (u_r) [m].
    """

    def __init__(
        self, voxel_m: float = 0.15, point_radius_m: float = 0.1, update_range_m: float = 5.0
    ) -> None:
        if not (voxel_m > 0 and point_radius_m >= 0 and update_range_m > 0):
            raise ValueError(
                f"need voxel_m > 0, point_radius_m >= 0, update_range_m > 0; got {voxel_m}, "
                f"{point_radius_m}, {update_range_m}"
            )
        self.voxel_m = voxel_m
        self.point_radius_m = point_radius_m
        self.update_range_m = update_range_m
        self._keys: set[tuple[int, int, int]] = set()
        self._points: list[np.ndarray] = []
        self._tree: cKDTree | None = None
        self._stale = False
        self.version = 0  # grows whenever points were added

    def __len__(self) -> int:
        return len(self._points)

    @property
    def points_ned_m(self) -> np.ndarray:
        """All map points (n, 3) [m]."""
        return np.array(self._points).reshape(-1, 3)

    def add_scan(
        self, origin_ned_m: np.ndarray, angles_rad: np.ndarray, distances_m: np.ndarray
    ) -> int:
        """Insert a horizontal scan: beam angles from north, clockwise (k,), ranges (k,) [m]
        (inf or nan: nothing seen). Returns how many new points entered the map."""
        d = np.asarray(distances_m, dtype=float)
        a = np.asarray(angles_rad, dtype=float)
        hit = np.isfinite(d) & (d <= self.update_range_m)
        o = np.asarray(origin_ned_m, dtype=float)
        pts = o + np.column_stack(
            [d[hit] * np.cos(a[hit]), d[hit] * np.sin(a[hit]), np.zeros(int(hit.sum()))]
        )
        return self.add_points(pts)

    def add_points(self, points_ned_m: np.ndarray) -> int:
        """Insert points (n, 3) [m]; returns how many fell into new voxels."""
        added = 0
        for p in np.atleast_2d(np.asarray(points_ned_m, dtype=float)).reshape(-1, 3):
            key = tuple(int(k) for k in np.floor(p / self.voxel_m))
            if key not in self._keys:
                self._keys.add(key)
                self._points.append(p)
                added += 1
        if added:
            self._stale = True
            self.version += 1
        return added

    def _kdtree(self) -> cKDTree | None:
        if self._stale or (self._tree is None and self._points):
            self._tree = cKDTree(self.points_ned_m[:, :2])
            self._stale = False
        return self._tree

    def clearance_m(self, points_ned_m: np.ndarray) -> np.ndarray:
        """Horizontal distance from each point (n, 3) to the nearest obstacle surface [m],
        shape (n,); inf for an empty map."""
        pts = np.atleast_2d(np.asarray(points_ned_m, dtype=float))
        tree = self._kdtree()
        if tree is None:
            return np.full(pts.shape[0], np.inf)
        dist, _ = tree.query(pts[:, :2])
        return np.asarray(dist) - self.point_radius_m

    def nearest_points(self, points_ned_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(distance [m] (n,), nearest map point (n, 3)) for each query point (n, 3)."""
        pts = np.atleast_2d(np.asarray(points_ned_m, dtype=float))
        tree = self._kdtree()
        if tree is None:
            return np.full(pts.shape[0], np.inf), np.full((pts.shape[0], 3), np.nan)
        dist, idx = tree.query(pts[:, :2])
        return np.asarray(dist), self.points_ned_m[np.asarray(idx)]

    def slots(self, points_ned_m: np.ndarray, count: int, safe_distance_m: float) -> np.ndarray:
        """For each query point (n, 3) (an NMPC node), the ``count`` map points nearest to it
        as NMPC slots, nearest first: (n, count, 7) ([Kulathunga23] eq. 4); a vertical
        cylinder of radius point_radius_m + d_o each; unused slots padded."""
        pts = np.atleast_2d(np.asarray(points_ned_m, dtype=float))
        out = np.tile(UNUSED_SLOT, (pts.shape[0], count, 1))
        tree = self._kdtree()
        if tree is None or count == 0:
            return out
        k = min(count, len(self._points))
        _, idx = tree.query(pts[:, :2], k=k)
        p = self.points_ned_m[np.reshape(idx, (pts.shape[0], k))]
        out[:, :k, 0:2] = p[:, :, :2]
        out[:, :k, 2] = 0.0
        out[:, :k, 3:6] = (1.0, 1.0, 0.0)
        out[:, :k, 6] = self.point_radius_m + safe_distance_m
        return out
