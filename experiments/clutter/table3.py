"""[Kulathunga23] Table 3 reproduced: every planner flown over the seeded pairs of one forest.

Steps: (1) the residual model, learnt as in the paper from obstacle-free flights: the nominal
NMPC flies ``training_flights`` seeded random B-spline trajectories (the study's generator,
30-40 m at 1.5 m/s) and fit-gp's library fits the residual on those logs (low-speed inducing
points, m = 30: the paper's; the study's nominal model and features); (2) each planner
flies each pair; (3) the figures, as the paper's: success fraction (goal reached without
contact), mean computation time per planning cycle, travelled distance mean/max/min, plus
contacts and the residual RMSE of the proposed planner's flights (Table 2's second row:
flights with obstacles). A model that fails its own held-out check against nominal is not
flown (the proposed planner then flies nominal: ``learned_flown`` False); one whose GP does
not beat the identified lag alone flies the lag without its GP (``gp_flown`` False), as the
companion flies such a file.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import get_args

import numpy as np

from companion.nmpc_planner import NmpcSettings
from experiments.clutter.flights import RATE_HZ, VEHICLE, ClutterFlight, PlannerKind, fly_pair
from experiments.clutter.rrtstar import plan_rrtstar
from experiments.clutter.scenario import ClutterScenario, make_scenario
from experiments.study.fitting import fit_residual
from experiments.study.flights import FlightSpec, fly
from experiments.study.metrics import residual_rmse_mps
from planners.forest import ForestSpec
from planners.trajectory_generator import TrajectorySpec, generate_trajectories

PLANNERS: tuple[PlannerKind, ...] = get_args(PlannerKind)


@dataclass(frozen=True)
class Table3Config:
    """Attributes:
    forest: the forest (paper: 60 x 60 x 10 m); n_pairs: start/goal pairs (paper: 10);
    pair_seed: seed of the pairs; training_flights: obstacle-free flights to learn the
    residual from (0: no GP); rrt_iterations: RRT*'s budget per plan, in the known forest
    (rrtstar) and at each re-plan in the sensed map (rrtstar_online) (paper: 10000); planners:
    which to fly.
    """

    forest: ForestSpec = field(default_factory=lambda: ForestSpec(seed=3, density_per_100m2=3.0))
    n_pairs: int = 10
    pair_seed: int = 11
    training_flights: int = 3
    rrt_iterations: int = 10000
    planners: tuple[PlannerKind, ...] = PLANNERS


@dataclass(frozen=True, eq=False)
class Table3Result:
    scenario: ClutterScenario
    flights: dict[str, list[ClutterFlight]]
    learned_flown: bool
    gp_flown: bool


def run_table3(config: Table3Config, progress: Callable[[str], None]) -> Table3Result:
    n_train = config.training_flights
    scenario = make_scenario(config.forest, config.n_pairs, config.pair_seed)
    model, gp_flies = None, False
    if n_train and "proposed" in config.planners:
        progress(f"clutter: {n_train} obstacle-free training flights for the residual model")
        refs = generate_trajectories(n_train, 100, TrajectorySpec(length_range_m=(30.0, 40.0)))
        settings = NmpcSettings(speed_limit_mps=2.0, period_s=1.0 / RATE_HZ)
        logs = [
            fly(FlightSpec(f"clutter_training_{i}", ref, VEHICLE, 100 + i), settings).log
            for i, ref in enumerate(refs)
        ]
        fit = fit_residual(logs, "low_speed", 1.0 / RATE_HZ, m=30, restarts=1)
        model = fit.model if fit.may_fly else None
        for check in (fit.check, fit.structure_check):
            if check is not None:
                progress(f"clutter: {check.describe()}")
        gp_flies = fit.flown == "learned"
        flies = {
            "nominal": "nominal",
            "structure": "the identified lag alone",
            "learned": "the learned model with its GP",
        }[fit.flown]
        progress(f"clutter: the proposed planner flies {flies}")
    size = config.forest.size_ne_m
    bounds = (-2.0, size[0] + 2.0, -2.0, size[1] + 2.0)
    flights: dict[str, list[ClutterFlight]] = {k: [] for k in config.planners}
    for i in range(config.n_pairs):
        start, goal = scenario.starts_ne_m[i], scenario.goals_ne_m[i]
        for kind in config.planners:
            rrt = None
            if kind == "rrtstar":
                rrt = plan_rrtstar(
                    scenario.world, start, goal, bounds, iterations=config.rrt_iterations
                )
                if rrt is None:
                    progress(f"clutter: pair {i}: RRT* found no path")
                    continue
            f = fly_pair(
                kind,
                scenario.world,
                start,
                goal,
                seed=i,
                residual_model=model,
                rrt_path_ne_m=rrt,
                bounds_ne_m=bounds,
                rrt_iterations=config.rrt_iterations,
            )
            flights[kind].append(f)
            progress(
                f"clutter: pair {i} {kind}: {'reached' if f.reached else 'FAILED'}, "
                f"{f.distance_m:.1f} m, {f.contacts} contacts, {np.mean(f.cycle_ms):.2f} ms/cycle"
            )
    return Table3Result(scenario, flights, model is not None, gp_flies)


def planner_row(flights: list[ClutterFlight], n_pairs: int) -> dict[str, float]:
    """The paper's columns for one planner (distances over the successful flights; an
    unplanned pair counts as a failure)."""
    ok = [f for f in flights if f.reached]
    dist = np.array([f.distance_m for f in ok]) if ok else np.array([np.nan])
    cycles = np.concatenate([f.cycle_ms for f in flights]) if flights else np.array([np.nan])
    return {
        "success_fraction": len(ok) / n_pairs,
        "mean_cycle_ms": float(np.mean(cycles)),
        "distance_mean_m": float(np.mean(dist)),
        "distance_max_m": float(np.max(dist)),
        "distance_min_m": float(np.min(dist)),
        "contacts": float(sum(f.contacts for f in flights)),
    }


def residual_rmse(flights: list[ClutterFlight]) -> float:
    """Pooled one-step residual RMSE [m/s] of the flights (Table 2's obstacle row)."""
    values = [residual_rmse_mps(f.log) for f in flights]
    return float(np.sqrt(np.mean(np.square(values)))) if values else float("nan")
