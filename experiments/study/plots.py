"""The study's PNG figures (matplotlib's object API: no global backend state)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from experiments.study.jobs import FlightSummary
from experiments.study.metrics import following_rows
from experiments.study.paper000 import Paper000Result, planner_label
from experiments.study.paper004 import TrialsResult
from gp.plots import plot_residuals

_N_PATH_PANELS = 4


def plot_paths(result: Paper000Result, path: Path) -> Path:
    """Top views of the first trajectories: reference and one flight of every planner."""
    paths_figure(result).savefig(path, dpi=90, bbox_inches="tight")
    return path


def paths_figure(result: Paper000Result) -> Figure:
    """plot_paths' figure: per panel a legend beside the axes (inside, it hid the paths) naming
    each planner with its flight's tracking RMSE."""
    n = min(_N_PATH_PANELS, len(result.references))
    fig = Figure(figsize=(7.5 * n, 4.8), layout="constrained")
    for i in range(n):
        ax = fig.add_subplot(1, n, i + 1)
        ref = result.references[i]
        pos = ref.sample(np.linspace(0.0, ref.duration_s, 400)).pos_ned_m
        ax.plot(pos[:, 1], pos[:, 0], "k--", lw=1.2, label="reference")
        for planner, flights in result.flights.items():
            flight = next(f for f in flights if f.trajectory == i)
            _plot_flight(ax, flight, planner_label(planner, result.structure_model))
        ax.set(xlabel="east [m]", ylabel="north [m]", title=f"trajectory {i}", aspect="equal")
        ax.grid(alpha=0.3)
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return fig


def _plot_flight(ax, flight: FlightSummary, label: str) -> None:
    log = flight.log
    follow = following_rows(log)
    ax.plot(
        log["pos_e_m"][follow],
        log["pos_n_m"][follow],
        lw=1.0,
        label=f"{label} (tracking RMSE {flight.tracking_rmse_m:.3f} m)",
    )


def plot_residual_fits(result: Paper000Result, out_dir: Path) -> list[Path]:
    """Residual vs velocity with the GP mean and inducing points, per selection and axis."""
    paths = []
    for sel, fit in result.fits.items():
        paths += plot_residuals(fit.model, fit.test, out_dir / f"gp_{sel}")
    return paths


def plot_trials(trials: TrialsResult, path: Path) -> Path:
    """Tracking and residual RMSE per trial on the repeated path ([Ostafew16], Fig. 10)."""
    k = np.arange(1, len(trials.trials) + 1)
    fig = Figure(figsize=(10.0, 4.0))
    ax1 = fig.add_subplot(1, 2, 1)
    ax1.plot(k, [t.tracking_rmse_m for t in trials.trials], "o-")
    ax1.set(xlabel="trial", ylabel="tracking RMSE [m]", title="tracking error per trial")
    ax2 = fig.add_subplot(1, 2, 2)
    ax2.plot(k, [t.residual_rmse_mps for t in trials.trials], "o-", color="tab:red")
    ax2.set(xlabel="trial", ylabel="residual RMSE [m/s]", title="model error per trial")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.set_xticks(k)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    return path
