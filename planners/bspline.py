"""Cubic uniform B-spline references through waypoints, timed under speed/accel limits.

The spline interpolates the waypoints at its knots and starts and ends at rest (zero
velocity). All segments last the same time (a uniform B-spline in time), the shortest that
keeps |velocity| <= max_speed_mps and |acceleration| <= max_acc_mps2 everywhere. Before t = 0
and after the end the reference holds its end points at rest. Yaw is held constant.
"""

from __future__ import annotations

import numpy as np

from planners.reference import ReferenceSample, SampledReference

# Rows: coefficients of 1, s, s^2, s^3 for the 4 control points of one segment.
_BASIS = np.array([[1, 4, 1, 0], [-3, 0, 3, 0], [3, -6, 3, 0], [-1, 3, -3, 1]]) / 6.0
_LIMIT_SAMPLES_PER_SEGMENT = 64
_LIMIT_MARGIN = 1.001


class BSplineReference(SampledReference):
    """Cubic uniform B-spline through ``waypoints_ned_m`` (M+1, 3), M >= 1.

    Attributes:
        waypoints_ned_m: the waypoints, shape (M+1, 3) [m].
        control_points_ned_m: control points, shape (M+3, 3) [m].
        segment_duration_s: time per spline segment [s].
        duration_s: total time, M * segment_duration_s [s].
        yaw_rad: constant yaw of the reference [rad].
    """

    def __init__(
        self,
        waypoints_ned_m: np.ndarray,
        max_speed_mps: float = 1.5,
        max_acc_mps2: float = 1.0,
        yaw_rad: float = 0.0,
    ) -> None:
        wp = np.asarray(waypoints_ned_m, dtype=float)
        if wp.ndim != 2 or wp.shape[1] != 3 or wp.shape[0] < 2:
            raise ValueError(f"waypoints_ned_m must have shape (M+1, 3), M >= 1; got {wp.shape}")
        if not np.all(np.isfinite(wp)):
            raise ValueError("waypoints_ned_m must be finite")
        if not (max_speed_mps > 0 and max_acc_mps2 > 0):
            raise ValueError(
                f"limits must be > 0, got max_speed_mps={max_speed_mps}, "
                f"max_acc_mps2={max_acc_mps2}"
            )
        self.waypoints_ned_m = wp
        self.yaw_rad = float(yaw_rad)
        self.control_points_ned_m = _interpolating_control_points(wp)
        self._n_seg = wp.shape[0] - 1
        s = np.linspace(0.0, self._n_seg, self._n_seg * _LIMIT_SAMPLES_PER_SEGMENT + 1)
        _, d1, d2 = self._param_derivatives(s)
        speed = np.max(np.linalg.norm(d1, axis=1))
        acc = np.max(np.linalg.norm(d2, axis=1))
        seg = max(speed / max_speed_mps, np.sqrt(acc / max_acc_mps2), 1e-6)
        self.segment_duration_s = float(seg * _LIMIT_MARGIN)
        self.duration_s = self.segment_duration_s * self._n_seg

    def _param_derivatives(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position and its first two derivatives w.r.t. the knot parameter u, each (n, 3)."""
        i = np.clip(np.floor(u).astype(int), 0, self._n_seg - 1)
        s = (u - i)[:, None]
        cp = self.control_points_ned_m
        pts = np.stack([cp[i], cp[i + 1], cp[i + 2], cp[i + 3]], axis=1)  # (n, 4, 3)
        coef = np.einsum("kj,njd->nkd", _BASIS, pts)  # (n, 4 powers, 3)
        pos = coef[:, 0] + s * coef[:, 1] + s**2 * coef[:, 2] + s**3 * coef[:, 3]
        d1 = coef[:, 1] + 2 * s * coef[:, 2] + 3 * s**2 * coef[:, 3]
        d2 = 2 * coef[:, 2] + 6 * s * coef[:, 3]
        return pos, d1, d2

    def sample(self, t_s: np.ndarray | float) -> ReferenceSample:
        """Reference at times ``t_s`` [s] (scalar or (n,)); arrays of leading size n."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        inside = (t > 0.0) & (t < self.duration_s)
        u = np.clip(t / self.segment_duration_s, 0.0, self._n_seg)
        pos, d1, d2 = self._param_derivatives(u)
        vel = np.where(inside[:, None], d1 / self.segment_duration_s, 0.0)
        acc = np.where(inside[:, None], d2 / self.segment_duration_s**2, 0.0)
        yaw = np.full(t.shape, self.yaw_rad)
        return ReferenceSample(pos, vel, acc, yaw, np.zeros(t.shape))

    def length_m(self) -> float:
        """Arc length [m] (dense polyline approximation)."""
        s = np.linspace(0.0, self._n_seg, self._n_seg * _LIMIT_SAMPLES_PER_SEGMENT + 1)
        pos, _, _ = self._param_derivatives(s)
        return float(np.sum(np.linalg.norm(np.diff(pos, axis=0), axis=1)))


def spline_points(waypoints_ned_m: np.ndarray, samples_per_segment: int) -> np.ndarray:
    """Points (M * samples_per_segment + 1, 3) [m] along the cubic B-spline through the
    waypoints (M+1, 3), evenly in the knot parameter: the geometry of a
    :class:`BSplineReference` through them, without its timing."""
    wp = np.asarray(waypoints_ned_m, dtype=float)
    cp = _interpolating_control_points(wp)
    n_seg = wp.shape[0] - 1
    u = np.linspace(0.0, n_seg, n_seg * samples_per_segment + 1)
    i = np.clip(np.floor(u).astype(int), 0, n_seg - 1)
    s = u - i
    powers = np.column_stack([np.ones_like(s), s, s**2, s**3])  # (n, 4)
    weights = powers @ _BASIS  # (n, 4): weight of control points i..i+3
    return sum(weights[:, k : k + 1] * cp[i + k] for k in range(4))


def _interpolating_control_points(wp: np.ndarray) -> np.ndarray:
    """Control points P_-1..P_M+1 with C(i) = W_i and C'(0) = C'(M) = 0."""
    m = wp.shape[0] - 1
    n = m + 3
    a = np.zeros((n, n))
    b = np.zeros((n, 3))
    for i in range(m + 1):
        a[i, i : i + 3] = (1 / 6, 4 / 6, 1 / 6)
        b[i] = wp[i]
    a[m + 1, [0, 2]] = (-1.0, 1.0)  # (P_1 - P_-1) / 2 = 0
    a[m + 2, [m, m + 2]] = (-1.0, 1.0)
    return np.linalg.solve(a, b)
