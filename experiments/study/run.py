"""Run the whole study and write ``report.md`` with its PNGs and model files.

Flights are spread over ``config.workers`` local processes, or over the workers of a Dask
cluster when ``config.scheduler`` names one (see :mod:`experiments.executors`); every flight is
lockstep and seeded, so the figures (all but the wall-clock solve times) are the same on every
run, machine and cluster, and planners that fly the same (e.g. two refused selections) share
one flight (experiments.study.same_flights).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from experiments.executors import job_executor
from experiments.study.config import StudyConfig
from experiments.study.figures import PlannerFigures, all_planner_figures, headline_figures
from experiments.study.paper000 import Paper000Result, run_paper000
from experiments.study.paper004 import TrialsResult, run_trials
from experiments.study.plots import plot_paths, plot_residual_fits, plot_trials
from experiments.study.report import render_report
from flightlog.atomic_output import atomic_output_dir, check_writable_dir
from gp.model_io import save_model


@dataclass(frozen=True, eq=False)
class StudyResult:
    """Everything the study measured, and where the report went."""

    paper000: Paper000Result
    figures: dict[str, PlannerFigures]
    headline: dict[str, float]
    trials: TrialsResult | None  # None: not flown (n_trials 0)
    report_path: Path


def worker_progress(message: str) -> None:
    """Progress from a worker process (stderr; picklable, unlike a closure)."""
    print(f"study [worker] {message}", file=sys.stderr, flush=True)


def run_study(config: StudyConfig, progress: Callable[[str], None]) -> StudyResult:
    """Fly [Kulathunga23]'s experiment and [Ostafew16]'s trials, write the report."""
    start = time.perf_counter()
    out = check_writable_dir(config.out_dir)
    with job_executor(config.workers, config.scheduler) as pool:
        trials_future = (
            pool.submit(run_trials, config, worker_progress) if config.n_trials else None
        )
        result = run_paper000(config, pool, progress)
        trials = None
        if trials_future is not None:
            progress("waiting for the trial-to-trial flights")
            trials = trials_future.result()
    figs = all_planner_figures(result)
    with atomic_output_dir(out) as tmp:  # the whole report set appears at once, or not at all
        for sel, fit in result.fits.items():
            save_model(tmp / f"gp_{sel}", fit.model)
        images = {
            "paths": [plot_paths(result, tmp / "paths.png").name],
            "residuals": [p.name for p in plot_residual_fits(result, tmp)],
            "trials": [plot_trials(trials, tmp / "trials.png").name] if trials else [],
        }
        text = render_report(config, result, figs, trials, images, time.perf_counter() - start)
        (tmp / "report.md").write_text(text)
    report = out / "report.md"
    progress(f"wrote {report}")
    return StudyResult(result, figs, headline_figures(result), trials, report)
