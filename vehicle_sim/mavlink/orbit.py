"""PX4's Orbit over MAVLink: MAV_CMD_DO_ORBIT in, ORBIT_EXECUTION_STATUS out.

[MAVLink] MAV_CMD_DO_ORBIT: param1 radius [m] (negative: counter-clockwise; NaN: keep),
param2 velocity [m/s] (NaN: keep), param3 ORBIT_YAW_BEHAVIOUR (NaN or 5, UNCHANGED: keep, else
MC_ORBIT_YAW_MOD), param4 orbits (PX4 orbits until told otherwise; not honoured), param5/6
(COMMAND_INT x/y) the
centre's latitude/longitude [deg] (NaN, or INT32_MAX in COMMAND_INT: the current centre or
the vehicle's position), param7 (z) the altitude AMSL [m] (NaN: keep). MAVSDK's do_orbit
sends it as COMMAND_INT. PX4 reports the mode as POSCTL sub mode ORBIT in HEARTBEAT and
streams ORBIT_EXECUTION_STATUS at 2 Hz while it orbits (mavlink_main.cpp's default rate).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.geodetic import GeodeticOrigin
from vehicle_sim.orbit import Orbit

if TYPE_CHECKING:
    from vehicle_sim import CommandResult, Simulator

ORBIT_STATUS_PERIOD_S = 0.5  # 2 Hz
_FACTORY = mavlink2.MAVLink(None)


def start_orbit(sim: Simulator, p: tuple[float, ...], origin: GeodeticOrigin) -> CommandResult:
    """Run DO_ORBIT's parameters ``p`` (param1..param7, degrees and metres AMSL) on ``sim``.

    Raises:
        ValueError: an infinite parameter, a latitude outside [-90, 90] deg or a longitude
            outside [-180, 180] deg.
    """
    radius, velocity, yaw_behaviour = p[0], p[1], p[2]
    lat, lon, alt = p[4], p[5], p[6]
    if any(math.isinf(v) for v in (radius, velocity, yaw_behaviour, lat, lon, alt)):
        raise ValueError("orbit parameters must be finite or NaN")
    if math.isfinite(lat) and not -90.0 <= lat <= 90.0:
        raise ValueError(f"orbit centre latitude {lat:g} deg is not in [-90, 90]")
    if math.isfinite(lon) and not -180.0 <= lon <= 180.0:
        raise ValueError(f"orbit centre longitude {lon:g} deg is not in [-180, 180]")
    north, east, down = origin.to_local(lat, lon, alt if math.isfinite(alt) else 0.0)
    centre = (north, east) if math.isfinite(lat) and math.isfinite(lon) else None
    return sim.orbit(radius, velocity, yaw_behaviour, centre, down if math.isfinite(alt) else None)


def orbit_execution_status(
    orbit: Orbit, origin: GeodeticOrigin, t_s: float
) -> mavlink2.MAVLink_orbit_execution_status_message:
    """ORBIT_EXECUTION_STATUS of ``orbit`` at simulated time ``t_s`` [s]: the signed radius
    (negative counter-clockwise), the centre in MAV_FRAME_GLOBAL (degE7) and its AMSL
    altitude [m], as PX4 sends it."""
    lat, lon, alt = origin.to_global((*orbit.centre_ne_m, orbit.down_m))
    if not (abs(lat) <= 90.0 and abs(lon) <= 180.0 and math.isfinite(alt)):
        raise ValueError(f"orbit centre {lat}, {lon}, {alt} is not a place on earth")
    radius = math.copysign(orbit.radius_m, orbit.velocity_mps)
    return _FACTORY.orbit_execution_status_encode(
        int(t_s * 1e6),
        radius,
        mavlink2.MAV_FRAME_GLOBAL,
        int(round(lat * 1e7)),
        int(round(lon * 1e7)),
        alt,
    )
