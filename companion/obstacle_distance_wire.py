"""MAVLink OBSTACLE_DISTANCE ([MAVLink] common.xml, id 330) to the companion's
:class:`~companion.link.ObstacleDistances`, as a real vehicle's range sensor delivers it.

Distances are in cm; sector i points at angle_offset + i * increment (increment_f when set,
degrees, clockwise from north for MAV_FRAME_LOCAL_NED, from the vehicle's heading for
MAV_FRAME_BODY_FRD); max_distance + 1 and above means "nothing within max_distance", UINT16_MAX
an unused sector (dropped), a reading below min_distance "no data" (dropped). The message has
no position: the scan's origin is the vehicle position the caller has for that time.
"""

from __future__ import annotations

import math

import numpy as np

from companion.link import ObstacleDistances

UINT16_MAX = 65535
MAV_FRAME_LOCAL_NED = 1
MAV_FRAME_BODY_FRD = 12


def obstacle_distances_of(
    msg: object, origin_ned_m: np.ndarray, t_s: float, yaw_rad: float = 0.0
) -> ObstacleDistances:
    """The scan in ``msg`` (an OBSTACLE_DISTANCE), taken at ``origin_ned_m`` (3,) [m] at
    ``t_s`` [s]; ``yaw_rad`` turns a body-frame scan into NED."""
    raw = np.asarray(msg.distances, dtype=float)
    increment_deg = float(msg.increment_f) if msg.increment_f > 0 else float(msg.increment)
    angles = np.radians(float(msg.angle_offset) + increment_deg * np.arange(raw.size))
    if int(msg.frame) == MAV_FRAME_BODY_FRD:
        angles = angles + yaw_rad
    used = (raw != UINT16_MAX) & (raw >= float(msg.min_distance))
    max_m = float(msg.max_distance) / 100.0
    dist = np.where(raw > float(msg.max_distance), math.inf, raw / 100.0)
    return ObstacleDistances(
        t_s=float(t_s),
        origin_ned_m=np.asarray(origin_ned_m, dtype=float),
        angles_rad=np.mod(angles[used], 2.0 * np.pi),
        distances_m=dist[used],
        max_range_m=max_m,
    )
