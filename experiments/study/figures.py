"""The study's numbers: per-planner pooled figures and the headline bench figures (pure)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from experiments.study.jobs import FlightSummary
from experiments.study.metrics import pooled_rmse, settled_tracking_rmse_m
from experiments.study.paper000 import IDENTIFIED_LAG, LAG_BESIDE, NOMINAL, Paper000Result


@dataclass(frozen=True)
class PlannerFigures:
    """One planner's flights pooled.

    Attributes:
        planner: "nominal", an inducing selection or "identified_lag".
        flights, completed: flights flown and how many completed.
        residual_rmse_mps: one-step velocity residual RMSE of the model that flew [m/s].
        tracking_rmse_m: position tracking RMSE [m].
        tracking_settled_rmse_m: the same after the first SETTLE_S s of following [m]
            (experiments.study.metrics.settled_tracking_rmse_m).
        solve_median_ms, solve_p99_ms: NMPC wall-clock time per plan [ms].
    """

    planner: str
    flights: int
    completed: int
    residual_rmse_mps: float
    tracking_rmse_m: float
    tracking_settled_rmse_m: float
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
        tracking_settled_rmse_m=settled_tracking_rmse(flights),
        solve_median_ms=float(np.median(times_ms)),
        solve_p99_ms=float(np.percentile(times_ms, 99)),
    )


def all_planner_figures(result: Paper000Result) -> dict[str, PlannerFigures]:
    """Figures for every planner flown, in flying order."""
    return {name: planner_figures(name, fl) for name, fl in result.flights.items()}


def settled_tracking_rmse(flights: list[FlightSummary]) -> float:
    """Tracking RMSE [m] pooled over ``flights`` after their first SETTLE_S s of following
    (each weighted by its following rows)."""
    values = [settled_tracking_rmse_m(f.log) for f in flights]
    return pooled_rmse(values, [f.n_residuals for f in flights])


def headline_figures(result: Paper000Result) -> dict[str, float]:
    """The bench figures: residual RMSE nominal / per selection [m/s], tracking RMSE nominal
    and augmented (the first selection, [Kulathunga23]'s low_speed) [m]; with the ablation
    flying the learned model's structure alone (keyed identified_lag whatever that structure
    is, Paper000Result.structure_model) also its residual and tracking RMSE (what the GP adds
    is the difference) and gp_over_structure, the tracking RMSE of the structure alone
    divided by structure + GP (low_speed): > 1 when the GP helps; the same after the first
    SETTLE_S s of following (tracking_settled_<planner>_m, gp_over_structure_settled: without
    the first transient from the start hover, the same for every planner); when the learned
    model's structure is not the lag, the identified lag alone flies beside it
    (tracking_rmse_lag_structure_m) and gp_over_lag_structure is its tracking RMSE divided by
    structure + GP's."""
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
        settled = {
            p: figs[p].tracking_settled_rmse_m for p in (NOMINAL, IDENTIFIED_LAG, *selections)
        }
        out |= {f"tracking_settled_{p}_m": v for p, v in settled.items()}
        out["gp_over_structure_settled"] = settled[IDENTIFIED_LAG] / settled[selections[0]]
    if LAG_BESIDE in figs:  # another structure learned on: what it gains over the lag alone
        out["tracking_rmse_lag_structure_m"] = figs[LAG_BESIDE].tracking_rmse_m
        out["gp_over_lag_structure"] = (
            figs[LAG_BESIDE].tracking_rmse_m / figs[selections[0]].tracking_rmse_m
        )
    return out
