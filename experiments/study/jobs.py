"""Work items the study hands to worker processes (top-level functions: picklable).

Each job builds everything it needs from plain data (trajectory spec, seeds, a fitted model),
so workers share nothing and results do not depend on which worker ran what.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from experiments.study.flights import FlightSpec, fly
from experiments.study.metrics import residual_rmse_mps, residuals_mps, tracking_rmse_m
from flightlog.schema import FlightLog
from gp.model_io import ResidualModel
from planners.bspline import BSplineReference


@dataclass(frozen=True)
class FlightJob:
    """One flight to fly: ``planner`` is "nominal" or an inducing selection's name.

    ``compile_functions``: compile the NMPC's symbolic linearisation to C (cached on disk);
    the default linearisation (compiled per shape, or NumPy) ignores it.
    """

    trajectory: int
    reference: BSplineReference
    planner: str
    seed: int
    vehicle: str
    settings: NmpcSettings
    model: ResidualModel | None = None
    compile_functions: bool = True


@dataclass(frozen=True, eq=False)
class FlightSummary:
    """A flown job's figures and log.

    Attributes:
        trajectory, planner, seed: as in the job.
        status: mission outcome ("completed", ...).
        residual_rmse_mps: RMSE of the one-step velocity residual of the model that flew.
        tracking_rmse_m: position tracking RMSE [m].
        n_residuals: residual rows (weights for pooling).
        solve_times_s: (n,) planner wall-clock times [s].
        log: the flight log.
        flown_as: the planner whose flight this is when another planner flew the same
            (flown once for both, experiments.study.same_flights; its solve times are that
            flight's), else None.
    """

    trajectory: int
    planner: str
    seed: int
    status: str
    residual_rmse_mps: float
    tracking_rmse_m: float
    n_residuals: int
    solve_times_s: np.ndarray
    log: FlightLog
    flown_as: str | None = None


def flight_name(job: FlightJob) -> str:
    """The flight's name in its log ("traj03_low_speed_s4")."""
    return f"traj{job.trajectory:02d}_{job.planner}_s{job.seed}"


def run_flight_job(job: FlightJob) -> FlightSummary:
    """Fly one job in this process and summarise it."""
    spec = FlightSpec(flight_name(job), job.reference, job.vehicle, job.seed)
    settings = replace(job.settings, compile_functions=job.compile_functions)
    record = fly(spec, settings, job.model)
    return FlightSummary(
        trajectory=job.trajectory,
        planner=job.planner,
        seed=job.seed,
        status=record.outcome.status,
        residual_rmse_mps=residual_rmse_mps(record.log),
        tracking_rmse_m=tracking_rmse_m(record.log),
        n_residuals=int(residuals_mps(record.log).shape[0]),
        solve_times_s=record.solve_times_s,
        log=record.log,
    )


def warm_up_planner(settings: NmpcSettings, model: ResidualModel | None) -> None:
    """Build the planner for ``model`` (which plans once), so that its compiled linearisation
    is in the on-disk cache before several processes fly with it."""
    CompanionNmpc(settings, model)
