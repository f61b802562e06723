"""Paper 004's view: trial-to-trial learning on one repeated path.

Trial 1 flies the nominal NMPC; after every trial the residual model is refitted on all trials
so far (the augmented ones too, so the model covers where the augmented planner flies) and the
next trial flies augmented with it (a new seed each trial), provided it predicts the held-out
trials better over the NMPC horizon than the model it would replace (gp.prediction_check);
otherwise the previous model flies again. The tracking error
per trial shows whether experience pays off, as in [Ostafew16], Fig. 10.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from experiments.study.config import StudyConfig
from experiments.study.fitting import fit_residual
from experiments.study.jobs import FlightJob, FlightSummary, run_flight_job
from gp.prediction_check import Predictor, refusal
from planners.bspline import BSplineReference
from planners.trajectory_generator import TrajectorySpec, generate_trajectories

TRIAL_PATH_SEED_OFFSET = 1000  # the repeated path is not one of [Kulathunga23]'s trajectories


@dataclass(frozen=True, eq=False)
class TrialsResult:
    """The repeated path and one flight per trial (trial 1 nominal)."""

    reference: BSplineReference
    selection: str
    trials: list[FlightSummary]


def run_trials(config: StudyConfig, progress: Callable[[str], None]) -> TrialsResult:
    """Fly ``config.n_trials`` trials in this process (each refit needs the previous trial)."""
    spec = TrajectorySpec(
        length_range_m=config.length_range_m,
        max_speed_mps=config.max_speed_mps,
        max_acc_mps2=config.max_acc_mps2,
        ramp_jerk_mps3=config.ramp_jerk_mps3,
    )
    seed = config.trajectory_seed + TRIAL_PATH_SEED_OFFSET
    reference = generate_trajectories(1, seed, spec)[0]
    selection = config.selections[0]
    trials: list[FlightSummary] = []
    model = None
    for trial in range(1, config.n_trials + 1):
        planner = "nominal" if model is None else selection
        job = FlightJob(
            0,
            reference,
            planner,
            trial,
            config.vehicle,
            config.nmpc,
            model,
            compile_functions=model is None,
        )
        summary = run_flight_job(job)
        trials.append(summary)
        progress(
            f"trial {trial}/{config.n_trials} ({planner}): tracking "
            f"{summary.tracking_rmse_m:.3f} m, residual {summary.residual_rmse_mps:.4f} m/s"
        )
        if trial < config.n_trials:
            fit = fit_residual(
                [t.log for t in trials],
                selection,
                config.nmpc.period_s,
                learned_model=config.learned_model,
                features=config.features,
                m=config.m,
                restarts=config.gp_restarts,
                incumbent=None if model is None else Predictor.as_flown(model),
            )
            if fit.may_fly:
                model = fit.model
            else:
                progress(f"trial {trial + 1}: {refusal(fit.model)}; keeping the previous model")
    return TrialsResult(reference, selection, trials)
