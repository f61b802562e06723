"""Local NED <-> geodetic conversion around a fixed origin (flat earth, fine for a few km)."""

from __future__ import annotations

import math
from dataclasses import dataclass

EARTH_RADIUS_M = 6378137.0


@dataclass(frozen=True)
class GeodeticOrigin:
    """Geodetic position of the local NED origin (= home). Default: PX4 SITL's Zurich home.

    Attributes:
        lat_deg, lon_deg: WGS84 latitude / longitude [deg].
        alt_amsl_m: altitude above mean sea level [m].
    """

    lat_deg: float = 47.397742
    lon_deg: float = 8.545594
    alt_amsl_m: float = 488.0

    def to_global(self, pos_ned_m: tuple[float, float, float]) -> tuple[float, float, float]:
        """(lat_deg, lon_deg, alt_amsl_m) of a local NED position [m]."""
        north_m, east_m, down_m = (float(v) for v in pos_ned_m)
        lat_deg = self.lat_deg + math.degrees(north_m / EARTH_RADIUS_M)
        lon_deg = self.lon_deg + math.degrees(
            east_m / (EARTH_RADIUS_M * math.cos(math.radians(self.lat_deg)))
        )
        return lat_deg, lon_deg, self.alt_amsl_m - down_m

    def to_local(self, lat_deg: float, lon_deg: float, alt_amsl_m: float) -> tuple[float, ...]:
        """Local NED position [m] of a geodetic one (inverse of :meth:`to_global`); a NaN
        coordinate stays NaN (MAVLink's "keep the current value")."""
        north_m = math.radians(lat_deg - self.lat_deg) * EARTH_RADIUS_M
        east_m = (
            math.radians(lon_deg - self.lon_deg)
            * EARTH_RADIUS_M
            * math.cos(math.radians(self.lat_deg))
        )
        return north_m, east_m, self.alt_amsl_m - alt_amsl_m
