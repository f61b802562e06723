"""A geometric path flown at a speed profile from a moving start: the reference the clutter
planner hands its NMPC each cycle.

The path is a dense polyline (n, 3) [m] with its arc length. ``PathReference(path, s0, t0)``
starts at arc length ``s0`` [m] at time ``t0`` [s] and moves along the path at
v(s) = min(v_max, sqrt(v_0^2 + 2 a_max s), sqrt(2 a_max (L - s))) (accelerate from the path's
start, where the vehicle was, cruise, brake to rest at the end), so the NMPC
gets position and velocity feed-forward on its horizon grid. Progress is the caller's: the
clutter planner moves ``s0`` with the vehicle, so a vehicle held up by an obstacle is not left
behind by a clock (our choice; [Kulathunga23] instead regenerates when the vehicle is ~2 m
from the reference).
"""

from __future__ import annotations

import numpy as np

from planners.reference import ReferenceSample, SampledReference

_V_FLOOR_MPS = 0.05
_V_START_MPS = 0.2  # speed at the path's start [m/s] (a path starts where the vehicle is)


class PolylinePath:
    """A polyline (n, 3) [m], n >= 2, with arc length ``s_m`` (n,) and total ``length_m``."""

    def __init__(self, points_ned_m: np.ndarray) -> None:
        pts = np.asarray(points_ned_m, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2 or not np.all(np.isfinite(pts)):
            raise ValueError(f"path points must be finite, shape (n >= 2, 3); got {pts.shape}")
        keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9])
        pts = pts[keep]
        if pts.shape[0] < 2:
            pts = np.vstack([pts, pts[-1] + 1e-6])
        self.points_ned_m = pts
        self.s_m = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        self.length_m = float(self.s_m[-1])

    def at(self, s_m: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """(positions (k, 3), unit tangents (k, 3)) at arc lengths ``s_m`` (clipped)."""
        s = np.clip(np.atleast_1d(np.asarray(s_m, dtype=float)), 0.0, self.length_m)
        i = np.clip(np.searchsorted(self.s_m, s, side="right") - 1, 0, len(self.s_m) - 2)
        seg = self.points_ned_m[i + 1] - self.points_ned_m[i]
        seg_len = self.s_m[i + 1] - self.s_m[i]
        frac = ((s - self.s_m[i]) / seg_len)[:, None]
        return self.points_ned_m[i] + frac * seg, seg / seg_len[:, None]

    def project(self, point_ned_m: np.ndarray, s_min_m: float, s_max_m: float) -> float:
        """Arc length [m] of the path point nearest to ``point_ned_m`` within [s_min, s_max]."""
        lo = max(0, int(np.searchsorted(self.s_m, s_min_m, side="right")) - 1)
        hi = min(len(self.s_m) - 1, int(np.searchsorted(self.s_m, s_max_m, side="left")))
        hi = max(hi, lo + 1)
        a = self.points_ned_m[lo:hi]
        ab = self.points_ned_m[lo + 1 : hi + 1] - a
        ab2 = np.maximum(np.sum(ab * ab, axis=1), 1e-12)
        u = np.clip(np.sum((np.asarray(point_ned_m) - a) * ab, axis=1) / ab2, 0.0, 1.0)
        d = np.linalg.norm(a + u[:, None] * ab - point_ned_m, axis=1)
        j = int(np.argmin(d))
        return float(np.clip(self.s_m[lo + j] + u[j] * np.sqrt(ab2[j]), s_min_m, s_max_m))


class PathReference(SampledReference):
    """``path`` flown from arc length ``s0_m`` at time ``t0_s`` (see the module docstring).

    Attributes: path, s0_m, t0_s, max_speed_mps, max_acc_mps2, yaw_rad; duration_s is the time
    [s] (on the same clock) at which the end is reached.
    """

    def __init__(
        self,
        path: PolylinePath,
        s0_m: float = 0.0,
        t0_s: float = 0.0,
        max_speed_mps: float = 1.5,
        max_acc_mps2: float = 1.0,
        yaw_rad: float = 0.0,
    ) -> None:
        self.path = path
        self.s0_m = float(np.clip(s0_m, 0.0, path.length_m))
        self.t0_s = float(t0_s)
        self.max_speed_mps = max_speed_mps
        self.max_acc_mps2 = max_acc_mps2
        self.yaw_rad = yaw_rad
        n = max(2, int(np.ceil((path.length_m - self.s0_m) / 0.05)) + 1)
        s = np.linspace(self.s0_m, path.length_m, n)
        v = self.speed_at(s)
        dt = np.diff(s) / np.maximum(0.5 * (v[1:] + v[:-1]), _V_FLOOR_MPS)
        self._s_grid = s
        self._t_grid = self.t0_s + np.concatenate([[0.0], np.cumsum(dt)])
        self.duration_s = float(self._t_grid[-1])

    def speed_at(self, s_m: np.ndarray) -> np.ndarray:
        """Profile speed [m/s] at arc lengths ``s_m``: accelerating from (nearly) rest at the
        path's start, cruising, braking to rest at its end."""
        s = np.asarray(s_m, dtype=float)
        rest = np.maximum(self.path.length_m - s, 0.0)
        start = np.sqrt(_V_START_MPS**2 + 2.0 * self.max_acc_mps2 * np.maximum(s, 0.0))
        return np.minimum(
            np.minimum(self.max_speed_mps, start), np.sqrt(2.0 * self.max_acc_mps2 * rest)
        )

    def s_at(self, t_s: np.ndarray | float) -> np.ndarray:
        """Arc length [m] reached at times ``t_s`` (held before t0 and after the end)."""
        return np.interp(np.atleast_1d(np.asarray(t_s, dtype=float)), self._t_grid, self._s_grid)

    def sample(self, t_s: np.ndarray | float) -> ReferenceSample:
        s = self.s_at(t_s)
        pos, tangent = self.path.at(s)
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        moving = (t >= self.t0_s) & (t < self.duration_s)
        vel = np.where(moving[:, None], tangent * self.speed_at(s)[:, None], 0.0)
        n = s.shape[0]
        return ReferenceSample(pos, vel, np.zeros((n, 3)), np.full(n, self.yaw_rad), np.zeros(n))
