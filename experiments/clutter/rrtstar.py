"""The RRT* baseline of [Kulathunga23] Table 3 (their ref. 13), from OMPL's Python bindings.

OMPL's ``RRTstar`` ([OMPL]; RRT* is [Karaman11]) plans a 2-D path (north, east) at flight
altitude, a state being valid when its clearance to every obstacle is at least
``clearance_m``; it stops after ``iterations`` iterations (the paper: max_iterations =
10000). Two maps: :func:`plan_rrtstar` plans in the full, known forest (an oracle, stronger
than the paper's baseline); :func:`plan_rrtstar_in_map` plans in the companion's sensed point
map (unknown space free), which the online baseline (:mod:`experiments.clutter.online_rrtstar`)
re-plans as the map grows, as the paper's RRT* row does (3.1 s per planning iteration, 0.3
success: it plans in the map it has built so far). Validity is looked up in a grid of 5 cm
cells computed once per problem (conservative by half a cell diagonal). OMPL's random
generator is seeded once per process (``ompl.util.RNG.setSeed`` works only before its first
use), so a fresh process planning the same problems in the same order gets the same paths.
"""

from __future__ import annotations

import numpy as np

from planners.obstacles import Cylinder, ObstacleWorld, Sphere

_seeded = False
_CELL_M = 0.05  # validity grid cell [m]


def _free_grid(
    world: ObstacleWorld, bounds_ne_m: tuple[float, ...], clearance_m: float, altitude_m: float
) -> np.ndarray:
    """Cells whose whole square keeps ``clearance_m`` (centre clearance minus the half
    diagonal): a lookup instead of a geometric query per state (OMPL checks millions). Each
    obstacle is rasterised in its own window (its horizontal extent plus the clearance)."""
    n = np.arange(bounds_ne_m[0], bounds_ne_m[1], _CELL_M) + _CELL_M / 2
    e = np.arange(bounds_ne_m[2], bounds_ne_m[3], _CELL_M) + _CELL_M / 2
    free = np.ones((n.size, e.size), dtype=bool)
    margin = clearance_m + _CELL_M / np.sqrt(2.0)
    for obstacle in world.obstacles:
        if isinstance(obstacle, Cylinder):
            centre, half = np.asarray(obstacle.center_ne_m), np.full(2, obstacle.radius_m)
        elif isinstance(obstacle, Sphere):
            centre, half = np.asarray(obstacle.center_ned_m[:2]), np.full(2, obstacle.radius_m)
        else:
            centre, half = (
                np.asarray(obstacle.center_ned_m[:2]),
                np.asarray(obstacle.half_extents_m[:2]),
            )
        lo_n, hi_n = (
            np.searchsorted(n, centre[0] - half[0] - margin),
            np.searchsorted(n, centre[0] + half[0] + margin),
        )
        lo_e, hi_e = (
            np.searchsorted(e, centre[1] - half[1] - margin),
            np.searchsorted(e, centre[1] + half[1] + margin),
        )
        if lo_n >= hi_n or lo_e >= hi_e:
            continue
        nn, ee = np.meshgrid(n[lo_n:hi_n], e[lo_e:hi_e], indexing="ij")
        pts = np.column_stack([nn.ravel(), ee.ravel(), np.full(nn.size, -altitude_m)])
        near = ObstacleWorld([obstacle]).clearance_m(pts).reshape(nn.shape) < margin
        free[lo_n:hi_n, lo_e:hi_e] &= ~near
    return free


def _points_free_grid(
    points_ne_m: np.ndarray, radius_m: float, bounds_ne_m: tuple[float, ...], clearance_m: float
) -> np.ndarray:
    """As :func:`_free_grid` for map points (k, 2) [m] of radius ``radius_m``: each point
    stamps the disk of cells within radius + clearance (+ half a cell diagonal) of it."""
    n_cells = int(np.ceil((bounds_ne_m[1] - bounds_ne_m[0]) / _CELL_M))
    e_cells = int(np.ceil((bounds_ne_m[3] - bounds_ne_m[2]) / _CELL_M))
    free = np.ones((n_cells, e_cells), dtype=bool)
    reach = radius_m + clearance_m + _CELL_M / np.sqrt(2.0)
    k = int(np.ceil(reach / _CELL_M))
    di, dj = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1), indexing="ij")
    disk = np.hypot(di, dj) * _CELL_M <= reach
    di, dj = di[disk], dj[disk]
    pts = np.asarray(points_ne_m, dtype=float).reshape(-1, 2)
    ci = np.floor((pts[:, 0] - bounds_ne_m[0]) / _CELL_M).astype(int)
    cj = np.floor((pts[:, 1] - bounds_ne_m[2]) / _CELL_M).astype(int)
    ii, jj = (ci[:, None] + di).ravel(), (cj[:, None] + dj).ravel()
    inside = (ii >= 0) & (ii < n_cells) & (jj >= 0) & (jj < e_cells)
    free[ii[inside], jj[inside]] = False
    return free


def plan_rrtstar(
    world: ObstacleWorld,
    start_ne_m: np.ndarray,
    goal_ne_m: np.ndarray,
    bounds_ne_m: tuple[float, float, float, float],
    clearance_m: float = 0.8,
    iterations: int = 10000,
    seed: int = 0,
    altitude_m: float = 2.5,
) -> np.ndarray | None:
    """A collision-free path (k, 2) [m] from start to goal in the known ``world``, or None
    when RRT* found none.

    ``bounds_ne_m`` = (north_min, north_max, east_min, east_max) [m]. Raises ImportError
    with the install line when OMPL is missing."""
    free = _free_grid(world, bounds_ne_m, clearance_m, altitude_m)
    return _plan_on_grid(free, bounds_ne_m, start_ne_m, goal_ne_m, iterations, seed)


def plan_rrtstar_in_map(
    points_ne_m: np.ndarray,
    point_radius_m: float,
    start_ne_m: np.ndarray,
    goal_ne_m: np.ndarray,
    bounds_ne_m: tuple[float, float, float, float],
    clearance_m: float = 0.8,
    iterations: int = 10000,
    seed: int = 0,
) -> np.ndarray | None:
    """As :func:`plan_rrtstar` in a sensed map: obstacle points (k, 2) [m] of radius
    ``point_radius_m``, unknown space free. Within ``clearance_m`` of the start only the
    obstacles themselves are invalid (a vehicle may be inside the clearance already: it
    has to leave it)."""
    free = _points_free_grid(points_ne_m, point_radius_m, bounds_ne_m, clearance_m)
    k = int(np.ceil(clearance_m / _CELL_M))
    i0 = int((start_ne_m[0] - bounds_ne_m[0]) / _CELL_M)
    j0 = int((start_ne_m[1] - bounds_ne_m[2]) / _CELL_M)
    ii, jj = np.meshgrid(
        np.arange(i0 - k, i0 + k + 1), np.arange(j0 - k, j0 + k + 1), indexing="ij"
    )
    near = (np.hypot(ii - i0, jj - j0) <= k) & (ii >= 0) & (jj >= 0)
    near &= (ii < free.shape[0]) & (jj < free.shape[1])
    bare = _points_free_grid(points_ne_m, point_radius_m, bounds_ne_m, 0.0)
    free[ii[near], jj[near]] = bare[ii[near], jj[near]]
    return _plan_on_grid(free, bounds_ne_m, start_ne_m, goal_ne_m, iterations, seed)


def _plan_on_grid(
    free: np.ndarray,
    bounds_ne_m: tuple[float, ...],
    start_ne_m: np.ndarray,
    goal_ne_m: np.ndarray,
    iterations: int,
    seed: int,
) -> np.ndarray | None:
    try:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError(
            "the RRT* baseline needs OMPL's Python bindings: pip install '.[planning]'"
        ) from exc
    global _seeded
    ou.setLogLevel(ou.LogLevel.LOG_ERROR)
    if not _seeded:
        ou.RNG.setSeed(seed)
        _seeded = True
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    for axis, (lo, hi) in enumerate((bounds_ne_m[0:2], bounds_ne_m[2:4])):
        bounds.setLow(axis, float(lo))
        bounds.setHigh(axis, float(hi))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)

    n0, e0 = bounds_ne_m[0], bounds_ne_m[2]
    rows, cols = free.shape

    def valid(state) -> bool:
        i = int((state[0] - n0) / _CELL_M)
        j = int((state[1] - e0) / _CELL_M)
        return 0 <= i < rows and 0 <= j < cols and bool(free[i, j])

    setup.setStateValidityChecker(valid)
    start, goal = space.allocState(), space.allocState()
    for state, ne in ((start, start_ne_m), (goal, goal_ne_m)):
        state[0], state[1] = float(ne[0]), float(ne[1])
    setup.setStartAndGoalStates(start, goal)
    info = setup.getSpaceInformation()
    # of the extent (~0.36 m here): trunks grown by the clearance are >= 2 m wide
    info.setStateValidityCheckingResolution(0.004)
    planner = og.RRTstar(info)
    setup.setPlanner(planner)
    done = ob.PlannerTerminationCondition(lambda: planner.numIterations() >= iterations)
    setup.solve(done)
    if not setup.haveExactSolutionPath():
        return None
    path = setup.getSolutionPath()
    return np.array(
        [[path.getState(i)[0], path.getState(i)[1]] for i in range(path.getStateCount())]
    )
