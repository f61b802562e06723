"""Seeded random 3-D reference trajectories like [Kulathunga23]'s real-world experiment.

Each trajectory is a :class:`BSplineReference` through a random walk of waypoints (bounded
heading changes, small altitude changes), scaled about its start so that its length is drawn
uniformly from ``length_range_m`` ([Kulathunga23]: twenty trajectories of 40-60 m, 1.5 m/s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planners.bspline import BSplineReference


@dataclass(frozen=True)
class TrajectorySpec:
    """What the generator produces.

    Attributes:
        length_range_m: (min, max) arc length [m].
        max_speed_mps, max_acc_mps2: timing limits of the B-spline.
        n_waypoints: waypoints per trajectory (>= 3).
        start_ned_m: common start point [m] (NED; down negative is above ground).
        max_turn_rad: largest heading change between waypoint legs [rad].
        max_climb_m: largest altitude change per leg before scaling [m].
    """

    length_range_m: tuple[float, float] = (40.0, 60.0)
    max_speed_mps: float = 1.5
    max_acc_mps2: float = 1.0
    n_waypoints: int = 8
    start_ned_m: tuple[float, float, float] = (0.0, 0.0, -3.0)
    max_turn_rad: float = 1.2
    max_climb_m: float = 0.5

    def __post_init__(self) -> None:
        lo, hi = self.length_range_m
        if not 0 < lo <= hi:
            raise ValueError(f"length_range_m must satisfy 0 < min <= max, got {lo, hi}")
        if self.n_waypoints < 3:
            raise ValueError(f"n_waypoints must be >= 3, got {self.n_waypoints}")


def generate_trajectories(
    count: int, seed: int, spec: TrajectorySpec | None = None
) -> list[BSplineReference]:
    """``count`` distinct trajectories; the same seed gives the same trajectories."""
    spec = spec or TrajectorySpec()
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        heading = rng.uniform(-np.pi, np.pi)
        steps = [np.zeros(3)]
        for _ in range(spec.n_waypoints - 1):
            heading += rng.uniform(-spec.max_turn_rad, spec.max_turn_rad)
            leg = rng.uniform(4.0, 8.0)
            climb = rng.uniform(-spec.max_climb_m, spec.max_climb_m)
            steps.append(steps[-1] + [leg * np.cos(heading), leg * np.sin(heading), climb])
        offsets = np.array(steps)
        target = rng.uniform(*spec.length_range_m)
        start = np.asarray(spec.start_ned_m, dtype=float)
        raw = BSplineReference(start + offsets, spec.max_speed_mps, spec.max_acc_mps2)
        scale = target / raw.length_m()
        out.append(BSplineReference(start + scale * offsets, spec.max_speed_mps, spec.max_acc_mps2))
    return out
