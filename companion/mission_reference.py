"""The reference trajectory a mission asks for (pure: builds objects, reads no files)."""

from __future__ import annotations

import numpy as np

from companion.mission import Mission, MissionError
from companion.waypoint_reference import WaypointReference
from planners.bspline import BSplineReference
from planners.reference import Reference


def reference_of(mission: Mission) -> Reference:
    """Waypoints -> constant-speed straight legs; bspline -> the cubic B-spline through the
    points, starting and ending at rest, timed so that its speed stays within the mission's
    limit ([Kulathunga23]'s references).

    Raises:
        MissionError: when the reference cannot be built from the mission's points.
    """
    points = np.asarray(mission.points_ned_m, dtype=float)
    try:
        if mission.reference_kind == "waypoints":
            return WaypointReference(points, mission.speed_limit_mps)
        return BSplineReference(points, max_speed_mps=mission.speed_limit_mps)
    except ValueError as exc:
        raise MissionError(f"mission {mission.name}: {exc}") from None
