"""Train a residual model from flight logs: dataset, hold-out split, SGPR fit, evaluation.

This is the library behind ``fit-gp``; it does no file I/O (logs come in as FlightLog objects,
the model goes out as a ResidualModel) and reports progress through a callback.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from flightlog.schema import FlightLog
from flightlog.velocity_loop_gains import velocity_loop_gains
from gp.datasets import DatasetConfig, ResidualDataset, residual_dataset
from gp.evaluation import holdout_split, residual_rmse
from gp.features import FeatureDefinition, feature_definition
from gp.inducing import InducingConfig
from gp.lag_identification import LagIdentification, identify_velocity_lag
from gp.model_io import ResidualModel
from gp.noise_optimum import all_noise_note, all_noise_outputs
from gp.prediction_check import (
    PredictionCheck,
    Predictor,
    check_prediction,
    split_logs,
    structure_only,
)
from gp.sparse_gp import SparseGP
from gp.training_config import TrainingConfig
from gp.velocity_integrator import VELOCITY_LOOP_GAIN_NAMES, logged_velocity_loop_gains
from planners.nominal_models import kinematic_4dof, make_model


@dataclass(frozen=True, eq=False)
class TrainingResult:
    """The trained model, the data it saw, its held-out figures and, when checked, the
    multi-step prediction verdict against the incumbent (``check.passed``: it may fly);
    ``all_noise``: one line when some output's GP explains nothing but noise
    (gp.noise_optimum), else None."""

    model: ResidualModel
    train: ResidualDataset
    test: ResidualDataset
    metrics: dict[str, list[float]]
    check: PredictionCheck | None = None
    structure_check: PredictionCheck | None = None
    all_noise: str | None = None

    @property
    def may_fly(self) -> bool:
        """False only if a check was made and the model did not beat the incumbent."""
        return self.check is None or self.check.passed

    @property
    def gp_earns_its_place(self) -> bool:
        """False only if checked and the GP does not beat its own nominal model alone (the
        identified structure): then the structure should fly without it."""
        return self.structure_check is None or self.structure_check.passed

    @property
    def flown(self) -> Literal["nominal", "structure", "learned"]:
        """What the companion's planner flies with this model: the nominal planner (the
        learned model refused), its structure alone (the GP does not beat it, or a closed-loop
        check recorded in the model chose it) or the learned model, structure plus GP."""
        if not self.may_fly:
            return "nominal"
        if not self.gp_earns_its_place or structure_only(self.model):
            return "structure"
        return "learned"


def train_residual_model(
    logs: Sequence[FlightLog],
    config: TrainingConfig,
    progress: Callable[[str], None] = lambda message: None,
    incumbent: Predictor | None = None,
) -> TrainingResult:
    """Build the dataset, hold out blocks, fit an SGPR, and evaluate on the held-out blocks;
    with ``config.check_horizon_s``, check it against ``incumbent`` on held-out logs."""
    check_logs: list[FlightLog] = []
    if config.check_horizon_s is not None:
        logs, check_logs = split_logs(
            logs, config.check_fraction, config.modes, config.check_rotate
        )
    features, identified = resolve_features(logs, config, progress)
    if identified is not None:
        progress(f"identified {identified.describe()}")
    progress(f"features {features.describe()}")
    data = residual_dataset(logs, DatasetConfig(features, modes=config.modes))
    train, test = holdout_split(data, config.holdout_fraction, config.seed)
    progress(
        f"{data.n_rows} rows in {len(data.segment_names)} "
        f"segment{'' if len(data.segment_names) == 1 else 's'}: "
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
    signal = np.array([kernel.variance for kernel in estimator.kernels_])
    noise = estimator.noise_variances_
    all_noise = all_noise_note(features.outputs, signal, noise)
    if all_noise is not None:
        found = all_noise_outputs(signal, noise)
        training["all_noise_outputs"] = [features.outputs[i] for i in found]
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
    check = alone = None
    if check_logs:
        horizon = float(config.check_horizon_s)
        candidate = Predictor.of_residual_model(model, f"learned ({features.nominal_model} + GP)")
        base = incumbent or Predictor("nominal kinematic_4dof", kinematic_4dof())
        check = check_prediction(candidate, base, check_logs, horizon, config.modes)
        progress(check.describe())
        training["prediction_check"] = check.to_dict()
        if features.nominal().carries_velocity:
            structure = Predictor(f"{features.nominal_model} alone", features.nominal())
            alone = check_prediction(candidate, structure, check_logs, horizon, config.modes)
            progress(alone.describe())
            training["prediction_check_structure"] = alone.to_dict()
        model = ResidualModel.from_estimator(estimator, features, model.inducing, training)
    return TrainingResult(model, train, test, metrics, check, alone, all_noise)


def resolve_features(
    logs: Sequence[FlightLog],
    config: TrainingConfig,
    progress: Callable[[str], None] = lambda message: None,
) -> tuple[FeatureDefinition, LagIdentification | None]:
    """The feature definition with the nominal parameters the logs decide: kinematic_4dof's
    residual_dt_s (their median step), first_order_lag's time constants when not given
    (identified; the identification is returned too, else None), px4_velocity_pi's gains when
    not given (the autopilot's, recorded with the logs; ``progress`` is told where each log's
    came from)."""
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
    gains = from_logs & set(VELOCITY_LOOP_GAIN_NAMES)
    if gains:
        logged = logged_velocity_loop_gains(logs)
        params |= {n: v for n, v in logged.items() if n in gains}
        for log in logs:
            progress(f"velocity-loop gains of {log.where}: {velocity_loop_gains(log).source}")
    definition = feature_definition(
        config.features, config.nominal, residual_steps=config.residual_steps, **params
    )
    return definition, identified
