"""Train a residual model from flight logs: dataset, hold-out split, SGPR fit, evaluation.

This is the library behind ``fit-gp``; it does no file I/O (logs come in as FlightLog objects,
the model goes out as a ResidualModel) and reports progress through a callback.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from flightlog.schema import FlightLog
from gp.datasets import DatasetConfig, ResidualDataset, residual_dataset
from gp.evaluation import holdout_split, residual_rmse
from gp.features import FeatureDefinition, feature_definition
from gp.inducing import InducingConfig
from gp.lag_identification import LagIdentification, identify_velocity_lag
from gp.model_io import ResidualModel
from gp.sparse_gp import SparseGP
from planners.nominal_models import make_model


@dataclass(frozen=True)
class TrainingConfig:
    """What to learn and how.

    Attributes:
        features: feature-set name (see gp.features.FEATURE_SETS).
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


@dataclass(frozen=True, eq=False)
class TrainingResult:
    """The trained model, the data it saw and its held-out figures."""

    model: ResidualModel
    train: ResidualDataset
    test: ResidualDataset
    metrics: dict[str, list[float]]


def train_residual_model(
    logs: Sequence[FlightLog],
    config: TrainingConfig,
    progress: Callable[[str], None] = lambda message: None,
) -> TrainingResult:
    """Build the dataset, hold out blocks, fit an SGPR, and evaluate on the held-out blocks."""
    features, identified = resolve_features(logs, config)
    if identified is not None:
        progress(f"identified {identified.describe()}")
    progress(f"features {features.describe()}")
    data = residual_dataset(logs, DatasetConfig(features, modes=config.modes))
    train, test = holdout_split(data, config.holdout_fraction, config.seed)
    progress(
        f"{data.n_rows} rows in {len(data.segment_names)} segments: "
        f"{train.n_rows} for training, {test.n_rows} held out"
    )
    inducing = InducingConfig(
        strategy=config.inducing,
        m=config.m,
        speed_columns=features.speed_columns or None,
        optimize_positions=config.optimize_inducing,
    )
    progress(f"fitting {len(features.outputs)} sparse GPs ({inducing.strategy}, m={inducing.m})")
    estimator = SparseGP(inducing=inducing, n_restarts=config.restarts, random_state=config.seed)
    estimator.fit(train.X, train.Y)
    mean, _ = estimator.predict(test.X)
    metrics = residual_rmse(test, mean)
    training = {**train.summary(), "held_out": test.summary(), **metrics}
    if identified is not None:
        training["identified_lag"] = identified.to_dict()
    model = ResidualModel.from_estimator(
        estimator,
        features,
        inducing={
            "strategy": inducing.strategy,
            "m": inducing.m,
            "optimize_positions": inducing.optimize_positions,
            "speed_scale_mps": inducing.speed_scale_mps,
        },
        training=training,
    )
    return TrainingResult(model, train, test, metrics)


def resolve_features(
    logs: Sequence[FlightLog], config: TrainingConfig
) -> tuple[FeatureDefinition, LagIdentification | None]:
    """The feature definition with the nominal parameters the logs decide: kinematic_4dof's
    residual_dt_s (their median step), first_order_lag's time constants when not given
    (identified; the identification is returned too, else None)."""
    params = dict(config.nominal_params)
    identified = None
    from_logs = set(make_model(config.nominal).params_from_logs) - set(params)
    if "residual_dt_s" in from_logs:
        steps = np.concatenate([np.diff(log["t_s"]) for log in logs])
        if steps.size:
            params["residual_dt_s"] = round(float(np.median(steps)), 6)
    if "tau_s" in from_logs:
        identified = identify_velocity_lag(logs, config.modes)
        params = {**identified.nominal_params(), **params}
    return feature_definition(config.features, config.nominal, **params), identified
