"""What a residual model learns and how: the settings of gp.training.train_residual_model.

Plain values only, apart from the learning's libraries, so that ``fit-gp``'s command line takes
its defaults from here and answers ``--help`` without loading them.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TrainingConfig:
    """What to learn and how.

    Attributes:
        features: feature-set name (gp.feature_sets.FEATURE_SETS).
        nominal: nominal model name (planners.nominal_models.MODELS).
        nominal_params: its parameters; for kinematic_4dof, residual_dt_s defaults to the logs'
            median step (the time base the residuals are measured over); for first_order_lag,
            missing time constants are identified from the logs (gp.lag_identification), so
            the GP learns only what the identified lag leaves.
        inducing: inducing strategy; m: number of inducing points.
        optimize_inducing: refine inducing positions on the bound.
        restarts: hyperparameter starting points.
        holdout_fraction: share of rows held out (contiguous blocks) for evaluation.
        modes: keep only these flight modes; None keeps all.
        seed: seed for selection, split and restarts.
        check_horizon_s: if set, hold out whole logs (or each log's last part, see
            gp.prediction_check.split_logs) and check the model's position prediction over this
            horizon [s] against the incumbent (default: [Kulathunga23]'s kinematic model) on
            them before it may fly; the verdict goes into the model file.
        check_fraction: share of the logs held out for that check.
        check_rotate: when each log is cut in time for that check, hold out a different part
            of each (gp.prediction_check.split_logs: logs of one repeated path).
        residual_steps: log steps the residual is measured over (gp.datasets); the planner's
            interval divided by the log step learns what one step hides under noise.
    """

    features: str = "velocity"
    nominal: str = "kinematic_4dof"
    nominal_params: tuple[tuple[str, float], ...] = ()
    inducing: str = "low_speed"
    m: int = 30
    optimize_inducing: bool = False
    restarts: int = 3
    holdout_fraction: float = 0.2
    modes: tuple[str, ...] | None = None
    seed: int = 0
    check_horizon_s: float | None = None
    check_fraction: float = 0.25
    check_rotate: bool = False
    residual_steps: int = 1
