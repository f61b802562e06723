"""Paper 000's experiment: random trajectories flown nominal, the residual learned offline,
then flown augmented, per inducing-point selection at equal m.

Nominal flights use seeds 0..R-1 per trajectory, augmented flights seeds R..2R-1: the
augmented flights are held out from the model's training data (and fly other gusts).

With the default learned model (first_order_lag, time constants identified from the nominal
flights, then the GP), an ablation flies the identified lag alone (no GP) on the augmented
seeds too, so the report separates what the identified structure and the GP each bring.
With ``closed_loop_check`` (the default), the model that would fly is first flown on the
training seeds and refused if it tracks worse there than the model it replaces
(experiments.study.closed_loop).
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass, replace

from companion.nmpc_planner import NmpcSettings
from experiments.study.closed_loop import confirm_lineage
from experiments.study.config import StudyConfig
from experiments.study.fitting import FOLLOWING_MODES, fit_for_study, regular_rows
from experiments.study.jobs import FlightJob, FlightSummary, warm_up_planner
from experiments.study.same_flights import FlownFlights, fly_once
from flightlog.schema import FlightLog
from gp.lag_identification import identify_velocity_lag
from gp.prediction_check import Predictor, refusal, structure_only
from gp.training import TrainingResult
from planners.bspline import BSplineReference
from planners.nominal_models import make_model
from planners.trajectory_generator import TrajectorySpec, generate_trajectories

NOMINAL = "nominal"
IDENTIFIED_LAG = "identified_lag"  # the learned model's structure alone (the ablation)
LAG_BESIDE = "lag_structure"  # the identified lag alone, beside another learned structure


def planner_label(planner: str, structure_model: str | None) -> str:
    """How the report and progress lines name ``planner``: the structure-alone arm, keyed
    IDENTIFIED_LAG in the figures whatever the structure, as "structure alone (MODEL)"
    (``structure_model``: the nominal model it flies, e.g. first_order_lag or
    px4_velocity_pi); every other planner by its key."""
    return f"structure alone ({structure_model})" if planner == IDENTIFIED_LAG else planner


@dataclass(eq=False)
class Learned:
    """One model a selection learned, and its flights on the training seeds once flown."""

    name: str
    fit: TrainingResult
    flights: list[FlightSummary] | None = None


@dataclass(frozen=True, eq=False)
class Paper000Result:
    """Flights per planner ("nominal", each selection, "identified_lag" if flown) and the
    fitted models; ``structure_model`` is the nominal model the structure-alone arm
    ("identified_lag") flew (first_order_lag, px4_velocity_pi), None when it did not fly."""

    references: list[BSplineReference]
    flights: dict[str, list[FlightSummary]]
    fits: dict[str, TrainingResult]
    structure_model: str | None = None


def study_trajectories(config: StudyConfig) -> list[BSplineReference]:
    """The seeded random trajectories of the experiment."""
    spec = TrajectorySpec(
        length_range_m=config.length_range_m,
        max_speed_mps=config.max_speed_mps,
        max_acc_mps2=config.max_acc_mps2,
        ramp_jerk_mps3=config.ramp_jerk_mps3,
    )
    return generate_trajectories(config.n_trajectories, config.trajectory_seed, spec)


def run_paper000(
    config: StudyConfig, pool: Executor, progress: Callable[[str], None]
) -> Paper000Result:
    """Fly, fit and fly again; flights run on ``pool``, fits one per selection on it too.
    Each distinct flight flies once (experiments.study.same_flights)."""
    refs = study_trajectories(config)
    distinct: FlownFlights = {}
    jobs = [
        FlightJob(i, ref, NOMINAL, seed, config.vehicle, config.nmpc)
        for i, ref in enumerate(refs)
        for seed in range(config.repeats)
    ]
    flights = {NOMINAL: _fly_all(jobs, pool, distinct, "nominal", progress)}
    logs = [f.log for f in flights[NOMINAL]]
    progress(f"fitting {len(config.selections)} residual models on {len(logs)} nominal flights")
    fits = _fit_selections(logs, config, pool)
    structure = fits[config.selections[0]].model.features.nominal_params
    identification = fits[config.selections[0]].model.training.get("identified_lag")
    structure_flights: list[FlightSummary] = []
    if config.learn_from_structure:
        fits, structure_flights = _refit_on_structure(
            config, refs, logs, fits, pool, distinct, progress, structure
        )
    lineage = {sel: [Learned(f"{sel} first fit", fit)] for sel, fit in fits.items()}
    augmented_logs: dict[str, list[FlightLog]] = {sel: [] for sel in config.selections}
    for round_ in range(1, config.refit_rounds + 1):
        fits, flown = _refit_on_augmented(
            config, refs, logs, augmented_logs, fits, pool, distinct, round_, progress, structure
        )
        for sel, summaries in flown.items():
            latest = lineage[sel][-1]
            latest.flights = latest.flights or summaries  # a kept model flies the same again
            if fits[sel] is not latest.fit:
                lineage[sel].append(Learned(f"{sel} round {round_} refit", fits[sel]))
    if config.closed_loop_check:
        fits = _confirm_in_closed_loop(
            config, refs, lineage, structure_flights, pool, distinct, progress
        )
    if identification is not None:  # the later rounds keep the structure: say where it came from
        fits = {sel: _with_identification(fit, identification) for sel, fit in fits.items()}
    for sel, fit in fits.items():
        nom, aug = fit.metrics["nominal_rmse_mps"], fit.metrics["augmented_rmse_mps"]
        progress(f"fit {sel}: held-out rows nominal {_fmt(nom)} -> augmented {_fmt(aug)} m/s")
        for check in (fit.check, fit.structure_check):
            if check is not None:
                progress(f"fit {sel}: {check.describe()}")
        progress(f"fit {sel}: {what_flies(fit)}")
    flying = {sel: fit.model if fit.may_fly else None for sel, fit in fits.items()}
    if config.compile_augmented:
        progress("compiling the augmented planners (once per model, cached on disk)")
        models = [m for m in flying.values() if m is not None]
        list(pool.map(warm_up_planner, [config.nmpc] * len(models), models))
    aug_jobs = [
        FlightJob(
            i,
            ref,
            sel,
            config.repeats + seed,
            config.vehicle,
            config.nmpc,
            flying[sel],
            config.compile_augmented,
        )
        for sel in config.selections
        for i, ref in enumerate(refs)
        for seed in range(config.repeats)
    ]
    lag = identified_lag_settings(config, fits[config.selections[0]])
    if lag is not None:
        aug_jobs += [
            FlightJob(
                i,
                ref,
                IDENTIFIED_LAG,
                config.repeats + seed,
                config.vehicle,
                lag,
                compile_functions=False,
            )
            for i, ref in enumerate(refs)
            for seed in range(config.repeats)
        ]
    if lag is not None and lag.nominal_model != "first_order_lag":
        beside = _identified_lag_beside(config, logs, progress)
        aug_jobs += [
            FlightJob(
                i,
                ref,
                LAG_BESIDE,
                config.repeats + seed,
                config.vehicle,
                beside,
                compile_functions=False,
            )  # fmt: skip
            for i, ref in enumerate(refs)
            for seed in range(config.repeats)
        ]
    for summary in _fly_all(aug_jobs, pool, distinct, "augmented", progress):
        flights.setdefault(summary.planner, []).append(summary)
    return Paper000Result(refs, flights, fits, None if lag is None else lag.nominal_model)


def what_flies(fit: TrainingResult) -> str:
    """One line: what a selection's held-out flights fly with ``fit`` and why: the nominal
    planner (the learned model refused), its structure alone (the GP did not beat it over
    the horizon, or the closed-loop check chose it) or the learned model."""
    flown = fit.flown
    if flown == "nominal":
        return f"{refusal(fit.model)}; its flights fly the nominal planner"
    if flown == "structure" and not fit.gp_earns_its_place:
        return "the GP does not beat its structure; the structure flies alone"
    if flown == "structure":
        return "the structure flies alone (closed-loop check)"
    return f"the learned model flies ({fit.model.features.nominal_model} + GP)"


def _refit_on_augmented(
    config: StudyConfig,
    refs: list[BSplineReference],
    nominal_logs: list[FlightLog],
    augmented_logs: dict[str, list[FlightLog]],
    fits: dict[str, TrainingResult],
    pool: Executor,
    distinct: FlownFlights,
    round_: int,
    progress: Callable[[str], None],
    structure: tuple[tuple[str, float], ...],
) -> tuple[dict[str, TrainingResult], dict[str, list[FlightSummary]]]:
    """One round of [Ostafew16]'s trial-after-trial learning: fly each selection's model on
    the nominal seeds (0..repeats-1; the comparison's seeds stay held out) and refit its GP on
    the nominal flights plus its augmented flights of every round so far (``augmented_logs``,
    extended here), on the ``structure`` (nominal parameters) identified from the nominal
    flights. A refit that does not predict the held-out logs better than the model it
    replaces is dropped (the old fit stays). Returns the fits and, per selection, the flights
    of the model it flew in this round."""
    jobs = [
        FlightJob(i, ref, sel, seed, config.vehicle, config.nmpc, fit.model, False)
        for sel, fit in fits.items()
        if fit.may_fly
        for i, ref in enumerate(refs)
        for seed in range(config.repeats)
    ]
    flown: dict[str, list[FlightSummary]] = {}
    for summary in _fly_all(jobs, pool, distinct, f"refit round {round_}", progress):
        flown.setdefault(summary.planner, []).append(summary)
    futures = {
        sel: pool.submit(
            fit_for_study,
            config,
            [*nominal_logs, *augmented_logs[sel], *(s.log for s in flown[sel])],
            sel,
            incumbent=Predictor.as_flown(fits[sel].model, f"the {sel} fit it would replace"),
            structure_params=structure,
        )
        for sel in flown
    }
    out = dict(fits)
    for sel, fut in futures.items():
        augmented_logs[sel].extend(s.log for s in flown[sel])
        refit = fut.result()
        if refit.may_fly:
            out[sel] = refit
            progress(f"refit {sel} round {round_}: {refit.check.describe()}")
        else:
            progress(f"refit {sel} round {round_}: {refusal(refit.model)}; keeping the previous")
    return out, flown


def _refit_on_structure(
    config: StudyConfig,
    refs: list[BSplineReference],
    nominal_logs: list[FlightLog],
    fits: dict[str, TrainingResult],
    pool: Executor,
    distinct: FlownFlights,
    progress: Callable[[str], None],
    structure: tuple[tuple[str, float], ...],
) -> tuple[dict[str, TrainingResult], list[FlightSummary]]:
    """[Ostafew16]'s trial after trial with the structure as the first learned model: fly the
    identified lag alone on the nominal flights' seeds (the comparison's seeds stay held
    out) and fit every selection's GP on the nominal flights and those flights together, so
    it learns what the structure leaves where a planner on the structure flies as well as
    where the nominal planner flew (agile, held-out seeds, m = 60: 1.28x over the lag alone
    from both, against 1.10x from the structure's flights only). The
    lag stays the one identified from the nominal flights (``structure``): identified anew
    from the lag's own flights its time constants came out longer (agile: 0.77 s, vertical
    0.65 s, against 0.72 s and 0.36 s) and flew worse alone (0.057 m against 0.044 m on the
    held-out seeds), so the GP was partly repairing its own structure. The fit is checked as
    any other (gp.prediction_check). Returns the fits and the structure's flights."""
    lag = identified_lag_settings(config, fits[config.selections[0]])
    if lag is None:
        return fits, []
    jobs = _structure_jobs(config, refs, lag)
    flights = _fly_all(jobs, pool, distinct, "structure round", progress)
    logs = [s.log for s in flights]
    return _fit_selections([*nominal_logs, *logs], config, pool, structure), flights


def _confirm_in_closed_loop(
    config: StudyConfig,
    refs: list[BSplineReference],
    lineage: dict[str, list[Learned]],
    structure_flights: list[FlightSummary],
    pool: Executor,
    distinct: FlownFlights,
    progress: Callable[[str], None],
) -> dict[str, TrainingResult]:
    """experiments.study.closed_loop's check on the training seeds: fly what has not flown
    there yet (each selection's newest model, and the structure alone unless the structure
    round flew it), keep per selection the newest model no worse than its predecessor and
    the structure alone, and record the verdict in its model file (``closed_loop_check``; a
    verdict for the structure alone makes the companion fly the structure without the GP)."""
    checked = {}
    for sel, models in lineage.items():
        fit = models[-1].fit
        if not fit.may_fly:
            progress(f"closed-loop check {sel}: none, {models[-1].name} was refused open loop")
        elif structure_only(fit.model):
            progress(f"closed-loop check {sel}: none, {models[-1].name} flies the structure alone")
        else:
            checked[sel] = models
    lag = identified_lag_settings(config, next(iter(lineage.values()))[0].fit)
    if checked and lag is None:
        progress(
            f"closed-loop check: none, {config.learned_model} has no identified structure to "
            "fly alone against"
        )
    if not checked or lag is None:
        return {sel: models[-1].fit for sel, models in lineage.items()}
    jobs = [] if structure_flights else _structure_jobs(config, refs, lag)
    jobs += [
        FlightJob(i, ref, sel, seed, config.vehicle, config.nmpc, models[-1].fit.model, False)
        for sel, models in checked.items()
        if models[-1].flights is None
        for i, ref in enumerate(refs)
        for seed in range(config.repeats)
    ]
    flown: dict[str, list[FlightSummary]] = {}
    for summary in _fly_all(jobs, pool, distinct, "closed-loop check", progress):
        flown.setdefault(summary.planner, []).append(summary)
    structure_flights = structure_flights or flown[IDENTIFIED_LAG]
    out = {sel: models[-1].fit for sel, models in lineage.items()}
    for sel, models in checked.items():
        models[-1].flights = models[-1].flights or flown[sel]
        verdict = confirm_lineage([(m.name, m.flights) for m in models], structure_flights)
        for comparison in verdict.comparisons:
            progress(f"closed-loop check {sel}: {comparison.describe()}")
        for line in verdict.refusals():
            progress(f"closed-loop check {sel}: {line}")
        progress(f"closed-loop check {sel}: {verdict.flies_name} flies")
        fit = models[-1 if verdict.flies is None else verdict.flies].fit
        training = {**fit.model.training, "closed_loop_check": verdict.to_dict()}
        out[sel] = replace(fit, model=replace(fit.model, training=training))
    return out


def _structure_jobs(
    config: StudyConfig, refs: list[BSplineReference], lag: NmpcSettings
) -> list[FlightJob]:
    """The identified lag alone on every trajectory and training seed."""
    return [
        FlightJob(i, ref, IDENTIFIED_LAG, seed, config.vehicle, lag, compile_functions=False)
        for i, ref in enumerate(refs)
        for seed in range(config.repeats)
    ]


def _fit_selections(
    logs: list[FlightLog],
    config: StudyConfig,
    pool: Executor,
    structure: tuple[tuple[str, float], ...] = (),
) -> dict[str, TrainingResult]:
    """One residual model per inducing-point selection of ``config``, fitted on ``logs`` in
    ``pool`` (on the nominal parameters ``structure``, or with them identified from ``logs``
    when empty): selection -> fit."""
    futures = {
        sel: pool.submit(
            fit_for_study,
            config,
            logs,
            sel,
            structure_params=structure,
        )
        for sel in config.selections
    }
    return {sel: fut.result() for sel, fut in futures.items()}


def _with_identification(fit: TrainingResult, record: object) -> TrainingResult:
    """``fit`` with ``record`` (the lag identification of the nominal flights) as its
    ``identified_lag``, unless its own fit identified one."""
    if "identified_lag" in fit.model.training:
        return fit
    training = {**fit.model.training, "identified_lag": record}
    return replace(fit, model=replace(fit.model, training=training))


def identified_lag_settings(config: StudyConfig, fit: TrainingResult) -> NmpcSettings | None:
    """The nominal NMPC on the fit's identified first_order_lag (no GP), or None when the
    learned model is not an identified lag."""
    features = fit.model.features
    if not make_model(features.nominal_model).carries_velocity:
        return None
    return replace(
        config.nmpc, nominal_model=features.nominal_model, nominal_params=features.nominal_params
    )


def _identified_lag_beside(
    config: StudyConfig, logs: list[FlightLog], progress: Callable[[str], None]
) -> NmpcSettings:
    """The nominal NMPC on first_order_lag with its time constants identified from the
    nominal flights ``logs`` (as the default learned model's structure is), flown beside a
    learned model on another structure so the report compares the two structures."""
    regular = [regular_rows(log, config.nmpc.period_s) for log in logs]
    identified = identify_velocity_lag(regular, FOLLOWING_MODES)
    progress(f"{LAG_BESIDE}: identified {identified.describe()}")
    params = tuple(sorted(identified.nominal_params().items()))
    return replace(config.nmpc, nominal_model="first_order_lag", nominal_params=params)


def _fly_all(
    jobs: list[FlightJob],
    pool: Executor,
    distinct: FlownFlights,
    what: str,
    progress: Callable[[str], None],
) -> list[FlightSummary]:
    """Fly ``jobs`` (each distinct flight once over ``distinct``, same_flights.fly_once), one
    progress line per job and one saying how many flights were reused and from whom."""
    out = []
    reused: dict[str, list[str]] = {}  # the planner that flew -> the planners reusing it
    flights = zip(jobs, fly_once(jobs, pool, distinct), strict=True)
    for n, (job, (summary, flyer)) in enumerate(flights, start=1):
        planner = planner_label(summary.planner, job.settings.nominal_model)
        same = ""
        if summary.flown_as is not None:
            source = planner_label(flyer.planner, flyer.settings.nominal_model)
            reused.setdefault(source, []).append(planner)
            same = f" (reused: same planner as {source})"
        progress(
            f"{what} flight {n}/{len(jobs)}: trajectory {summary.trajectory} {planner} "
            f"seed {summary.seed}: {summary.status}, tracking {summary.tracking_rmse_m:.3f} m, "
            f"residual {summary.residual_rmse_mps:.4f} m/s{same}"
        )
        out.append(summary)
    if reused:
        sources = "; ".join(f"{s} for {', '.join(dict.fromkeys(p))}" for s, p in reused.items())
        n_reused = sum(len(p) for p in reused.values())
        progress(f"{what}: {n_reused} of {len(jobs)} flights reused: same planner as {sources}")
    return out


def _fmt(values: list[float]) -> str:
    return "/".join(f"{v:.4f}" for v in values)
