"""The study's numbers: per-planner pooled figures and the headline bench figures (pure)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from experiments.study.jobs import FlightSummary
from experiments.study.metrics import pooled_rmse
from experiments.study.paper000 import IDENTIFIED_LAG, NOMINAL, Paper000Result


@dataclass(frozen=True)
class PlannerFigures:
    """One planner's flights pooled.

    Attributes:
        planner: "nominal", an inducing selection or "identified_lag".
        flights, completed: flights flown and how many completed.
        residual_rmse_mps: one-step velocity residual RMSE of the model that flew [m/s].
        tracking_rmse_m: position tracking RMSE [m].
        solve_median_ms, solve_p99_ms: NMPC wall-clock time per plan [ms].
    """

    planner: str
    flights: int
    completed: int
    residual_rmse_mps: float
    tracking_rmse_m: float
    solve_median_ms: float
    solve_p99_ms: float


def planner_figures(planner: str, flights: list[FlightSummary]) -> PlannerFigures:
    """Pool ``flights`` (RMSEs weighted by their row counts)."""
    weights = [f.n_residuals for f in flights]
    times_ms = 1e3 * np.concatenate([f.solve_times_s for f in flights])
    return PlannerFigures(
        planner=planner,
        flights=len(flights),
        completed=sum(f.status == "completed" for f in flights),
        residual_rmse_mps=pooled_rmse([f.residual_rmse_mps for f in flights], weights),
        tracking_rmse_m=pooled_rmse([f.tracking_rmse_m for f in flights], weights),
        solve_median_ms=float(np.median(times_ms)),
        solve_p99_ms=float(np.percentile(times_ms, 99)),
    )


def all_planner_figures(result: Paper000Result) -> dict[str, PlannerFigures]:
    """Figures for every planner flown, in flying order."""
    return {name: planner_figures(name, fl) for name, fl in result.flights.items()}


def headline_figures(result: Paper000Result) -> dict[str, float]:
    """The bench figures: residual RMSE nominal / per selection [m/s], tracking RMSE nominal
    and augmented (the first selection, [Kulathunga23]'s low_speed) [m]; with the identified-lag
    ablation also its residual and tracking RMSE (what the GP adds is the difference) and
    gp_over_structure, the tracking RMSE of the structure alone divided by structure + GP
    (low_speed): > 1 when the GP helps."""
    figs = all_planner_figures(result)
    selections = list(result.fits)
    out = {"residual_rmse_nominal": figs[NOMINAL].residual_rmse_mps}
    out |= {f"residual_rmse_{sel}": figs[sel].residual_rmse_mps for sel in selections}
    out["tracking_rmse_nominal_m"] = figs[NOMINAL].tracking_rmse_m
    out["tracking_rmse_augmented_m"] = figs[selections[0]].tracking_rmse_m
    out |= {f"tracking_rmse_{sel}_m": figs[sel].tracking_rmse_m for sel in selections[1:]}
    if IDENTIFIED_LAG in figs:
        out["residual_rmse_identified_lag"] = figs[IDENTIFIED_LAG].residual_rmse_mps
        out["tracking_rmse_identified_lag_m"] = figs[IDENTIFIED_LAG].tracking_rmse_m
        out["gp_over_structure"] = (
            figs[IDENTIFIED_LAG].tracking_rmse_m / figs[selections[0]].tracking_rmse_m
        )
    return out
