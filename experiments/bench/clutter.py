"""Clutter benchmark (`bench --only clutter`): [Kulathunga23] Table 3 in a seeded forest.

Ten seeded start/goal pairs in one seeded 60 m x 60 m forest (two with ``quick``), flown
closed loop in process by the proposed planner, the same without its GP (nominal) and
without regeneration (gp_no_regeneration), the paper's NMPC replanner (no GP, no
regeneration), OMPL's RRT* and the PD regulator (experiments/clutter).
Figures:
    clutter_success_fraction         proposed: goal reached without contact / pairs [-]
    clutter_mean_cycle_ms            proposed: mean computation time per planning cycle [ms]
                                     (map + replanner + NMPC with the learned model)
    clutter_distance_mean_m          proposed: mean travelled distance, successful flights [m]
    clutter_rrtstar_distance_mean_m  RRT* (OMPL) in the known forest, its path tracked by the
                                     NMPC: the same [m]
    clutter_contacts                 proposed: contacts summed over every flight [count]
    clutter_learned_model_flown      1 when the proposed planner flies the learned model (0: its
                                     check against nominal refused it, nominal flies)
    clutter_gp_flown                 1 when that model's GP flies too (0: it did not beat the
                                     identified lag alone, which flies without it)
and, for the table in BENCHMARKS.md, the paper's own RRT* row (``rrtstar_online``: re-planned
in the sensed map), the other planners' rows and the residual RMSE with
obstacles. The forest with every flown path goes to out/bench/clutter_forest.png.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from experiments.clutter.plot import plot_forest
from experiments.clutter.table3 import Table3Config, planner_row, residual_rmse, run_table3

PLOT_PATH = Path("out/bench/clutter_forest.png")


def run(
    progress: Callable[[str], None] = print,
    quick: bool = False,
    config: Table3Config | None = None,
    plot_path: Path | None = PLOT_PATH,
) -> dict[str, float]:
    config = config or Table3Config()
    if quick:
        config = replace(config, n_pairs=2, rrt_iterations=3000)
    result = run_table3(config, progress)
    figures: dict[str, float] = {}
    rows = {k: planner_row(v, config.n_pairs) for k, v in result.flights.items()}
    if "proposed" in rows:
        p = rows["proposed"]
        figures |= {
            "clutter_success_fraction": p["success_fraction"],
            "clutter_mean_cycle_ms": p["mean_cycle_ms"],
            "clutter_distance_mean_m": p["distance_mean_m"],
            "clutter_contacts": p["contacts"],
            "clutter_distance_max_m": p["distance_max_m"],
            "clutter_distance_min_m": p["distance_min_m"],
            "clutter_residual_rmse_mps": residual_rmse(result.flights["proposed"]),
            "clutter_learned_model_flown": float(result.learned_flown),
            "clutter_gp_flown": float(result.gp_flown),
        }
    if "rrtstar" in rows:
        figures["clutter_rrtstar_distance_mean_m"] = rows["rrtstar"]["distance_mean_m"]
        figures["clutter_rrtstar_success_fraction"] = rows["rrtstar"]["success_fraction"]
    if "rrtstar_online" in rows:
        figures["clutter_rrtstar_online_mean_cycle_ms"] = rows["rrtstar_online"]["mean_cycle_ms"]
    for kind in ("rrtstar_online", "nominal", "gp_no_regeneration", "no_regeneration", "pd"):
        if kind in rows:
            figures[f"clutter_{kind}_success_fraction"] = rows[kind]["success_fraction"]
            figures[f"clutter_{kind}_distance_mean_m"] = rows[kind]["distance_mean_m"]
            figures[f"clutter_{kind}_contacts"] = rows[kind]["contacts"]
    if plot_path is not None:
        progress(f"clutter: forest and paths in {plot_forest(result, plot_path)}")
    return figures
