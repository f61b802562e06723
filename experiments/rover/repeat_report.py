"""What a teach-and-repeat run reports: one line per trial, a JSON summary, a PNG of errors.

The errors are [Ostafew16]'s e_L [m] and e_H [rad] against the path pose at the rover's
projection, from the Link's own telemetry (experiments.rover.link_drive); the figure has the
same panels as the regimes' (experiments.rover.report): max and RMS errors per trial, and
travel time per trial, numbered over every run that used the experience file (its history
rows, experiments.rover.experience_file.HISTORY_COLUMNS), and the speeds along the path,
scheduled and driven, in this run's trials (earlier runs' schedules are not kept).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from experiments.rover.experience_file import HISTORY_COLUMNS
from experiments.rover.link_drive import LinkDrive
from experiments.rover.repeat import RepeatOutcome, Trial

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _max(a: np.ndarray) -> float:
    return float(np.max(np.abs(a))) if len(a) else float("nan")


def _rms(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(a**2))) if len(a) else float("nan")


def _driven_mps(d: LinkDrive) -> float:
    """The speed the rover drove [m/s]: arc length covered over the travel time (NaN without
    steps); a rover slower than its schedule (at its speed limit) drives less than asked."""
    return float((d.s_m[-1] - d.s_m[0]) / d.travel_time_s) if d.travel_time_s > 0 else math.nan


def _json_numbers(values: list) -> list:
    """Floats as JSON has them: NaN (a trial that never got to drive) becomes null."""
    return [None if isinstance(v, float) and not np.isfinite(v) else v for v in values]


def trial_line(trial: Trial) -> str:
    """One line: max / RMS e_L and e_H, travel time, mean speed driven and scheduled,
    experiences stored."""
    d = trial.drive
    end = "" if d.reached_end else ", did not reach the end"
    return (
        f"trial {trial.number}: max |e_L| {_max(d.e_lat_m):.3f} m, RMS e_L {_rms(d.e_lat_m):.3f} "
        f"m, max |e_H| {_max(d.e_head_rad):.3f} rad, RMS e_H {_rms(d.e_head_rad):.3f} rad, "
        f"travel time {d.travel_time_s:.1f} s at {_driven_mps(d):.2f} m/s mean "
        f"({float(np.mean(trial.schedule_mps)):.2f} m/s scheduled), {trial.experiences} "
        f"experiences{end}"
    )


def history_row(trial: Trial) -> np.ndarray:
    """The trial's figures in HISTORY_COLUMNS order, (6,)."""
    d = trial.drive
    return np.array([trial.number, _max(d.e_lat_m), _rms(d.e_lat_m), _max(d.e_head_rad),
                     _rms(d.e_head_rad), d.travel_time_s])  # fmt: skip


def summary(outcome: RepeatOutcome, about: dict, history: np.ndarray) -> dict:
    """The run's JSON summary: ``about`` (path, files, options), this run's per-trial figures
    and, under "all_trials", those of every trial kept in the experience file."""
    ts = outcome.trials
    figures = {
        "max_e_lat_m": [_max(t.drive.e_lat_m) for t in ts],
        "rms_e_lat_m": [_rms(t.drive.e_lat_m) for t in ts],
        "max_e_head_rad": [_max(t.drive.e_head_rad) for t in ts],
        "rms_e_head_rad": [_rms(t.drive.e_head_rad) for t in ts],
        "travel_time_s": [t.drive.travel_time_s for t in ts],
        "mean_speed_mps": [float(np.mean(t.schedule_mps)) for t in ts],
        "driven_speed_mps": [_driven_mps(t.drive) for t in ts],
    }
    return {
        **about,
        "status": outcome.status,
        "detail": outcome.detail,
        "trial": [t.number for t in ts],
        **{k: _json_numbers(v) for k, v in figures.items()},
        "reached_end": [t.drive.reached_end for t in ts],
        "experiences": [t.experiences for t in ts],
        "all_trials": {
            "trial": [int(n) for n in history[:, 0]],
            **{
                c: _json_numbers(history[:, k].tolist())
                for k, c in enumerate(HISTORY_COLUMNS)
                if k > 0
            },
        },
    }


def figure(
    history: np.ndarray, title: str, path_s_m: np.ndarray, trials: Sequence[Trial]
) -> Figure:
    """The figure of history rows (k, 6): max and RMS e_L / e_H per trial; travel time per
    trial; and for ``trials`` (this run's), the scheduled speed at each path vertex (its arc
    length ``path_s_m``, (N,) [m]) and the speed driven along the path (ds/dt of the drive)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    s = {c: history[:, k] for k, c in enumerate(HISTORY_COLUMNS)}
    j = s["trial"]
    fig, axes = plt.subplots(3, 1, figsize=(8, 9))
    ax = axes[0]
    ax.plot(j, s["max_e_lat_m"], "o-", label="max |e_L| [m]")
    ax.plot(j, s["rms_e_lat_m"], "s-", label="RMS e_L [m]")
    ax.plot(j, s["max_e_head_rad"], "o--", label="max |e_H| [rad]")
    ax.plot(j, s["rms_e_head_rad"], "s--", label="RMS e_H [rad]")
    ax.set_ylabel("path error [m] or [rad]")
    ax.legend()
    axes[1].plot(j, s["travel_time_s"], "o-")
    axes[1].set_ylabel("travel time [s]")
    if np.any(np.isfinite(s["travel_time_s"])):  # from 0: equal times got an offset axis
        axes[1].set_ylim(0.0, 1.1 * np.nanmax(s["travel_time_s"]) + 1e-9)
    for ax in axes[:2]:
        ax.set_xlabel("trial")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax = axes[2]
    for trial in trials:
        (line,) = ax.plot(path_s_m, trial.schedule_mps, label=f"trial {trial.number} scheduled")
        d = trial.drive
        if len(d.t_s) > 1:
            driven = np.gradient(d.s_m, d.t_s)
            ax.plot(d.s_m, driven, ".", ms=3, color=line.get_color(), alpha=0.5)
    ax.set_xlabel("distance along the path [m] (dots: speed driven)")
    ax.set_ylabel("speed [m/s]")
    if trials:
        ax.legend(fontsize="small", ncol=2)
    fig.suptitle(title)
    fig.tight_layout()
    return fig
