"""[Kulathunga23] Table 3's RRT* row as the paper ran it: RRT* re-planned in the map built so
far, its path tracked by the NMPC.

The paper's RRT* (their ref. 13, max_iterations 10000) takes 3.1 s per planning iteration and
reaches the goal in 3 of 10 pairs: it plans in the incrementally built map, not in a known
forest. Here it senses as the proposed planner does (the same range scans, map and NMPC with
the GP and d_o), and whenever the map shows the stretch of path ahead closer than
``replan_clearance_m`` to an obstacle, OMPL's RRT* plans again from there to the goal in the
sensed map, unknown space free (:func:`experiments.clutter.rrtstar.plan_rrtstar_in_map`).
No push-out, no detour, no regeneration: RRT* is the whole replanner, asked through the clutter
planner's stretch-replanner seam (:mod:`planners.stretch_replanner`). Our choices: the
replanning trigger, and that a planning iteration's time is reported, not flown (the flight
runs in lockstep, as every planner's here).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from companion.clutter_planner import ClutterNmpc, ClutterSettings
from companion.nmpc_planner import CompanionNmpc
from experiments.clutter.rrtstar import plan_rrtstar_in_map
from planners.obstacle_map import PointObstacleMap
from planners.replanner import resample
from planners.stretch_replanner import BlockedStretch, Splice


@dataclass
class RrtStarToGoal:
    """The stretch replanner of the paper's RRT* row: OMPL's RRT* from the blocked stretch's
    start to the goal in the sensed map, flown as planned (no push-out).

    Attributes:
        bounds_ne_m: (north_min, north_max, east_min, east_max) [m] RRT* samples in, in the
            flight's frame.
        clearance_m: RRT*'s clearance from obstacle surfaces [m].
        spacing_m: spacing of the new waypoints [m].
        iterations: RRT*'s budget per plan (paper: 10000).
        trigger_clearance_m: the path ahead is re-planned when it comes closer than this to
            an obstacle surface [m] (what the NMPC keeps, d_o + a point's radius).
        plans, failures: plans made, and plans that found no path.
    """

    bounds_ne_m: tuple[float, float, float, float]
    clearance_m: float
    spacing_m: float
    iterations: int = 10000
    trigger_clearance_m: float | None = 0.75
    push_out_after: bool = False
    plans: int = field(default=0, init=False)
    failures: int = field(default=0, init=False)

    def splice(self, stretch: BlockedStretch, obstacle_map: PointObstacleMap) -> Splice | None:
        """The RRT* path from the stretch's start to the goal (None when it finds none)."""
        start = stretch.waypoints_ned_m[stretch.here]
        goal = stretch.goal_ned_m
        self.plans += 1
        path = plan_rrtstar_in_map(
            obstacle_map.points_ned_m[:, :2],
            obstacle_map.point_radius_m,
            start[:2],
            goal[:2],
            self.bounds_ne_m,
            self.clearance_m,
            self.iterations,
        )
        if path is None:
            self.failures += 1
            return None
        pts = np.column_stack([path, np.full(path.shape[0], goal[2])])
        return Splice(resample(pts, self.spacing_m)[1:], len(stretch.waypoints_ned_m))


def online_rrtstar(
    nmpc: CompanionNmpc,
    bounds_ne_m: tuple[float, float, float, float],
    settings: ClutterSettings | None = None,
    iterations: int = 10000,
) -> ClutterNmpc:
    """The obstacle-aware planner with RRT* as its whole replanner (see the module docstring):
    ``nmpc`` built with n_obstacles > 0; ``settings``' sensing, map and reference (regeneration
    switched off)."""
    base = replace(settings or ClutterSettings(), regenerate=False)
    r = base.replanner
    rrt = RrtStarToGoal(bounds_ne_m, r.clearance_m, r.waypoint_spacing_m, iterations)
    return ClutterNmpc(nmpc, base, rrt)
