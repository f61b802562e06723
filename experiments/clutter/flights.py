"""One flight of Table 3: a planner flown from a start to a goal in the forest, in process.

Every flight is the companion's own mission sequence (takeoff, offboard, follow, land) over
the in-process Link, the simulator carrying the forest (contact = crash) and its range
sensor. The forest is moved so that the start is the simulator's origin.

Planners (``kind``):
    proposed         NMPC + GP residual + map + replanner + regeneration ([Kulathunga23])
    nominal          the same without the GP: the companion's clutter planner flown without a
                     model file, on the velocity-lag model (what the GP adds, our ablation)
    gp_no_regeneration  the same with the GP but without regeneration (what regeneration adds)
    no_regeneration  the NMPC replanner without regeneration and without GP (their ref. 9)
    rrtstar          OMPL's RRT* path in the known forest, tracked by the proposed planner's
                     NMPC (with its GP) that also keeps d_o from the known trunks: a global
                     planner with the full map, stronger than the paper's baseline
    rrtstar_online   the paper's RRT* row: OMPL's RRT* re-planned in the sensed map whenever
                     the path ahead is blocked, tracked by the same NMPC (with its GP and
                     d_o) (experiments/clutter/online_rrtstar.py)
    pd               the PD regulator on the initial (straight) reference
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from companion.app import LOCKSTEP_PLAN_BUDGET_S
from companion.clutter_planner import ClutterNmpc, ClutterSettings
from companion.control_loop import Tick
from companion.flight_recorder import FlightRecorder
from companion.inprocess_link import InProcessLink
from companion.mission import Mission
from companion.mission_reference import reference_of
from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from companion.planner_registry import (
    CLUTTER_N_OBSTACLES,
    CLUTTER_SAFE_DISTANCE_M,
    clutter_nominal,
)
from companion.runner import RunnerConfig, fly_mission
from experiments.clutter.online_rrtstar import online_rrtstar
from experiments.clutter.scenario import ALTITUDE_M, shifted
from flightlog.schema import FlightLog
from gp.model_io import ResidualModel
from planners.obstacle_map import PointObstacleMap
from planners.obstacles import ObstacleWorld
from planners.path_reference import PathReference, PolylinePath
from planners.pd_regulator import PdGains, PdRegulator
from vehicle_sim import Simulator, load_sim_config

PlannerKind = Literal[
    "proposed",
    "nominal",
    "gp_no_regeneration",
    "no_regeneration",
    "rrtstar_online",
    "rrtstar",
    "pd",
]
RATE_HZ = 20.0  # [Kulathunga23] Table 3: s_t = 50 ms
SPEED_MPS = 1.5  # [Kulathunga23]: v_max 1.5 m/s in cluttered flight
VEHICLE = "iris_study"
POINT_RADIUS_M = PointObstacleMap().point_radius_m


@dataclass(frozen=True, eq=False)
class ClutterFlight:
    """A flown pair.

    Attributes:
        kind: the planner; reached: goal reached without contact (the paper's success).
        contacts: contacts with a trunk; distance_m: distance flown while following [m].
        cycle_ms: (n,) computation time of each planning cycle [ms].
        path_ne_m: (n, 2) the flown path in forest coordinates [m].
        log: the schema-v1 log; regenerations: how often the reference was regenerated.
        failures: why the planner returned the safe command, reason -> cycles.
    """

    kind: str
    reached: bool
    contacts: int
    distance_m: float
    cycle_ms: np.ndarray
    path_ne_m: np.ndarray
    log: FlightLog
    regenerations: int
    failures: dict[str, int]


def fly_pair(
    kind: PlannerKind,
    world: ObstacleWorld,
    start_ne_m: np.ndarray,
    goal_ne_m: np.ndarray,
    *,
    seed: int = 0,
    residual_model: ResidualModel | None = None,
    rrt_path_ne_m: np.ndarray | None = None,
    bounds_ne_m: tuple[float, float, float, float] | None = None,
    rrt_iterations: int = 10000,
    settle_s: float = 90.0,
) -> ClutterFlight:
    """Fly ``kind`` from ``start_ne_m`` to ``goal_ne_m`` (2,) [m] in ``world``.

    ``rrt_path_ne_m`` (k, 2) [m]: the known-forest RRT* path ``rrtstar`` tracks;
    ``bounds_ne_m``: (north_min, north_max, east_min, east_max) [m] the online ``rrtstar_online``
    samples in (default: the world's extent plus 2 m); ``rrt_iterations``: its RRT*'s budget
    per plan (paper: 10000)."""
    start = np.asarray(start_ne_m, dtype=float)
    goal = np.asarray(goal_ne_m, dtype=float) - start
    mission = Mission(
        name=f"clutter_{kind}",
        altitude_m=ALTITUDE_M,
        speed_limit_mps=SPEED_MPS,
        reference_kind="waypoints",
        points_ned_m=((0.0, 0.0, -ALTITUDE_M), (float(goal[0]), float(goal[1]), -ALTITUDE_M)),
        goal_tolerance_m=0.5,
    )
    reference = reference_of(mission)
    if bounds_ne_m is None:
        bounds_ne_m = world_bounds_ne_m(world)
    bounds = (
        bounds_ne_m[0] - start[0],
        bounds_ne_m[1] - start[0],
        bounds_ne_m[2] - start[1],
        bounds_ne_m[3] - start[1],
    )
    planner = _planner(kind, residual_model, bounds, rrt_iterations)
    if kind == "rrtstar":
        planner.set_obstacles(shifted(world, start))
        if rrt_path_ne_m is None:
            raise ValueError("the rrtstar flight needs rrt_path_ne_m (from plan_rrtstar)")
        pts = np.column_stack([rrt_path_ne_m - start, np.full(len(rrt_path_ne_m), -ALTITUDE_M)])
        reference = PathReference(PolylinePath(pts), max_speed_mps=SPEED_MPS)
    sim = Simulator(load_sim_config(VEHICLE), seed=seed)
    sim.set_world(shifted(world, start))
    link = InProcessLink(sim, {"vehicle_preset": VEHICLE, "seed": seed})
    recorder = FlightRecorder(period_s=1.0 / RATE_HZ, wall_clock_columns=False)
    cycles: list[float] = []
    path: list[np.ndarray] = []
    failures: dict[str, int] = {}

    def on_tick(tick: Tick) -> None:
        if sim.crashed:
            raise _Crashed  # the flight is over: no need to wait out the follow deadline
        recorder.record(tick)
        if tick.state.mode == "OFFBOARD" and tick.decision.ref_pos_ned_m is not None:
            cycles.append(1000.0 * tick.decision.solve_time_s)
            path.append(tick.state.pos_ned_m[:2] + start)
            if not tick.decision.ok:
                reason = tick.decision.reason.split(" by ")[0][:60]
                failures[reason] = failures.get(reason, 0) + 1

    runner = RunnerConfig(rate_hz=RATE_HZ, settle_timeout_s=settle_s)
    try:
        outcome = fly_mission(link, planner, reference, mission, runner, on_tick, lambda _m: None)
        completed = outcome.status == "completed"
    except _Crashed:
        completed = False
    flown = np.array(path).reshape(-1, 2)
    distance = float(np.sum(np.linalg.norm(np.diff(flown, axis=0), axis=1)))
    contacts = len(sim.contacts)
    log = recorder.to_log({"source": "clutter-bench", "planner": kind, **link.metadata()})
    return ClutterFlight(
        kind,
        completed and contacts == 0,
        contacts,
        distance,
        np.asarray(cycles),
        flown,
        log,
        getattr(planner, "regenerations", 0),
        failures,
    )


class _Crashed(Exception):
    """The vehicle touched an obstacle (the simulator disarmed it)."""


def world_bounds_ne_m(world: ObstacleWorld, margin_m: float = 2.0) -> tuple[float, ...]:
    """(north_min, north_max, east_min, east_max) [m] of the obstacles' centres plus
    ``margin_m``."""
    centres = np.array([_centre_ne(o) for o in world.obstacles]).reshape(-1, 2)
    lo, hi = centres.min(axis=0) - margin_m, centres.max(axis=0) + margin_m
    return (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))


def _centre_ne(obstacle) -> tuple[float, float]:
    centre = getattr(obstacle, "center_ne_m", None)
    return tuple(centre if centre is not None else obstacle.center_ned_m[:2])


def _planner(
    kind: PlannerKind, residual_model: ResidualModel | None, bounds_ne_m, rrt_iterations: int
):
    if kind == "pd":
        return PdRegulator(PdGains(max_speed_mps=SPEED_MPS))
    clutter = kind in (
        "proposed",
        "nominal",
        "gp_no_regeneration",
        "no_regeneration",
        "rrtstar_online",
    )
    settings = NmpcSettings(
        speed_limit_mps=SPEED_MPS,
        period_s=1.0 / RATE_HZ,
        time_budget_s=LOCKSTEP_PLAN_BUDGET_S,
        n_obstacles=CLUTTER_N_OBSTACLES,
        # from a trunk's surface: d_o plus a map point's radius, as the sensing planners keep
        safe_distance_m=CLUTTER_SAFE_DISTANCE_M + (0.0 if clutter else POINT_RADIUS_M),
        # the companion's clutter planner without a GP; the paper's rows fly its kinematic model
        **(clutter_nominal() if kind == "nominal" else {}),
    )
    with_gp = kind in ("proposed", "gp_no_regeneration", "rrtstar_online", "rrtstar")
    nmpc = CompanionNmpc(settings, residual_model if with_gp else None)
    if not clutter:
        return nmpc
    if kind == "rrtstar_online":
        settings = ClutterSettings(max_speed_mps=SPEED_MPS)
        return online_rrtstar(nmpc, bounds_ne_m, settings, rrt_iterations)
    regenerate = kind in ("proposed", "nominal")
    return ClutterNmpc(nmpc, ClutterSettings(regenerate=regenerate, max_speed_mps=SPEED_MPS))
