"""Run a rover regime and write its figures and summary (atomically) into a folder.

Figures (:func:`figure`): max and RMS e_L / e_H per trial, e_L along the path in the first and
the last trial, scheduled speeds along the path per trial, travel time per trial;
``<regime>.json`` holds the per-trial numbers (with how often the safety
governor slowed each pass, ``safety_trips``) and the reductions 1 - (last trial / trial 1) of
the max errors. With a speed scheduler the last trial is driven
again with learning disabled (:func:`learning_disabled_pass`), and the summary adds that pair.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from experiments.rover.learner import make_history_gp
from experiments.rover.scenarios import RoverScenario, scenario
from experiments.rover.trial import TrialRecord, run_trial, run_trials
from flightlog.atomic_output import write_figure_atomic, write_text_atomic

if TYPE_CHECKING:
    import matplotlib.figure


def _late_reductions(first: float, late: list[float]) -> list[float]:
    """1 - late / first for each trial of the second half, sorted (min, ..., max) [-]."""
    return sorted(1.0 - v / first for v in late)


def summarise(records: list[TrialRecord]) -> dict:
    """Per-trial figures and reductions. [Ostafew16] Figs. 10, 13, 18 plot the max error of
    every trial and say the late trials "continued to vary" (section 5.3), so beside the last
    trial's reduction (the issue's figure) the reductions of every trial in the second half are
    given too (``late_*``, sorted): which one is last decides the headline figure.
    """
    first, last = records[0], records[-1]
    late = records[len(records) // 2 :]
    return {
        "trials": len(records),
        "max_e_lat_m": [r.max_e_lat_m for r in records],
        "rms_e_lat_m": [r.rms_e_lat_m for r in records],
        "max_e_head_rad": [r.max_e_head_rad for r in records],
        "rms_e_head_rad": [r.rms_e_head_rad for r in records],
        "travel_time_s": [r.travel_time_s for r in records],
        "mean_scheduled_speed_mps": [float(np.mean(r.schedule_mps)) for r in records],
        "completed": [r.completed for r in records],
        "safety_trips": [r.safety_trips for r in records],
        "max_lateral_reduction": 1.0 - last.max_e_lat_m / first.max_e_lat_m,
        "max_heading_reduction": 1.0 - last.max_e_head_rad / first.max_e_head_rad,
        # as the localisation measures them, [Ostafew16]'s own measure (TrialRecord)
        "max_e_lat_localised_m": [r.max_e_lat_est_m for r in records],
        "max_lateral_reduction_localised": 1.0 - last.max_e_lat_est_m / first.max_e_lat_est_m,
        "max_heading_reduction_localised": 1.0 - last.max_e_head_est_rad / first.max_e_head_est_rad,
        "late_lateral_reductions": _late_reductions(
            first.max_e_lat_m, [r.max_e_lat_m for r in late]
        ),
        "late_lateral_reductions_localised": _late_reductions(
            first.max_e_lat_est_m, [r.max_e_lat_est_m for r in late]
        ),
        "late_heading_reductions": _late_reductions(
            first.max_e_head_rad, [r.max_e_head_rad for r in late]
        ),
        "max_local_experiences": int(max(int(r.n_local.max()) for r in records)),
        "step_median_ms": float(np.median(np.concatenate([r.step_time_s for r in records]))) * 1e3,
        "step_median_cpu_ms": float(np.median(np.concatenate([r.step_cpu_s for r in records])))
        * 1e3,
    }


def learning_disabled_pass(sc: RoverScenario, records: list[TrialRecord]) -> TrialRecord:
    """The last trial's schedule driven again with learning disabled.

    [Ostafew16] Fig. 11 compares learning disabled and enabled on the same robot, path and
    speed (the ROC6 at 0.6 m/s). Under a speed scheduler the last trial is much faster than
    the first, so 1 - last / first mixes learning with the speed increase; this pass keeps the
    speed and removes the learning. Same trial index, hence the same start and
    localisation-error draws as the last trial.
    """
    return run_trial(
        replace(sc, learning=False), make_history_gp(), records[-1].schedule_mps, len(records) - 1
    )


def same_schedule_figures(last: TrialRecord, disabled: TrialRecord) -> dict:
    """The last trial against :func:`learning_disabled_pass`: max errors and reductions."""
    return {
        "learning_disabled_max_e_lat_m": disabled.max_e_lat_m,
        "learning_disabled_max_e_head_rad": disabled.max_e_head_rad,
        "learning_disabled_travel_time_s": disabled.travel_time_s,
        # the governor may slow this pass below the schedule: its travel time then says so
        "learning_disabled_safety_trips": disabled.safety_trips,
        "max_lateral_reduction_vs_learning_disabled": 1.0 - last.max_e_lat_m / disabled.max_e_lat_m,
        "max_heading_reduction_vs_learning_disabled": 1.0
        - last.max_e_head_rad / disabled.max_e_head_rad,
    }


def figure(records: list[TrialRecord], s_m: np.ndarray, name: str) -> matplotlib.figure.Figure:
    """The regime's figure: errors per trial; e_L along the path in the first and the last
    trial ([Ostafew16] Figs. 9, 12, 17); scheduled speed along the path (one line per trial,
    coloured by trial); travel time per trial. ``s_m`` (N,) is the vertices' arc length."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    j = np.arange(1, len(records) + 1)
    fig, axes = plt.subplots(4, 1, figsize=(8, 12))
    ax = axes[0]
    ax.plot(j, [r.max_e_lat_m for r in records], "o-", label="max |e_L| [m]")
    ax.plot(j, [r.rms_e_lat_m for r in records], "s-", label="RMS e_L [m]")
    ax.plot(j, [r.max_e_head_rad for r in records], "o--", label="max |e_H| [rad]")
    ax.plot(j, [r.rms_e_head_rad for r in records], "s--", label="RMS e_H [rad]")
    ax.set_ylabel("path error [m] or [rad]")
    ax.legend()
    ax = axes[1]
    first_and_last = {0: "r", len(records) - 1: "k"}  # one entry when one trial
    for k, style in first_and_last.items():
        r = records[k]
        ax.plot(r.s_m, r.e_lat_m, style, lw=0.8, label=f"trial {k + 1}")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("distance along path [m]")
    ax.set_ylabel("lateral error e_L [m]")
    ax.legend()
    ax = axes[2]
    colours = plt.cm.viridis
    for k, r in enumerate(records):
        ax.plot(s_m, r.schedule_mps, color=colours(k / max(1, len(records) - 1)))
    ax.set_xlabel("distance along path [m]")
    ax.set_ylabel("scheduled speed [m/s]")
    scale = plt.cm.ScalarMappable(cmap=colours, norm=plt.Normalize(1, max(2, len(records))))
    bar = fig.colorbar(scale, ax=ax, pad=0.01)
    bar.set_label("trial")
    bar.locator = MaxNLocator(integer=True)
    bar.update_ticks()
    axes[3].plot(j, [r.travel_time_s for r in records], "o-")
    axes[3].set_ylabel("travel time [s]")
    for ax in (axes[0], axes[3]):
        ax.set_xlabel("trial")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    fig.suptitle(f"{name}: [Ostafew16] path repeating with LB-NMPC")
    fig.tight_layout()
    return fig


def _plots(records: list[TrialRecord], s_m: np.ndarray, folder: str, name: str) -> None:
    """``folder/<name>.png``: :func:`figure`, written whole or not at all."""
    write_figure_atomic(figure(records, s_m, name), os.path.join(folder, f"{name}.png"), dpi=90)


def run_regime(
    name: str,
    out_dir: str,
    trials: int | None = None,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Run regime ``name`` (rover_exp1..3) and write ``<name>.png`` and ``<name>.json`` into
    ``out_dir``, each whole or not at all; ``progress`` is told each trial as it ends (one line).

    Raises:
        OutputError: ``out_dir`` cannot be written (one line).
    """
    sc = scenario(name, seed)
    if trials is not None:
        sc = replace(sc, trials=trials)

    def trial_done(j: int, r: TrialRecord) -> None:
        if progress is not None:
            progress(
                f"{name} trial {j + 1}/{sc.trials}: max |e_L| {r.max_e_lat_m:.3f} m, "
                f"max |e_H| {r.max_e_head_rad:.3f} rad, travel time {r.travel_time_s:.1f} s"
                + ("" if r.completed else ", did not complete")
            )

    records = run_trials(sc, on_trial=trial_done)
    summary = summarise(records)
    if sc.scheduler is not None and sc.learning:
        if progress is not None:
            progress(f"{name}: the last trial's speeds again with learning disabled")
        summary.update(same_schedule_figures(records[-1], learning_disabled_pass(sc, records)))
    _plots(records, sc.path.s_m, out_dir, name)
    write_text_atomic(os.path.join(out_dir, f"{name}.json"), json.dumps(summary, indent=1))
    return summary
