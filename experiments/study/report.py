"""The study's Markdown report (pure: returns text)."""

from __future__ import annotations

from experiments.study.config import StudyConfig
from experiments.study.figures import PlannerFigures
from experiments.study.metrics import SETTLE_S
from experiments.study.paper000 import (
    IDENTIFIED_LAG,
    LAG_BESIDE,
    NOMINAL,
    Paper000Result,
    planner_label,
    what_flies,
)
from experiments.study.paper004 import TrialsResult


def figures_table(figs: dict[str, PlannerFigures], structure_model: str | None) -> str:
    """One row per planner: residual, tracking, solve times, completed flights; the
    structure-alone arm named by the model it flew (``structure_model``, planner_label)."""
    nominal = figs[NOMINAL]
    lines = [
        "| planner | flights (completed) | residual RMSE [m/s] | gain | tracking RMSE [m] | gain "
        f"| tracking after {SETTLE_S:g} s [m] | solve median [ms] | solve p99 [ms] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for f in figs.values():
        lines.append(
            f"| {planner_label(f.planner, structure_model)} | {f.flights} ({f.completed}) "
            f"| {f.residual_rmse_mps:.4f} "
            f"| {nominal.residual_rmse_mps / f.residual_rmse_mps:.2f}x | {f.tracking_rmse_m:.4f} "
            f"| {nominal.tracking_rmse_m / f.tracking_rmse_m:.2f}x "
            f"| {f.tracking_settled_rmse_m:.4f} | {f.solve_median_ms:.2f} "
            f"| {f.solve_p99_ms:.2f} |"
        )
    return "\n".join(lines)


def render_report(
    config: StudyConfig,
    result: Paper000Result,
    figs: dict[str, PlannerFigures],
    trials: TrialsResult | None,
    images: dict[str, list[str]],
    elapsed_s: float,
) -> str:
    """report.md text; ``images`` maps a section ("paths", "residuals", "trials") to PNG names;
    ``trials`` None: the trial-to-trial view was not flown (n_trials 0)."""
    nmpc = config.nmpc
    model = nmpc.nominal_model + "".join(f", {k}={v:g}" for k, v in nmpc.nominal_params)
    lines = [
        "# Residual-learning study",
        "",
        f"Regime `{config.regime}` (see experiments/study/regimes.py). "
        f"Vehicle `{config.vehicle}`; NMPC on `{model}` (N={nmpc.horizon_steps}, "
        f"dt={nmpc.dt_s:g} s, loop {1 / nmpc.period_s:g} Hz, command limit "
        f"{nmpc.speed_limit_mps:g} m/s). Learned model: `{config.learned_model}` "
        f"{_identified(result)}plus a sparse GP on features `{config.features}`, m={config.m} "
        f"per output. Lockstep in process, {_where(config)}, {elapsed_s:.0f} s.",
        "",
        "## Paper 000: random trajectories, nominal vs augmented",
        "",
        f"{config.n_trajectories} trajectories ({config.length_range_m[0]:g}-"
        f"{config.length_range_m[1]:g} m, {config.max_speed_mps:g} m/s"
        + (
            f", jerk-limited start and end at {config.ramp_jerk_mps3:g} m/s^3"
            if config.ramp_jerk_mps3 is not None
            else ""
        )
        + f"), each flown "
        f"{config.repeats}x nominal (seeds 0-{config.repeats - 1}); one residual model per "
        "inducing selection fitted on all nominal flights; each trajectory flown "
        f"{config.repeats}x augmented per selection on other seeds (held-out flights)"
        + (
            f"; the row {planner_label(IDENTIFIED_LAG, result.structure_model)} flies the "
            f"learned model's structure (`{result.structure_model}`) without the GP on the same "
            f"seeds (what the GP adds is the difference; its figures are named `{IDENTIFIED_LAG}`)."
            if IDENTIFIED_LAG in figs
            else "."
        )
        + (
            f" `{LAG_BESIDE}` flies first_order_lag alone, its time constants identified from "
            "the nominal flights, on the same seeds (the default learned model's structure)."
            if LAG_BESIDE in figs
            else ""
        ),
        "",
        "Residual: one-step velocity error of the model that flew, "
        "v_meas(t+dt) - pred_vel(t), RMSE over the three axes; tracking: distance to the "
        "reference position; both over the OFFBOARD (following) rows, pooled over flights.",
        "",
        figures_table(figs, result.structure_model),
        "",
        *_same_planner_lines(result),
        *_flown_lines(result),
        "Held-out rows of each fit (fit-gp's evaluation, per axis n/e/d, m/s):",
        "",
    ]
    for sel, fit in result.fits.items():
        nom = ", ".join(f"{v:.4f}" for v in fit.metrics["nominal_rmse_mps"])
        aug = ", ".join(f"{v:.4f}" for v in fit.metrics["augmented_rmse_mps"])
        lines.append(f"- `{sel}`: nominal [{nom}] -> augmented [{aug}]")
    lines += _closed_loop_lines(result)
    lines += ["", *[f"![{p}]({p})" for p in images["paths"]], ""]
    lines += ["Residual vs velocity (held-out rows), GP mean and inducing points:", ""]
    lines += [f"![{p}]({p})" for p in images["residuals"]]
    lines += ["", "## Paper 004: trial after trial on one path", "", *_trials_lines(trials, images)]
    return "\n".join(lines)


def _trials_lines(trials: TrialsResult | None, images: dict[str, list[str]]) -> list[str]:
    """The paper 004 section's body: the trials table, why each model flew, the plot."""
    if trials is None:
        return ["Not flown (`--trials 0`): this report has no trial-to-trial view.", ""]
    lines = [
        f"Trial 1 nominal; after each trial the `{trials.selection}` model is refitted on all "
        "trials so far and flies the next trial (a new seed each time) if it passes the "
        "checks (before each trial: why its model flies).",
        "",
        "| trial | model | tracking RMSE [m] | residual RMSE [m/s] |",
        "|---|---|---|---|",
    ]
    for k, (t, model) in enumerate(zip(trials.trials, trials.models, strict=True), start=1):
        lines.append(f"| {k} | {model} | {t.tracking_rmse_m:.4f} | {t.residual_rmse_mps:.4f} |")
    lines += ["", *[f"- before trial {k}: {c}" for k, c in enumerate(trials.checks, start=2)]]
    return [*lines, "", *[f"![{p}]({p})" for p in images["trials"]], ""]


def _same_planner_lines(result: Paper000Result) -> list[str]:
    """A line per row with flights another row's planner flew: the same planner on the same
    trajectory and seed, flown once for both (experiments.study.same_flights), so both rows
    show that flight's solve times."""
    lines = []
    for planner, flights in result.flights.items():
        reused = [f.flown_as for f in flights if f.flown_as is not None]
        if reused:
            names = " and ".join(
                f"`{planner_label(p, result.structure_model)}`" for p in dict.fromkeys(reused)
            )
            lines.append(
                f"- `{planner_label(planner, result.structure_model)}` flies the same planner "
                f"as {names} ({len(reused)} of its {len(flights)} flights, the same trajectories "
                "and seeds): each such flight was flown once, its solve times are in both rows."
            )
    return [*lines, ""] if lines else []


def _flown_lines(result: Paper000Result) -> list[str]:
    """Per selection, what its rows above flew and why: the open-loop checks' verdicts
    (predicting held-out logs over the horizon) and the model that flew (what_flies)."""
    lines = ["What each selection's held-out flights flew:", ""]
    for sel, fit in result.fits.items():
        checks = [c.describe() for c in (fit.check, fit.structure_check) if c is not None]
        lines.append(f"- `{sel}`: " + "; ".join([*checks, f"**{what_flies(fit)}**"]))
    return [*lines, ""]


def _closed_loop_lines(result: Paper000Result) -> list[str]:
    """The closed-loop check's verdicts (experiments.study.closed_loop): per selection which
    model flew and every comparison with both RMSEs; none if the check did not run."""
    records = {
        sel: fit.model.training["closed_loop_check"]
        for sel, fit in result.fits.items()
        if "closed_loop_check" in fit.model.training
    }
    if not records:
        return []
    lines = [
        "",
        "Closed-loop check on the training seeds (each model that would fly, flown on the "
        "nominal flights' seeds and compared flight for flight with the model it replaces and "
        "the structure alone; it flies only if it tracks no worse, pooled tracking RMSE):",
        "",
        "| selection | candidate | incumbent | candidate [m] | incumbent [m] | flights | verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for sel, record in records.items():
        for c in record["comparisons"]:
            verdict = "no worse" if c["passed"] else "worse: refused"
            lines.append(
                f"| {sel} | {c['candidate']} | {c['incumbent']} | {c['candidate_rmse_m']:.4f} "
                f"| {c['incumbent_rmse_m']:.4f} | {c['n_flights']} | {verdict} |"
            )
    lines.append("")
    lines += [f"- `{sel}` flew: {record['flies']}" for sel, record in records.items()]
    return lines


def _identified(result: Paper000Result) -> str:
    """ "with time constants identified from the nominal flights (...) ", "with the
    autopilot's velocity-loop gains recorded with the nominal flights (...) " or ""."""
    fit = next(iter(result.fits.values()))
    lag = fit.model.training.get("identified_lag")
    if lag is None:
        gains = [(k, v) for k, v in fit.model.features.nominal_params if k.startswith("vel_")]
        if not gains:
            return ""
        listed = ", ".join(f"{k}={v:g}" for k, v in gains)
        return (
            f"with the autopilot's velocity-loop gains recorded with the nominal flights "
            f"({listed}) "
        )
    return (
        f"with time constants identified from the nominal flights (tau_s={lag['tau_s']:.3f} s, "
        f"tau_d_s={lag['tau_d_s']:.3f} s) "
    )


def _where(config: StudyConfig) -> str:
    """Where the flights ran: local worker processes or a Dask cluster."""
    if config.scheduler is None:
        return f"{config.workers} worker processes"
    return f"on the Dask cluster at {config.scheduler}"
