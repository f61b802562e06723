"""Fit the residual model from study flights with fit-gp's library function (pure: no files)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from flightlog.schema import FlightLog
from gp.prediction_check import Predictor
from gp.residual_interval import residual_steps
from gp.training import TrainingConfig, TrainingResult, train_residual_model
from planners.nominal_models import make_model

if TYPE_CHECKING:
    from experiments.study.config import StudyConfig

FOLLOWING_MODES = ("OFFBOARD",)
CHECK_HORIZON_S = 2.0  # the NMPC's horizon, N x dt = 20 x 0.1 s ([Kulathunga23])
PLANNER_DT_S = 0.1  # the NMPC's interval [s]


def fit_residual(
    logs: Sequence[FlightLog],
    inducing: str,
    period_s: float,
    *,
    learned_model: str = "first_order_lag",
    features: str = "velocity",
    m: int = 30,
    seed: int = 0,
    restarts: int = 2,
    progress: Callable[[str], None] = lambda message: None,
    incumbent: Predictor | None = None,
    check_horizon_s: float | None = CHECK_HORIZON_S,
    planner_dt_s: float | None = PLANNER_DT_S,
    structure_params: tuple[tuple[str, float], ...] = (),
    rotate_held_out: bool = False,
) -> TrainingResult:
    """A residual model from the following phase (OFFBOARD rows) of ``logs``, flown with a
    control period of ``period_s`` [s], with ``m`` inducing points chosen by ``inducing``
    ("low_speed", "cluster" or "random"), on ``features`` (gp.features; the default is paper
    000's velocity, as StudyConfig's: a GP on the command, the NMPC's own decision variable,
    is exploited by its optimiser, see experiments.study.regimes).

    ``learned_model`` is the nominal model under the residual: "first_order_lag" has its
    time constants identified from the logs first (the model file records them);
    "kinematic_4dof" is [Kulathunga23]'s (its residual time base is one control period).
    ``structure_params`` fixes the learned model's parameters (e.g. the time constants an
    earlier fit identified) instead of identifying them from ``logs``.

    A learned model that carries the velocity measures its residual over ``planner_dt_s`` [s],
    a whole number of the logs' steps (gp.residual_interval: GPInputError if it is not one);
    with None, or under the kinematic model, over one step.

    With ``check_horizon_s`` a quarter of the logs (or of each log) is held out and the model's
    position prediction over that horizon is checked against ``incumbent`` (default: the
    nominal kinematic model); ``result.may_fly`` is the verdict (gp.prediction_check).
    ``rotate_held_out``: each log cut in time holds out a different quarter (logs of one
    repeated path, gp.prediction_check.split_logs).
    """
    params = {"residual_dt_s": period_s} if learned_model == "kinematic_4dof" else {}
    params.update(dict(structure_params))
    regular = [regular_rows(log, period_s) for log in logs]
    steps = 1
    if planner_dt_s is not None and make_model(learned_model).carries_velocity:
        steps = residual_steps(regular, planner_dt_s)
    config = TrainingConfig(
        features=features,
        nominal=learned_model,
        nominal_params=tuple(sorted(params.items())),
        inducing=inducing,
        m=m,
        restarts=restarts,
        modes=FOLLOWING_MODES,
        seed=seed,
        check_horizon_s=check_horizon_s,
        residual_steps=steps,
        check_rotate=rotate_held_out,
    )
    return train_residual_model(regular, config, progress, incumbent)


def fit_for_study(
    config: StudyConfig, logs: Sequence[FlightLog], inducing: str, **options: Any
) -> TrainingResult:
    """:func:`fit_residual` with the study's settings (the NMPC's period, learned model,
    features, m and restarts of ``config``); ``options``: its others (incumbent,
    structure_params, rotate_held_out)."""
    return fit_residual(
        logs,
        inducing,
        config.nmpc.period_s,
        learned_model=config.learned_model,
        features=config.features,
        m=config.m,
        restarts=config.gp_restarts,
        **options,
    )


def regular_rows(log: FlightLog, period_s: float, min_fraction: float = 0.5) -> FlightLog:
    """``log`` without the rows that follow their predecessor by less than ``min_fraction`` of
    a period [s] (a wall-clock loop catching up after a late tick): a residual divides by the
    step, so a near-zero step would turn telemetry jitter into a huge residual."""
    t = log["t_s"]
    keep = np.zeros(t.size, dtype=bool)
    last = -np.inf
    for i, ti in enumerate(t):
        if ti - last >= min_fraction * period_s:
            keep[i] = True
            last = ti
    if keep.all():
        return log
    return FlightLog({k: v[keep] for k, v in log.columns.items()}, log.metadata, log.path)
