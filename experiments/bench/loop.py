"""Learning-loop benchmark (`bench --only loop`): the study's headline figures and the 50 Hz
control loop's deadline misses with the augmented NMPC.

Figures:
    residual_rmse_nominal, residual_rmse_low_speed, residual_rmse_cluster   one-step velocity
        residual RMSE [m/s] of the model that flew (nominal NMPC; augmented per selection)
    tracking_rmse_nominal_m, tracking_rmse_augmented_m   position tracking RMSE [m]
        (augmented: low_speed)
    loop_deadline_miss_fraction   deadline misses / ticks of a whole mission flown at 50 Hz
        with the augmented NMPC (compiled) against the simulator paced by the wall clock
    agile_gp_over_structure, wind_gp_over_structure   tracking RMSE of the identified structure
        alone divided by structure + GP (low_speed), in the agile and wind_field regimes
        (experiments.study.regimes; > 1 when the GP helps); reduced studies of
        REGIME_TRAJECTORIES x REGIME_REPEATS flights per planner
    agile_gp_over_structure_settled, wind_gp_over_structure_settled   the same after the first
        2 s of following (experiments.study.metrics.SETTLE_S), without the start offset the
        takeoff left
The figures come from a reduced study (4 trajectories, one flight each per planner, m = 30);
``study`` runs [Kulathunga23]'s full experiment. ``quick=True`` runs the study's smoke version and
a short paced flight with the uncompiled planner (under a minute; its deadline figure is then
only a smoke value). Each study's report (which model flew and why) is kept in
out/bench/loop_study/<regime>/.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from companion.flight_recorder import FlightRecorder
from companion.mission import Mission
from companion.nmpc_planner import CompanionNmpc
from companion.runner import RunnerConfig, fly_mission
from experiments.study.config import StudyConfig
from experiments.study.paced_link import WallPacedInProcessLink
from experiments.study.regimes import with_regime
from experiments.study.run import run_study
from gp.model_io import ResidualModel
from planners.bspline import BSplineReference
from vehicle_sim import Simulator, load_sim_config

STUDY_OUT = Path("out/bench/loop_study")  # the studies' reports, kept
_PACED_POINTS_QUICK = ((0.0, 0.0, -3.0), (3.0, 2.0, -3.0), (6.0, 0.0, -3.0))
_PACED_POINTS = ((0.0, 0.0, -3.0), (8.0, 4.0, -3.0), (16.0, -4.0, -3.5), (24.0, 0.0, -3.0))


def paced_deadline_miss_fraction(
    config: StudyConfig,
    model: ResidualModel,
    points: tuple[tuple[float, float, float], ...],
    progress: Callable[[str], None],
) -> float:
    """Fly ``points`` (a B-spline) at the loop rate with the augmented NMPC, real time."""
    settings = replace(
        config.nmpc,
        time_budget_s=config.nmpc.period_s,
        compile_functions=config.compile_augmented,
    )
    planner = CompanionNmpc(settings, model)
    reference = BSplineReference(np.asarray(points), config.max_speed_mps)
    mission = Mission("paced", 3.0, settings.speed_limit_mps, "bspline", points, 0.5)
    link = WallPacedInProcessLink(Simulator(load_sim_config(config.vehicle), seed=0))
    recorder = FlightRecorder(settings.period_s)
    runner = RunnerConfig(rate_hz=1.0 / settings.period_s)
    outcome = fly_mission(link, planner, reference, mission, runner, recorder.record, progress)
    return outcome.deadline_misses / max(outcome.ticks, 1)


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """Run the reduced (or smoke) study and the paced flight; returns the figures."""
    config = StudyConfig(out_dir=STUDY_OUT / "paper000", n_trajectories=4, repeats=1, n_trials=2)
    if quick:
        config = replace(config.quick(), n_trials=2)
    progress(f"loop: study with {config.n_trajectories} trajectories")
    result = run_study(config, progress)
    model = result.paper000.fits[config.selections[0]].model
    progress("loop: flying the augmented NMPC at 50 Hz on the wall clock")
    points = _PACED_POINTS_QUICK if quick else _PACED_POINTS
    miss = paced_deadline_miss_fraction(config, model, points, progress)
    figures = {**result.headline, "loop_deadline_miss_fraction": miss}
    for regime, prefix in (("agile", "agile"), ("wind_field", "wind")):
        figures |= regime_figures(regime, prefix, progress, quick)
    from experiments.bench import rover  # [Ostafew16] on its own robot (issue 16)

    rover_figures = rover.run(progress, quick)
    figures["rover_exp1_max_lateral_reduction"] = rover_figures["rover_exp1_max_lateral_reduction"]
    return figures


REGIME_TRAJECTORIES, REGIME_REPEATS = 2, 3


def regime_figures(
    regime: str, prefix: str, progress: Callable[[str], None], quick: bool
) -> dict[str, float]:
    """A reduced study of ``regime``: its gp_over_structure and tracking figures, prefixed."""
    config = StudyConfig(
        out_dir=STUDY_OUT / regime,
        n_trajectories=REGIME_TRAJECTORIES,
        repeats=REGIME_REPEATS,
        n_trials=2,
    )
    if quick:
        config = replace(config.quick(), n_trials=2)
    config = with_regime(config, regime)
    progress(f"loop: {regime} regime, {config.n_trajectories} trajectories")
    headline = run_study(config, progress).headline
    keep = ("gp_over_structure", "gp_over_structure_settled", "tracking_rmse_nominal_m",
            "tracking_rmse_augmented_m", "tracking_rmse_identified_lag_m")  # fmt: skip
    return {f"{prefix}_{k}": headline[k] for k in keep if k in headline}
