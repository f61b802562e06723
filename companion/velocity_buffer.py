"""The measured velocities of the last moments, by time: the velocity one planner interval ago.

A model that carries the previous velocity along the horizon (planners.velocity_history) starts
from the velocity measured one interval before the plan; the companion records every measured
velocity it plans from and reads that one back, linearly interpolated between the records
around it. Before the records reach back that far (the first plans), the oldest record stands
in: on the very first plan the current velocity, as the training rows' lag starts at a
segment's first row (gp.datasets). Time going backwards or a gap over ``max_gap_s`` starts
the record afresh (a new flight, a stalled loop).
"""

from __future__ import annotations

from collections import deque

import numpy as np


class VelocityBuffer:
    """Measured velocities (3,) [m/s] by time [s], kept for ``span_s`` [s] back from the
    newest."""

    def __init__(self, span_s: float, max_gap_s: float) -> None:
        self._span_s = float(span_s)
        self._max_gap_s = float(max_gap_s)
        self._records: deque[tuple[float, np.ndarray]] = deque()

    def clear(self) -> None:
        """Forget every record."""
        self._records.clear()

    def record(self, t_s: float, vel_ned_mps: np.ndarray) -> None:
        """Add the velocity measured at ``t_s``; drop the records no longer needed."""
        if self._records:
            gap_s = t_s - self._records[-1][0]
            if not 0.0 <= gap_s <= self._max_gap_s:
                self._records.clear()
        self._records.append((float(t_s), np.array(vel_ned_mps, dtype=float).reshape(3)))
        while len(self._records) > 1 and self._records[1][0] <= t_s - self._span_s:
            self._records.popleft()

    def at(self, t_s: float) -> np.ndarray:
        """The velocity (3,) [m/s] at ``t_s``: interpolated between the records around it, the
        oldest before them, the newest after them; ValueError with no record."""
        if not self._records:
            raise ValueError("no velocity recorded yet")
        times = np.array([t for t, _ in self._records])
        vels = np.array([v for _, v in self._records])
        return np.array([np.interp(t_s, times, vels[:, i]) for i in range(3)])
