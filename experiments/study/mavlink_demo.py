"""The learning loop over MAVLink, end to end: what `make demo` runs.

A `vehicle-sim` endpoint (the study vehicle) is started as a child process; the companion flies
the mission with the nominal NMPC ([Kulathunga23]'s kinematic model) over MAVSDK; the model is
learned from that log with fit-gp's library function: the velocity loop's lag identified by
least squares, then a sparse GP (low_speed inducing points) on what is left; a fresh endpoint
is started and the companion flies the mission again with the augmented NMPC. The two flights
are compared and written up (report.md with PNGs). Every endpoint is stopped when its flight
ends, also on errors and Ctrl-C (the companion itself lands the vehicle first).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from companion.app import CompanionConfig, CompanionResult, run_companion
from companion.mission import load_mission
from companion.mission_reference import reference_of
from companion.runner import RunnerConfig
from experiments.sim_endpoint import SimEndpoint
from experiments.study.config import STUDY_VEHICLE
from experiments.study.fitting import fit_residual
from experiments.study.metrics import residual_rmse_mps, tracking_errors_m, tracking_rmse_m
from flightlog.atomic_output import write_figure_atomic, write_text_atomic
from flightlog.reader import read_log
from flightlog.schema import FlightLog
from gp.errors import DatasetError
from gp.model_io import save_model
from gp.plots import plot_residuals
from gp.prediction_check import refusal
from gp.training import TrainingResult

SELECTION = "low_speed"
# The GP's inputs: the velocity, not the command. The command is the NMPC's decision variable;
# a GP fitted on one nominal flight's commands is wrong off them and the optimiser exploits it
# (one-flight tracking gain 1.4-2.3x with the command among the features, 3-4.5x without,
# measured on the study's short trajectories).
FEATURES = "velocity"
# Generous deadlines: on a busy computer the endpoint (a fresh Python process) may need most of
# a minute before its first heartbeat; the flight itself is not affected by waiting longer.
DEMO_CONNECT_TIMEOUT_S = 120.0
DEMO_PHASE_TIMEOUT_S = 30.0


@dataclass(frozen=True)
class DemoConfig:
    """The demo's inputs: mission file, vehicle config, output folder, seeds, loop rate."""

    mission_path: Path
    out_dir: Path = Path("out/demo")
    vehicle: str = STUDY_VEHICLE
    rate_hz: float = 50.0
    seed: int = 0


@dataclass(frozen=True)
class FlightFigures:
    """One demo flight's figures (residual [m/s], tracking [m], solve times [ms]), the
    computer's 1-minute load average when it landed (timings are read against it) and the
    model its planner flew, as its log records it (CompanionNmpc.flown_model)."""

    name: str
    status: str
    residual_rmse_mps: float
    tracking_rmse_m: float
    solve_median_ms: float
    solve_p99_ms: float
    deadline_misses: int
    ticks: int
    load_average: float
    planner_model: str = ""


class DemoError(RuntimeError):
    """A demo flight did not complete; one line."""


def run_demo(config: DemoConfig, progress: Callable[[str], None]) -> list[FlightFigures]:
    """Fly nominal, fit, fly augmented; write report.md; return both flights' figures."""
    out = config.out_dir
    out.mkdir(parents=True, exist_ok=True)
    nominal, nominal_load = _fly(config, "nominal", None, config.seed, progress)
    progress(f"fitting the residual model ({SELECTION}, m=30) from {nominal.path}")
    try:
        fit = fit_residual(
            [nominal], SELECTION, 1.0 / config.rate_hz, features=FEATURES, progress=progress
        )
    except DatasetError as exc:  # nothing learned may fly unchecked
        raise DemoError(f"{_unlearnable(nominal)}: {exc}") from None
    model_path = save_model(out / f"gp_{SELECTION}", fit.model)
    progress(f"wrote {model_path}")
    flying = model_path
    if fit.flown == "structure":
        progress("the augmented flight flies the identified lag without the GP")
    if fit.flown == "nominal":
        progress(f"{refusal(fit.model)}: the second flight flies the nominal planner")
        flying = None
    augmented, augmented_load = _fly(config, "augmented", flying, config.seed + 1, progress)
    logs = {"nominal": nominal, "augmented": augmented}
    loads = {"nominal": nominal_load, "augmented": augmented_load}
    figures = [_figures(name, log, loads[name]) for name, log in logs.items()]
    images = _plots(config, logs, fit, out)
    write_text_atomic(out / "report.md", _report(config, figures, images, model_path, fit))
    progress(f"wrote {out / 'report.md'}")
    return figures


def _fly(
    config: DemoConfig,
    name: str,
    gp_model: Path | None,
    seed: int,
    progress: Callable[[str], None],
) -> tuple[FlightLog, float]:
    """Fly one flight against a fresh endpoint: its log and the 1-minute load average after."""
    log_path = config.out_dir / f"{name}.csv"
    progress(f"== {name} flight: starting vehicle-sim ({config.vehicle}) on loopback")
    with SimEndpoint(config.vehicle, seed, config.out_dir / f"vehicle_sim_{name}.log") as sim:
        companion = CompanionConfig(
            mission_path=config.mission_path,
            link="mavsdk",
            url=sim.mavsdk_url,
            planner="nmpc",
            gp_model=gp_model,
            log_path=log_path,
            replace_log=True,
            runner=RunnerConfig(
                rate_hz=config.rate_hz,
                connect_timeout_s=DEMO_CONNECT_TIMEOUT_S,
                arm_timeout_s=DEMO_PHASE_TIMEOUT_S,
                offboard_timeout_s=DEMO_PHASE_TIMEOUT_S,
            ),
        )
        result: CompanionResult = run_companion(companion, progress)
    if result.outcome.status == "interrupted":  # landed after the user's Ctrl-C: stop here
        raise KeyboardInterrupt
    if result.outcome.status != "completed" or result.log_path is None:
        raise DemoError(f"the {name} flight did not complete: {result.outcome.detail}")
    return read_log(result.log_path), os.getloadavg()[0]


def _unlearnable(log: FlightLog) -> str:
    """Why a flight log may be too broken up to learn from: the loop's misses and longest gap."""
    t = log["t_s"][log["mode"] == "OFFBOARD"]
    gap_s = float(np.max(np.diff(t))) if t.size > 1 else float("nan")
    return (
        f"the nominal flight cannot be learned from on this computer "
        f"({log.metadata.get('loop_deadline_misses', '?')} deadline misses in "
        f"{log.metadata.get('loop_ticks', '?')} ticks, longest gap {gap_s:.2f} s, load "
        f"average {os.getloadavg()[0]:.1f})"
    )


def _figures(name: str, log: FlightLog, load_average: float) -> FlightFigures:
    follow = log["mode"] == "OFFBOARD"
    solve_ms = 1e3 * log["solve_time_s"][follow]
    return FlightFigures(
        name=name,
        status=str(log.metadata.get("outcome", "")),
        residual_rmse_mps=residual_rmse_mps(log),
        tracking_rmse_m=tracking_rmse_m(log),
        solve_median_ms=float(np.median(solve_ms)),
        solve_p99_ms=float(np.percentile(solve_ms, 99)),
        deadline_misses=int(log.metadata.get("loop_deadline_misses", 0)),
        ticks=int(log.metadata.get("loop_ticks", 0)),
        load_average=load_average,
        planner_model=str(log.metadata.get("planner_model", "")),
    )


def comparison_table(figures: list[FlightFigures]) -> str:
    """The two flights side by side (Markdown)."""
    lines = [
        "| flight | residual RMSE [m/s] | tracking RMSE [m] | solve median / p99 [ms] "
        "| deadline misses | load average | planner model |",
        "|---|---|---|---|---|---|---|",
    ]
    for f in figures:
        lines.append(
            f"| {f.name} | {f.residual_rmse_mps:.4f} | {f.tracking_rmse_m:.4f} "
            f"| {f.solve_median_ms:.2f} / {f.solve_p99_ms:.2f} | {f.deadline_misses} / {f.ticks} "
            f"| {f.load_average:.1f} | {f.planner_model} |"
        )
    return "\n".join(lines)


def _plots(config: DemoConfig, logs: dict[str, FlightLog], fit, out: Path) -> list[str]:
    from matplotlib.figure import Figure

    reference = reference_of(load_mission(config.mission_path))
    ref = reference.sample(np.linspace(0.0, reference.duration_s, 400)).pos_ned_m
    fig = Figure(figsize=(12.0, 4.8))
    ax_path, ax_err = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    ax_path.plot(ref[:, 1], ref[:, 0], "k--", lw=1.2, label="reference")
    for name, log in logs.items():
        follow = log["mode"] == "OFFBOARD"
        ax_path.plot(log["pos_e_m"][follow], log["pos_n_m"][follow], label=name)
        t = log["t_s"][follow]
        ax_err.plot(t - t[0], tracking_errors_m(log), label=name)
    ax_path.set(xlabel="east [m]", ylabel="north [m]", title="reference vs flown", aspect="equal")
    ax_err.set(
        xlabel="time in OFFBOARD [s]",
        ylabel="distance to the reference's point at that time [m]",
        title="tracking error (lagging along the path counts)",
    )
    for ax in (ax_path, ax_err):
        ax.grid(alpha=0.3)
        ax.legend()
    fig.tight_layout()
    write_figure_atomic(fig, out / "paths.png", dpi=90)
    residual_pngs = plot_residuals(fit.model, fit.train, out / f"gp_{SELECTION}")
    return ["paths.png", *[p.name for p in residual_pngs]]


def _report(
    config: DemoConfig,
    figures: list[FlightFigures],
    images: list[str],
    model_path: Path,
    fit: TrainingResult,
) -> str:
    features = fit.model.features
    lag = fit.model.training.get("identified_lag")
    structure = (
        f"the velocity lag identified from the first flight (tau_s={lag['tau_s']:.3f} s, "
        f"tau_d_s={lag['tau_d_s']:.3f} s)"
        if lag is not None
        else f"`{features.nominal_model}`"
    )
    checks = [c for c in (fit.check, fit.structure_check) if c is not None]
    lines = [
        "# Demo: the learning loop over MAVLink",
        "",
        f"Mission `{config.mission_path.name}`, vehicle `{config.vehicle}` behind a `vehicle-sim` "
        f"MAVLink endpoint, companion over MAVSDK at {config.rate_hz:g} Hz with the NMPC: first "
        f"nominal ([Kulathunga23]'s kinematic model), then "
        f"{what_flew_second(fit, model_path.name, structure)}",
        "",
        comparison_table(figures),
        "",
        *(["Checked before the second flight:", *[f"- {c.describe()}" for c in checks], ""]),
        *[f"![{p}]({p})" for p in images],
        "",
    ]
    return "\n".join(lines)


def what_flew_second(fit: TrainingResult, model_file: str, structure: str) -> str:
    """One sentence: the model the second flight flew and why, from the fit's two checks
    (``structure``: how the report names the learned model's nominal model)."""
    gp = f"a sparse GP on `{fit.model.features.name}` features"
    if fit.flown == "nominal":
        return (
            f"with the nominal planner again: the learned model (`{model_file}`: {structure} "
            f"plus {gp}) was refused, since it did not predict better than nominal."
        )
    if fit.flown == "structure":
        return (
            f"augmented with {structure} alone (from `{model_file}`): {gp} was fitted on top "
            "but left out, since it did not predict better than the structure without it."
        )
    return f"augmented with `{model_file}`: {structure} plus {gp}, fitted from the first flight."
