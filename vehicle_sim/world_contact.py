"""A world the simulated vehicle can hit, and a range sensor that sees it.

The simulator does not import the planners (arrows point down); it takes any object with the
two geometric queries of :class:`ContactWorld` (``planners.obstacles.ObstacleWorld`` has
them; the vehicle-sim CLI and the in-process Link load a world file into one).

Contact: after every stretch of at most ``CONTACT_CHECK_STEPS`` physics steps the straight
segment the vehicle's centre swept is checked against the world; a clearance below the
vehicle's radius is a contact. What follows a contact is what PX4 does after a crash in
Gazebo (its land detector / failure detector cuts the motors): the vehicle is disarmed (it
falls), a STATUSTEXT reports it and the truth log carries ``crash`` = 1 from then on.

Range sensor: a horizontal ring of beams at the vehicle's centre, as a 2-D lidar or the
OBSTACLE_DISTANCE message ([MAVLink] OBSTACLE_DISTANCE: 72 sectors, cm, UINT16_MAX for
"nothing within max_distance"). Sector 0 points north (MAV_FRAME_LOCAL_NED, angle_offset 0),
angles grow clockwise seen from above (towards east), as the message defines.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

CONTACT_CHECK_STEPS = 5  # physics steps between contact checks (10 ms at 2 ms)
DEFAULT_VEHICLE_RADIUS_M = 0.3  # an Iris-size frame: arm 0.18 m + propeller 0.12 m


class ContactWorld(Protocol):
    """Geometry the simulator needs (NED, metres)."""

    def segment_clearance_m(self, start_ned_m: np.ndarray, end_ned_m: np.ndarray) -> float:
        """Smallest distance from the segment to any obstacle surface [m]."""
        ...

    def ray_distance_m(
        self, origin_ned_m: np.ndarray, directions_ned: np.ndarray, max_range_m: float
    ) -> np.ndarray:
        """First-hit distance [m] along each unit direction (k, 3), inf when none in range."""
        ...


@dataclass(frozen=True)
class RangeSensorSpec:
    """A horizontal ring range sensor.

    Attributes:
        n_sectors: beams, evenly spaced over 360 deg (OBSTACLE_DISTANCE carries 72).
        min_range_m, max_range_m: the sensor's range [m] ([Kulathunga23]: the map is built
            within about 5 m of the vehicle).
        rate_hz: scans per second.
    """

    n_sectors: int = 72
    min_range_m: float = 0.2
    max_range_m: float = 5.0
    rate_hz: float = 10.0

    def __post_init__(self) -> None:
        if not 1 <= self.n_sectors <= 72:
            raise ValueError(
                f"n_sectors must be in [1, 72] (OBSTACLE_DISTANCE), got {self.n_sectors}"
            )
        if not 0 < self.min_range_m < self.max_range_m:
            raise ValueError(
                f"need 0 < min_range_m < max_range_m, got {self.min_range_m}, {self.max_range_m}"
            )

    @property
    def angles_rad(self) -> np.ndarray:
        """Beam angles [rad] from north, clockwise (towards east), shape (n_sectors,)."""
        return np.arange(self.n_sectors) * (2.0 * np.pi / self.n_sectors)


@dataclass(frozen=True)
class RangeScan:
    """One scan: where it was taken and what each beam saw.

    Attributes:
        t_s: simulated time of the scan [s].
        origin_ned_m: sensor position (3,) [m].
        angles_rad: beam angles from north, clockwise (k,).
        distances_m: range per beam [m] (k,); inf when nothing within max_range_m.
        max_range_m: the sensor's range [m].
    """

    t_s: float
    origin_ned_m: np.ndarray
    angles_rad: np.ndarray
    distances_m: np.ndarray
    max_range_m: float

    def hit_points_ned_m(self) -> np.ndarray:
        """Points (m, 3) [m] where beams hit something."""
        hit = np.isfinite(self.distances_m)
        a, d = self.angles_rad[hit], self.distances_m[hit]
        return self.origin_ned_m + np.column_stack([d * np.cos(a), d * np.sin(a), np.zeros_like(d)])


def scan_world(
    world: ContactWorld, spec: RangeSensorSpec, t_s: float, pos_ned_m: np.ndarray
) -> RangeScan:
    """A scan of ``world`` from ``pos_ned_m`` (3,) at time ``t_s`` [s]; beams below the
    minimum range report inf (a real sensor's blind zone)."""
    angles = spec.angles_rad
    dirs = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
    dist = np.asarray(world.ray_distance_m(np.asarray(pos_ned_m, float), dirs, spec.max_range_m))
    dist = np.where(dist < spec.min_range_m, np.inf, dist)
    return RangeScan(float(t_s), np.array(pos_ned_m, float), angles, dist, spec.max_range_m)


@dataclass(frozen=True)
class Contact:
    """A contact: when, where the vehicle's centre was [m] (3,), and its speed [m/s]."""

    t_s: float
    pos_ned_m: tuple[float, float, float]
    speed_mps: float
    clearance_m: float
