"""The obstacle-aware companion planner: [Kulathunga23]'s NMPC + map + replanner + regeneration.

Each control cycle:
1. new range scans enter the incremental KD-tree map (:mod:`planners.obstacle_map`), hits
   within ``update_range_m`` (paper: u_r 4-6 m);
2. when the map has grown and the stretch of reference ahead is blocked, it becomes the
   shortest detour round the known obstacles (:mod:`planners.local_detour`, our choice) and
   is pushed out of them (:func:`planners.replanner.push_out`, the paper's replanner), a few
   iterations per cycle; another path planner can take the detour's place through
   :mod:`planners.stretch_replanner` (the paper's RRT* row does);
3. with ``regenerate`` on, a vehicle more than ~2 m from the reference point regenerates the
   reference from where it is to the goal (paper, Fig. 7);
4. the NMPC (N_o nearest map points per node as hard constraints with safe distance d_o,
   eq. 4; the GP residual model in the same solve when given) tracks the reference; a failed
   or infeasible solve gives the safe command (brake and hover) through the planner policy.

Our choices: the reference's progress follows the vehicle (it is at most ``lead_m`` ahead of
the vehicle's projection on the path; see :mod:`planners.path_reference`), and the initial
reference is the mission's, sampled into a path; the map starts empty (the companion knows
only what it has sensed). ``solve_time_s`` of every result is the whole cycle (map, replanner
and NMPC), the paper's "computation time per planning cycle".
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from companion.link import ObstacleDistances
from companion.nmpc_planner import CompanionNmpc
from planners.local_detour import ShortestDetour
from planners.obstacle_map import PointObstacleMap
from planners.path_reference import PathReference, PolylinePath
from planners.plan_result import PlanResult, safe_result
from planners.reference import PlannerState, Reference
from planners.replanner import (
    ReplannerConfig,
    needs_regeneration,
    push_out,
    resample,
    spline_path,
)
from planners.stretch_replanner import BlockedStretch, StretchReplanner

_PATH_SAMPLES_PER_S = 10.0
_REFINE_ITERATIONS = 8  # pushes per control cycle while the stretch ahead is not clear


@dataclass(frozen=True)
class ClutterSettings:
    """How the obstacle-aware planner flies.

    Attributes:
        regenerate: regenerate the reference when the vehicle is far from it (paper Fig. 7).
        replanner: the replanner's clearance, waypoint spacing, iterations, regeneration
            distance.
        max_speed_mps, max_acc_mps2: the reference's speed and braking limits.
        lead_m: how far the reference point may run ahead of the vehicle's projection [m];
            above the regeneration distance, so that a vehicle held up head-on by an
            obstacle falls far enough behind to regenerate (paper, Fig. 7).
        voxel_m, point_radius_m, update_range_m: the map (see PointObstacleMap).
        max_scan_age_s: without a new range scan for longer than this [s] the planner gives
            the safe command (brake and hover): it would be flying blind.
        shortest_detour: a blocked stretch of reference becomes the shortest detour around
            the known obstacles before it is pushed out (our choice); off: only pushed out,
            as the paper's replanner.
        detour_rejoin_m: the detour rejoins the reference this far [m] ahead (or at the first
            clear waypoint beyond): twice the sensing range, just beyond what the map can
            know (20 m flew the same on a second forest).
        rejoin_m: a regenerated reference runs straight from the vehicle to the initial one
            this far [m] ahead of the vehicle's projection on it, then along it.
    """

    regenerate: bool = True
    replanner: ReplannerConfig = field(default_factory=ReplannerConfig)
    max_speed_mps: float = 1.5
    max_acc_mps2: float = 1.0
    lead_m: float = 2.5
    voxel_m: float = 0.15
    point_radius_m: float = 0.1
    update_range_m: float = 5.0
    max_scan_age_s: float = 0.5
    rejoin_m: float = 1.0
    shortest_detour: bool = True
    detour_rejoin_m: float = 10.0


class ClutterNmpc:
    """See the module docstring. ``nmpc`` must have been built with n_obstacles > 0;
    ``stretch_replanner`` replaces a blocked stretch of reference (default: the shortest
    detour when ``settings.shortest_detour``, else none: push-out only).

    Attributes:
        obstacle_map: what the companion has sensed so far.
        stretch_replanner: what replaces a blocked stretch (None: only pushed out).
        regenerations, replans: counts over the flight.
        path: the current reference path (None before the first plan).
    """

    honours_obstacles = True

    def __init__(
        self,
        nmpc: CompanionNmpc,
        settings: ClutterSettings | None = None,
        stretch_replanner: StretchReplanner | None = None,
    ) -> None:
        self.settings = settings or ClutterSettings()
        s = self.settings
        if stretch_replanner is None and s.shortest_detour:
            r = s.replanner
            rejoin = s.detour_rejoin_m
            stretch_replanner = ShortestDetour(r.clearance_m, r.waypoint_spacing_m, rejoin)
        self.stretch_replanner = stretch_replanner
        self._nmpc = nmpc
        self.obstacle_map = PointObstacleMap(s.voxel_m, s.point_radius_m, s.update_range_m)
        nmpc.set_obstacles(self.obstacle_map)
        self.regenerations = 0
        self.replans = 0
        self.path: PolylinePath | None = None
        self._initial: PolylinePath | None = None
        self._waypoints: np.ndarray | None = None
        self._anchor: np.ndarray | None = None
        self._map_version = -1
        self._s_m = 0.0
        self._last_t_s: float | None = None
        self._last_scan_t_s = -np.inf
        self._scan_age_s = np.inf

    @property
    def augmented(self) -> bool:
        return self._nmpc.augmented

    @property
    def flown_model(self) -> str:
        """What its NMPC plans with, in words (CompanionNmpc.flown_model)."""
        return self._nmpc.flown_model

    def one_step_velocity(
        self,
        vel_ned_mps: np.ndarray,
        cmd_vel_ned_mps: np.ndarray,
        pos_ned_m: np.ndarray | None = None,
    ) -> np.ndarray:
        return self._nmpc.one_step_velocity(vel_ned_mps, cmd_vel_ned_mps, pos_ned_m)

    def observe_obstacles(self, scan: ObstacleDistances) -> None:
        """Take a range scan into the map (each scan once)."""
        if scan.t_s > self._last_scan_t_s:
            self._last_scan_t_s = scan.t_s
            self._scan_age_s = 0.0
            self.obstacle_map.add_scan(scan.origin_ned_m, scan.angles_rad, scan.distances_m)

    def reference_point_ned_m(self) -> np.ndarray | None:
        """Where the reference is now [m] (3,), None before the first plan."""
        return None if self.path is None else self.path.at(self._s_m)[0][0]

    def plan(self, state: PlannerState, reference: Reference, t_s: float) -> PlanResult:
        """One cycle (see the module docstring); never raises."""
        start = time.perf_counter()
        if self._last_t_s is not None:
            self._scan_age_s += max(0.0, float(t_s) - self._last_t_s)
        if self._scan_age_s > self.settings.max_scan_age_s:
            m = self._nmpc.model
            age = "never" if np.isinf(self._scan_age_s) else f"{self._scan_age_s:.1f} s ago"
            self._last_t_s = float(t_s)
            return safe_result(m.nu, m.nx, f"no range scan (last {age}): flying blind")
        try:
            snapshot = self._reference(state, reference, float(t_s))
        except Exception as exc:  # noqa: BLE001 - the flight must get a command
            result = self._nmpc.plan(state, reference, t_s)
            return replace(result, ok=False, reason=f"replanner error: {exc}")
        result = self._nmpc.plan(state, snapshot, t_s)
        return replace(result, solve_time_s=time.perf_counter() - start)

    def _reference(self, state: PlannerState, reference: Reference, t_s: float) -> PathReference:
        s = self.settings
        pos = np.asarray(state.pos_ned_m, dtype=float)
        if self._initial is None:
            n = max(2, int(reference.duration_s * _PATH_SAMPLES_PER_S) + 1)
            pts = reference.sample(np.linspace(0.0, reference.duration_s, n)).pos_ned_m
            self._initial = PolylinePath(np.vstack([pos, pts]))
            spacing = s.replanner.waypoint_spacing_m
            self._set_waypoints(resample(self._initial.points_ned_m, spacing), anchor=True)
            self._last_t_s = t_s
        path = self.path
        dt_s = max(0.0, t_s - self._last_t_s)
        self._last_t_s = t_s
        s_proj = path.project(pos, self._s_m - 1.0, self._s_m + s.lead_m + 2.0)
        speed = float(self._profile(path).speed_at(np.array([self._s_m]))[0])
        self._s_m = min(self._s_m + max(speed, 0.2) * dt_s, s_proj + s.lead_m, path.length_m)
        ref_point = path.at(self._s_m)[0][0]
        if s.regenerate and needs_regeneration(pos, ref_point, s.replanner):
            self._regenerate(pos)
        elif self.obstacle_map.version != self._map_version:
            self._refine()
        return self._profile(self.path, self._s_m, t_s)

    def _profile(self, path: PolylinePath, s0_m: float = 0.0, t0_s: float = 0.0) -> PathReference:
        s = self.settings
        return PathReference(path, s0_m, t0_s, s.max_speed_mps, s.max_acc_mps2)

    def _set_waypoints(
        self,
        waypoints: np.ndarray,
        window: tuple[int, int] | None = None,
        iterations: int | None = None,
        anchor: bool = False,
    ) -> None:
        """Push ``waypoints`` out; ``anchor``: they are newly generated (the reference a
        refinement may not stray from by more than max_shift_m)."""
        if anchor:
            self._anchor = np.array(waypoints, dtype=float)
        replan = push_out(
            waypoints,
            self.obstacle_map,
            self.settings.replanner,
            window,
            iterations,
            self._anchor,
        )
        self._map_version = self.obstacle_map.version
        self._waypoints = replan.waypoints_ned_m
        self.path = replan.path
        self.replans += 1

    def _refine(self) -> None:
        """When the map has grown and the stretch of reference ahead (the map's range, twice)
        is no longer clear: the stretch replanner splices in new waypoints (the shortest
        detour, by default), then the stretch is pushed out (a few iterations per cycle; the
        next cycles go on while it is not clear); keep the progress point."""
        s = self.settings
        ref_point = self.path.at(self._s_m)[0][0]
        s_old = self._s_m
        wp = self._waypoints
        here = int(np.argmin(np.linalg.norm(wp - ref_point, axis=1)))
        reach = int(np.ceil(2.0 * s.update_range_m / s.replanner.waypoint_spacing_m))
        window = (here - 1, here + reach)
        replanner = self.stretch_replanner
        trigger = s.replanner
        if replanner is not None and replanner.trigger_clearance_m is not None:
            trigger = replace(trigger, clearance_m=replanner.trigger_clearance_m)
        stretch = push_out(wp, self.obstacle_map, trigger, window, 0, self._anchor)
        if stretch.ok:
            self._map_version = self.obstacle_map.version
            return
        splice = None
        if replanner is not None:
            blocked = BlockedStretch(wp, here, self._initial.points_ned_m[-1])
            splice = replanner.splice(blocked, self.obstacle_map)
        if splice is not None:
            new, end = splice.points_ned_m, splice.end
            self._waypoints = np.vstack([wp[: here + 1], new, wp[end:]])
            self._anchor = np.vstack([self._anchor[: here + 1], new, self._anchor[end:]])
        if replanner is None or replanner.push_out_after:
            self._set_waypoints(self._waypoints, window, _REFINE_ITERATIONS)
        else:
            self._map_version = self.obstacle_map.version
            if splice is None:
                return
            self.path = spline_path(self._waypoints)
            self.replans += 1
        self._s_m = self.path.project(ref_point, max(0.0, s_old - 3.0), s_old + 3.0)

    def _regenerate(self, pos: np.ndarray) -> None:
        """A new reference from ``pos`` straight to the initial one ``rejoin_m`` ahead (our
        choice), then along it, pushed out."""
        initial = self._initial
        s_here = initial.project(pos, 0.0, initial.length_m)
        rest = initial.points_ned_m[initial.s_m > s_here + self.settings.rejoin_m]
        if rest.shape[0] == 0:
            rest = initial.points_ned_m[-1:]
        start = np.array([pos[0], pos[1], rest[0][2]])
        spacing = self.settings.replanner.waypoint_spacing_m
        self._set_waypoints(resample(np.vstack([start, rest]), spacing), anchor=True)
        self._s_m = 0.0
        self.regenerations += 1
