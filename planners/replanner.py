"""[Kulathunga23]'s replanner and regeneration: keep the reference out of the known obstacles.

Following the paper (its ref. 9): the B-spline reference is pushed out of the obstacles the
map knows, with a clearance, and refined again whenever the map grows; when the vehicle is
more than ``regenerate_distance_m`` (~2 m, Fig. 7) from the reference, the reference is
regenerated from the vehicle's position to the goal and pushed again, which is how the paper
escapes the local minima a pushed reference can leave.

Our choices (the paper does not give them): the reference is a cubic B-spline through
waypoints spaced ``waypoint_spacing_m`` apart (the geometry of
:class:`~planners.bspline.BSplineReference`);
a waypoint near a too-close stretch of the spline moves away from the nearest obstacle point,
across the path (sideways, so a trunk standing on the path is passed, not backed away from),
by the missing clearance; iterations stop when the whole spline keeps the clearance or after
``max_iterations`` (then ``ok`` is False and the best reference so far is kept); a side is
chosen once per obstacle contact by the side with more room; no waypoint moves more than
``max_shift_m`` from where it was generated. Pure: no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from planners.bspline import spline_points
from planners.path_reference import PolylinePath

_SAMPLES_PER_SEGMENT = 8


class ObstacleMap(Protocol):
    def nearest_points(self, points_ned_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...

    def clearance_m(self, points_ned_m: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class ReplannerConfig:
    """Attributes:
    clearance_m: least distance [m] from the reference to an obstacle surface (our choice: the
        RRT* baseline's clearance; the NMPC keeps d_o + a point's radius = 0.6 m).
    waypoint_spacing_m: distance between the spline's waypoints [m].
    max_iterations: pushes per replan.
    regenerate_distance_m: vehicle-to-reference distance [m] that triggers regeneration
        ([Kulathunga23] Fig. 7: ~2 m).
    max_shift_m: farthest a waypoint may be pushed from where it was generated [m]: a
        refinement stays local (pushes between close obstacles on both sides would otherwise
        walk a waypoint away without end); farther detours are the NMPC's and the
        regeneration's.
    """

    clearance_m: float = 0.8
    waypoint_spacing_m: float = 1.0
    max_iterations: int = 40
    regenerate_distance_m: float = 2.0
    max_shift_m: float = 4.0


@dataclass(frozen=True)
class Replan:
    """A replanned reference: its waypoints (m, 3), dense path, and whether it is clear."""

    waypoints_ned_m: np.ndarray
    path: PolylinePath
    ok: bool
    min_clearance_m: float


def resample(points_ned_m: np.ndarray, spacing_m: float) -> np.ndarray:
    """A polyline (n, 3) resampled every ~``spacing_m`` [m], keeping both ends."""
    path = PolylinePath(points_ned_m)
    n = max(1, int(np.ceil(path.length_m / spacing_m)))
    pos, _ = path.at(np.linspace(0.0, path.length_m, n + 1))
    return pos


def spline_path(waypoints_ned_m: np.ndarray) -> PolylinePath:
    """The B-spline through the waypoints (m, 3), as a dense polyline."""
    return PolylinePath(spline_points(waypoints_ned_m, _SAMPLES_PER_SEGMENT))


def push_out(
    waypoints_ned_m: np.ndarray,
    obstacle_map: ObstacleMap,
    config: ReplannerConfig,
    window: tuple[int, int] | None = None,
    max_iterations: int | None = None,
    anchor_ned_m: np.ndarray | None = None,
) -> Replan:
    """Push the spline through ``waypoints_ned_m`` (m, 3) out of the map's obstacles (see the
    module docstring). Only waypoints ``window`` = (first, last) (default: all but the ends)
    move, and only the spline between them is checked: a vehicle needs the stretch ahead of
    it clear, and refining only that keeps a replan cheap. ``ok`` is about that stretch.
    ``anchor_ned_m`` (m, 3): where the waypoints were generated; no waypoint ends farther
    than ``max_shift_m`` from its anchor (default: from where it is now)."""
    wp = np.array(waypoints_ned_m, dtype=float)
    origin = wp.copy() if anchor_ned_m is None else np.asarray(anchor_ned_m, dtype=float)
    m = wp.shape[0]
    first, last = (1, m - 2) if window is None else (max(1, window[0]), min(m - 2, window[1]))
    lo, hi = (first - 1) * _SAMPLES_PER_SEGMENT, (last + 1) * _SAMPLES_PER_SEGMENT + 1
    path = spline_path(wp)
    for _ in range(config.max_iterations if max_iterations is None else max_iterations):
        if last < first:
            break
        pts = path.points_ned_m[lo:hi]
        clear = obstacle_map.clearance_m(pts)
        bad = np.flatnonzero(clear < config.clearance_m)
        if bad.size == 0:
            break
        _, nearest = obstacle_map.nearest_points(pts[bad])
        j = bad + lo
        i = np.clip(np.rint(j / _SAMPLES_PER_SEGMENT).astype(int), first, last)
        tangent = wp[np.minimum(i + 1, m - 1)] - wp[np.maximum(i - 1, 0)]
        tangent[:, 2] = 0.0
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1), 1e-9)[:, None]
        away = pts[bad] - nearest
        away[:, 2] = 0.0
        side = away - np.sum(away * tangent, axis=1)[:, None] * tangent
        normal = np.column_stack([-tangent[:, 1], tangent[:, 0], np.zeros(bad.size)])
        ahead = np.linalg.norm(side, axis=1) < 0.05 * np.maximum(np.linalg.norm(away, axis=1), 1e-3)
        if np.any(ahead):  # dead ahead: the side with more room
            probe_l = obstacle_map.clearance_m(pts[bad][ahead] + normal[ahead])
            probe_r = obstacle_map.clearance_m(pts[bad][ahead] - normal[ahead])
            side[ahead] = np.where((probe_l >= probe_r)[:, None], normal[ahead], -normal[ahead])
        side /= np.maximum(np.linalg.norm(side, axis=1), 1e-9)[:, None]
        step = side * (config.clearance_m - clear[bad] + 0.05)[:, None]
        moves = np.zeros_like(wp)
        counts = np.zeros(m)
        np.add.at(moves, i, step)
        np.add.at(counts, i, 1.0)
        moved = counts > 0
        wp[moved] += moves[moved] / counts[moved, None]
        shift = wp - origin
        norm = np.linalg.norm(shift, axis=1)
        far = norm > config.max_shift_m
        wp[far] = origin[far] + shift[far] * (config.max_shift_m / norm[far])[:, None]
        path = spline_path(wp)
    clear = obstacle_map.clearance_m(path.points_ned_m[lo:hi])
    min_clear = float(np.min(clear)) if clear.size else float("inf")
    return Replan(wp, path, min_clear >= config.clearance_m, min_clear)


def needs_regeneration(
    vehicle_ned_m: np.ndarray, reference_point_ned_m: np.ndarray, config: ReplannerConfig
) -> bool:
    """True when the vehicle is more than ``regenerate_distance_m`` from where the reference
    is now ([Kulathunga23] Fig. 7)."""
    gap = np.asarray(vehicle_ned_m, dtype=float) - np.asarray(reference_point_ned_m, dtype=float)
    return bool(np.linalg.norm(gap) > config.regenerate_distance_m)
