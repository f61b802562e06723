"""The seam between the obstacle-aware planner and the path planner it asks when the map shows
the stretch of reference ahead blocked.

:class:`companion.clutter_planner.ClutterNmpc` finds the blocked stretch and keeps the
reference, its progress and the paper's push-out ([Kulathunga23]'s ref. 9); a
:class:`StretchReplanner` only says which new waypoints replace which old ones. The companion's
own is the shortest detour (:class:`planners.local_detour.ShortestDetour`); the paper's RRT*
row re-plans to the goal through the same seam (``experiments/clutter/online_rrtstar.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from planners.obstacle_map import PointObstacleMap


@dataclass(frozen=True)
class BlockedStretch:
    """The reference the map shows blocked ahead.

    Attributes:
        waypoints_ned_m: (K, 3) the reference's waypoints [m].
        here: index of the waypoint nearest the reference point (the stretch starts there).
        goal_ned_m: (3,) the end of the mission's reference [m].
    """

    waypoints_ned_m: np.ndarray
    here: int
    goal_ned_m: np.ndarray


@dataclass(frozen=True)
class Splice:
    """New waypoints (k, 3) [m] that replace waypoints ``here + 1`` to ``end - 1`` of the
    blocked stretch (``end`` = K: to the goal)."""

    points_ned_m: np.ndarray
    end: int


class StretchReplanner(Protocol):
    """What replaces a blocked stretch.

    Attributes:
        trigger_clearance_m: the stretch counts as blocked when the reference comes closer than
            this to an obstacle surface [m]; None: the replanner settings' clearance.
        push_out_after: the paper's push-out refines the new stretch (off: flown as planned).
    """

    trigger_clearance_m: float | None
    push_out_after: bool

    def splice(self, stretch: BlockedStretch, obstacle_map: PointObstacleMap) -> Splice | None:
        """The new waypoints, or None to keep the stretch as it is."""
        ...
