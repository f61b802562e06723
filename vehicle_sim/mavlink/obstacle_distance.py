"""The range sensor on the wire: MAVLink OBSTACLE_DISTANCE ([MAVLink] common.xml, id 330).

As PX4 and ArduPilot use it for collision prevention: 72 distances in cm, sector i at
angle_offset + i * increment_f degrees, clockwise from north in MAV_FRAME_LOCAL_NED;
max_distance + 1 means "no obstacle within max_distance", UINT16_MAX "no data" (unused
sectors). The sensor sits at the vehicle's centre: the receiver takes the scan's origin from
the vehicle position it has for the same time.
"""

from __future__ import annotations

import numpy as np
from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.world_contact import RangeScan

N_SECTORS = 72
UINT16_MAX = 65535
_FACTORY = mavlink2.MAVLink(None)


def obstacle_distance_message(scan: RangeScan, min_range_m: float) -> mavlink2.MAVLink_message:
    """OBSTACLE_DISTANCE for ``scan`` (at most 72 evenly spaced beams, the first at north)."""
    k = scan.angles_rad.size
    if not 1 <= k <= N_SECTORS:
        raise ValueError(f"OBSTACLE_DISTANCE carries 1..{N_SECTORS} sectors, got {k}")
    max_cm = int(round(scan.max_range_m * 100.0))
    d = scan.distances_m
    cm = np.where(np.isfinite(d), np.round(np.nan_to_num(d, posinf=0.0) * 100.0), max_cm + 1)
    distances = [UINT16_MAX] * N_SECTORS
    distances[:k] = [int(np.clip(v, 0, UINT16_MAX - 1)) for v in cm]
    increment_deg = 360.0 / k
    return _FACTORY.obstacle_distance_encode(
        int(round(scan.t_s * 1e6)),
        mavlink2.MAV_DISTANCE_SENSOR_LASER,
        distances,
        int(round(increment_deg)),
        int(round(min_range_m * 100.0)),
        max_cm,
        increment_deg,
        float(np.degrees(scan.angles_rad[0])),
        mavlink2.MAV_FRAME_LOCAL_NED,
    )
