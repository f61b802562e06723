"""Straight legs between waypoints flown at constant speed: a mission's simplest reference.

Implements planners.reference.Reference. The position moves along the polyline at
``speed_mps`` (arc length s = speed * t); the velocity is the leg direction times the speed;
acceleration, yaw and yaw rate are zero (the vehicle keeps its heading). Before t = 0 and
after the end the reference rests at its end points.
"""

from __future__ import annotations

import numpy as np

from planners.reference import ReferenceSample, SampledReference


class WaypointReference(SampledReference):
    """Constant-speed polyline through ``points_ned_m`` (N, 3) [m] at ``speed_mps`` [m/s]."""

    def __init__(self, points_ned_m: np.ndarray, speed_mps: float) -> None:
        points = np.asarray(points_ned_m, dtype=float)
        if points.ndim != 2 or points.shape[1] != 3 or points.shape[0] < 2:
            raise ValueError(f"points_ned_m must have shape (N >= 2, 3), got {points.shape}")
        if not speed_mps > 0.0:
            raise ValueError(f"speed_mps must be positive, got {speed_mps}")
        lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
        keep = np.concatenate([[True], lengths > 1e-9])
        self._points = points[keep]
        self._speed_mps = float(speed_mps)
        self._s_at_point = np.concatenate([[0.0], np.cumsum(lengths[lengths > 1e-9])])

    @property
    def duration_s(self) -> float:
        return float(self._s_at_point[-1] / self._speed_mps)

    def sample(self, t_s: np.ndarray | float) -> ReferenceSample:
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        s = np.clip(t * self._speed_mps, 0.0, self._s_at_point[-1])
        pos = np.column_stack(
            [np.interp(s, self._s_at_point, self._points[:, k]) for k in range(3)]
        )
        vel = np.zeros_like(pos)
        if len(self._points) > 1:
            leg = np.clip(
                np.searchsorted(self._s_at_point, s, side="right") - 1, 0, len(self._points) - 2
            )
            direction = np.diff(self._points, axis=0)
            direction /= np.linalg.norm(direction, axis=1, keepdims=True)
            moving = (t >= 0.0) & (t < self.duration_s)
            vel[moving] = direction[leg[moving]] * self._speed_mps
        zeros = np.zeros(len(t))
        return ReferenceSample(pos, vel, np.zeros_like(pos), zeros, zeros.copy())
