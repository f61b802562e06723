"""Seeded random 3-D reference trajectories like [Kulathunga23]'s real-world experiment.

Each trajectory is a :class:`BSplineReference` through a random walk of waypoints (bounded
heading changes, small altitude changes), scaled about its start so that its length is drawn
uniformly from ``length_range_m`` ([Kulathunga23]: twenty trajectories of 40-60 m, 1.5 m/s).

No trajectory flies below ``min_altitude_m`` (default: PX4's MIS_TAKEOFF_ALT, 2.5 m above home,
the altitude a PX4 mission climbs to before it flies its first waypoint, [PX4-params]): the
random walk of altitudes reflects off that floor (a waypoint d below it goes d above it; if
the spline between waypoints still dips under, the reflecting level is raised by twice the
dip; the start stays where it is), and the horizontal offsets are then rescaled so that the
length is again the drawn one. A walk that never comes down to the floor is left exactly as
drawn. (Without the floor, seed 1 of the agile regime's lengths put a waypoint 0.3 m below
the ground.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from planners.bspline import BSplineReference, spline_points

MIS_TAKEOFF_ALT_M = 2.5  # PX4's default takeoff altitude above home [m] ([PX4-params])
_FLOOR_SAMPLES_PER_SEGMENT = 64  # spline points per segment the floor is checked on
_FLOOR_ITERATIONS = 20  # raises of the reflecting level before giving up


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
        min_altitude_m: lowest altitude above home (down = 0) any point of a trajectory
            flies at [m]; the start must be at or above it.
        ramp_jerk_mps3: the peak jerk [m/s^3] of a jerk-limited start and end, the
            acceleration rising from 0 instead of stepping (planners.bspline; PX4's
            MPC_JERK_AUTO is 4 m/s^3); None (default): the plain spline, its acceleration
            stepping at both ends. The path is the same either way.
    """

    length_range_m: tuple[float, float] = (40.0, 60.0)
    max_speed_mps: float = 1.5
    max_acc_mps2: float = 1.0
    n_waypoints: int = 8
    start_ned_m: tuple[float, float, float] = (0.0, 0.0, -3.0)
    max_turn_rad: float = 1.2
    max_climb_m: float = 0.5
    min_altitude_m: float = MIS_TAKEOFF_ALT_M
    ramp_jerk_mps3: float | None = None

    def __post_init__(self) -> None:
        lo, hi = self.length_range_m
        if not 0 < lo <= hi:
            raise ValueError(f"length_range_m must satisfy 0 < min <= max, got {lo, hi}")
        if self.n_waypoints < 3:
            raise ValueError(f"n_waypoints must be >= 3, got {self.n_waypoints}")
        start_alt_m = -self.start_ned_m[2]
        if not self.min_altitude_m <= start_alt_m:
            raise ValueError(
                f"start_ned_m is {start_alt_m:g} m above home, below min_altitude_m "
                f"{self.min_altitude_m:g} m; start higher or lower the floor"
            )


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
        waypoints = start + target / raw.length_m() * offsets
        if _lowest_altitude_m(waypoints) < spec.min_altitude_m:
            waypoints = _above_floor(waypoints, spec.min_altitude_m, target, spec)
        out.append(
            BSplineReference(
                waypoints,
                spec.max_speed_mps,
                spec.max_acc_mps2,
                ramp_jerk_mps3=spec.ramp_jerk_mps3,
            )
        )
    return out


def _lowest_altitude_m(waypoints_ned_m: np.ndarray) -> float:
    """Lowest altitude [m] of the spline through ``waypoints_ned_m`` (M+1, 3)."""
    return float(-np.max(spline_points(waypoints_ned_m, _FLOOR_SAMPLES_PER_SEGMENT)[:, 2]))


def _above_floor(
    waypoints_ned_m: np.ndarray, floor_m: float, length_m: float, spec: TrajectorySpec
) -> np.ndarray:
    """``waypoints_ned_m`` (M+1, 3) with altitudes reflected off the floor [m] so that the
    spline stays at or above it, then the horizontal offsets from the start rescaled so the
    spline's length is ``length_m`` again (the spline's altitudes depend on the waypoints'
    altitudes only, so the rescale keeps them)."""
    altitude = -waypoints_ned_m[:, 2]
    level = floor_m
    for _ in range(_FLOOR_ITERATIONS):
        folded = waypoints_ned_m.copy()
        folded[1:, 2] = -np.where(altitude < level, 2.0 * level - altitude, altitude)[1:]
        lowest = _lowest_altitude_m(folded)
        if lowest >= floor_m:
            break
        level += 2.0 * (floor_m - lowest)  # twice the dip: ends in a step or two
    else:
        raise RuntimeError(f"could not lift the trajectory above {floor_m:g} m")
    start = folded[0]

    def length_error(horizontal_scale: float) -> float:
        scaled = folded.copy()
        scaled[:, :2] = start[:2] + horizontal_scale * (folded[:, :2] - start[:2])
        ref = BSplineReference(scaled, spec.max_speed_mps, spec.max_acc_mps2)
        return ref.length_m() - length_m

    scale = brentq(length_error, 0.5, 2.0, xtol=1e-9)
    folded[:, :2] = start[:2] + scale * (folded[:, :2] - start[:2])
    return folded
