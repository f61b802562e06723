"""Paper 004's view: trial-to-trial learning on one repeated path.

Trial 1 flies the nominal NMPC; after every trial the residual model is refitted on all trials
so far (the augmented ones too, so the model covers where the augmented planner flies) and the
next trial flies augmented with it (a new seed each trial), provided it predicts the held-out
trials better over the NMPC horizon than the model it would replace (gp.prediction_check)
and, with ``closed_loop_check`` (the default), tracks no worse in closed loop on the trial
just flown: it is flown once more on that trial's seed and compared with that trial's flight
(experiments.study.closed_loop; lockstep, so the same gusts: a difference is the model's).
Otherwise the previous model flies again. The check's flight is not a trial and teaches the
model nothing. The tracking error per trial shows whether experience pays off, as in
[Ostafew16], Fig. 10.

Why the closed-loop check: on the default study's path the refit after trial 5 passed the
open-loop check and flew trial 6 at 0.021 m where trials 2-5, all flying the fit after trial
1, flew 0.009-0.014 m (BENCHMARKS.md, session 12).

Why each trial holds out a different quarter for the open-loop check (gp.prediction_check
.split_logs, ``rotate``): cut at their last quarter, as one flight is, all trials of the
repeated path hold out the same last stretch of it, which no fit ever trains on. There the
GP extrapolates (its mean residual 3-8x the true one) and every refit predicted 3-4x worse
over 2 s than the identified lag alone that flew as "fit after trial 1" (whose own GP was
as bad there and so dropped): 0.045 / 0.040 / 0.067 m against 0.015 m after trials 2-4, on
the default study. Rotated, each held-out quarter is a stretch the other trials train on,
so a refit is judged where it has learnt: 0.019 / 0.014 / 0.018 m against 0.015 / 0.015 /
0.019 m (BENCHMARKS.md, session 12).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from experiments.study.closed_loop import compare_tracking
from experiments.study.config import StudyConfig
from experiments.study.fitting import fit_for_study
from experiments.study.jobs import FlightJob, FlightSummary, run_flight_job
from gp.model_io import ResidualModel
from gp.prediction_check import Predictor, refusal, structure_only
from planners.bspline import BSplineReference
from planners.trajectory_generator import TrajectorySpec, generate_trajectories

TRIAL_PATH_SEED_OFFSET = 1000  # the repeated path is not one of [Kulathunga23]'s trajectories
NOMINAL_NAME = "nominal"  # how the trials name the planner without a learned model


@dataclass(frozen=True, eq=False)
class TrialsResult:
    """The repeated path and one flight per trial (trial 1 nominal).

    Attributes:
        models: per trial, the name of the model it flew ("nominal", "fit after trial k", with
            " (its structure alone)" when that fit flies without its GP).
        checks: per trial after the first, one line: why its model flies (the closed-loop
            comparison, or which check refused the newer fit).
    """

    reference: BSplineReference
    selection: str
    trials: list[FlightSummary]
    models: list[str]
    checks: list[str]


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
    model, name = None, NOMINAL_NAME
    models: list[str] = []
    checks: list[str] = []
    for trial in range(1, config.n_trials + 1):
        summary = run_flight_job(_trial_job(config, reference, selection, trial, model))
        trials.append(summary)
        models.append(name)
        progress(
            f"trial {trial}/{config.n_trials} ({name}): tracking "
            f"{summary.tracking_rmse_m:.3f} m, residual {summary.residual_rmse_mps:.4f} m/s"
        )
        if trial == config.n_trials:
            break
        fit = fit_for_study(
            config,
            [t.log for t in trials],
            selection,
            incumbent=None if model is None else Predictor.as_flown(model, name),
            rotate_held_out=True,
        )
        candidate = _as_flown(f"fit after trial {trial}", fit.model)
        if not fit.may_fly:
            check = f"{candidate}: {refusal(fit.model)}; {name} flies again"
        elif not config.closed_loop_check:
            check, model, name = f"{candidate} flies (no closed-loop check)", fit.model, candidate
        else:
            rehearsal = run_flight_job(_trial_job(config, reference, selection, trial, fit.model))
            comparison = compare_tracking(
                candidate, [rehearsal], name, [summary], flown_on=f"trial {trial}'s seed"
            )
            check = comparison.describe()
            if comparison.passed:
                model, name = fit.model, candidate
            else:
                check += f"; {name} flies again"
        checks.append(check)
        progress(f"trial {trial + 1}: {check}")
    return TrialsResult(reference, selection, trials, models, checks)


def _trial_job(
    config: StudyConfig,
    reference: BSplineReference,
    selection: str,
    seed: int,
    model: ResidualModel | None,
) -> FlightJob:
    """One flight of the repeated path on ``seed``: nominal without ``model``, else augmented."""
    planner = NOMINAL_NAME if model is None else selection
    return FlightJob(
        0,
        reference,
        planner,
        seed,
        config.vehicle,
        config.nmpc,
        model,
        compile_functions=model is None,
    )


def _as_flown(name: str, model: ResidualModel) -> str:
    """How the checks name the model ``name`` as it flies: its structure alone when its GP was
    refused (gp.prediction_check.structure_only)."""
    return f"{name} (its structure alone)" if structure_only(model) else name
