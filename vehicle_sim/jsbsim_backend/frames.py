"""Frame helpers for mapping JSBSim's earth-centred state onto a local NED frame.

JSBSim reports position and velocity in ECEF and attitude as Z-Y-X Euler angles relative to the
local NED frame at the vehicle; its body frame is X forward, Y right, Z down (PX4's FRD axes). We
express everything in the NED tangent frame at a fixed origin, so that d(pos_ned)/dt = vel_ned
holds exactly.
"""

from __future__ import annotations

import math

import numpy as np


def ecef_to_ned_matrix(lat_geod_rad: float, lon_rad: float) -> np.ndarray:
    """Rotation (3, 3) taking ECEF vectors into the NED frame at a geodetic latitude/longitude."""
    s_lat, c_lat = math.sin(lat_geod_rad), math.cos(lat_geod_rad)
    s_lon, c_lon = math.sin(lon_rad), math.cos(lon_rad)
    return np.array(
        [
            [-s_lat * c_lon, -s_lat * s_lon, c_lat],
            [-s_lon, c_lon, 0.0],
            [-c_lat * c_lon, -c_lat * s_lon, -s_lat],
        ]
    )


def quat_wxyz_from_dcm(dcm: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix (3, 3).

    ``dcm`` maps vectors from frame A into frame B (v_B = dcm @ v_A); the quaternion rotates A
    into B in the Hamilton convention (v_B = q * v_A * q^-1). Uses the largest-diagonal branch
    (Shepperd) so it stays accurate for every attitude.
    """
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = np.asarray(dcm, dtype=float).tolist()
    trace = r00 + r11 + r22
    diag = (trace, r00, r11, r22)
    k = diag.index(max(diag))
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = (0.25 * s, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s)
    elif k == 1:
        s = 2.0 * math.sqrt(1.0 + r00 - r11 - r22)
        q = ((r21 - r12) / s, 0.25 * s, (r01 + r10) / s, (r02 + r20) / s)
    elif k == 2:
        s = 2.0 * math.sqrt(1.0 - r00 + r11 - r22)
        q = ((r02 - r20) / s, (r01 + r10) / s, 0.25 * s, (r12 + r21) / s)
    else:
        s = 2.0 * math.sqrt(1.0 - r00 - r11 + r22)
        q = ((r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, 0.25 * s)
    norm = math.copysign(math.sqrt(sum(c * c for c in q)), q[0])
    return np.array(q) / norm


def ned_to_body_matrix(roll_rad: float, pitch_rad: float, yaw_rad: float) -> np.ndarray:
    """Rotation (3, 3) taking local NED vectors into the body frame, from Z-Y-X Euler angles."""
    sr, cr = math.sin(roll_rad), math.cos(roll_rad)
    sp, cp = math.sin(pitch_rad), math.cos(pitch_rad)
    sy, cy = math.sin(yaw_rad), math.cos(yaw_rad)
    return np.array(
        [
            [cp * cy, cp * sy, -sp],
            [sr * sp * cy - cr * sy, sr * sp * sy + cr * cy, sr * cp],
            [cr * sp * cy + sr * sy, cr * sp * sy - sr * cy, cr * cp],
        ]
    )
