"""Versioned residual-model files: ``MODEL.json`` (description) + ``MODEL.npz`` (arrays).

The JSON records the format and its version, the model type, the feature definition (with the
nominal model and its parameters), hyperparameters per output, the inducing-point choice, a
training-data summary and the name of the array file. The arrays are the cached posterior.
Loading checks the format version and, if the caller says which features it will feed, that
they are the ones the model was trained on.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from gp.base import IndependentOutputGP
from gp.casadi_export import posterior_function
from gp.errors import ModelFileError
from gp.features import FeatureDefinition
from gp.posterior import Posterior

FORMAT = "residual-gp"
FORMAT_VERSION = 1
RESIDUAL_BOUND_STD = 4.0
_ARRAYS = ("support", "lengthscales", "variance", "alpha", "var_factor", "y_offset")


@dataclass(frozen=True, eq=False)
class ResidualModel:
    """A trained residual model as the planner and the companion use it.

    Attributes:
        features: what the input vector holds and which nominal model the residual corrects.
        posterior: the cached posterior (n_out = len(features.outputs)).
        noise_variance: (n_out,) observation noise of the training residuals, output units^2.
        model_type: "sgpr" or "exact".
        inducing: how the support points were chosen (strategy, m, ...), JSON-ready.
        training: training-data summary and evaluation figures, JSON-ready.
    """

    features: FeatureDefinition
    posterior: Posterior
    noise_variance: np.ndarray
    model_type: str
    inducing: Mapping[str, object] = field(default_factory=dict)
    training: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        got = (self.posterior.n_features, self.posterior.n_outputs)
        want = (self.features.n_features, len(self.features.outputs))
        if got != want:
            raise ModelFileError(
                f"posterior has (inputs, outputs) = {got} but feature set {self.features.name!r} "
                f"has {want}; fit the model on data built with this feature definition"
            )

    @classmethod
    def from_estimator(
        cls,
        estimator: IndependentOutputGP,
        features: FeatureDefinition,
        inducing: Mapping[str, object] | None = None,
        training: Mapping[str, object] | None = None,
    ) -> ResidualModel:
        """Wrap a fitted ExactGP or SparseGP."""
        model_type = "sgpr" if hasattr(estimator, "inducing_points_") else "exact"
        return cls(
            features,
            estimator.posterior_,
            np.asarray(estimator.noise_variances_, dtype=float),
            model_type,
            dict(inducing or {}),
            dict(training or {}),
        )

    def predict(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual mean and std, (n, n_out) each, for feature rows X (n, d)."""
        return self.posterior.predict(X)

    def casadi_function(self, include_variance: bool = True) -> ca.Function:
        """CasADi Function z (d,) -> mean (n_out,), var (n_out,); z in ``features.input_names``
        order."""
        return posterior_function(self.posterior, include_variance=include_variance)

    def flight_mean_function(self, bound_std: float = RESIDUAL_BOUND_STD) -> ca.Function:
        """The mean g(z) as it flies (SX): clipped per axis to the training residuals' mean
        +- ``bound_std`` std (the training summary's residual_mean/std), so that a badly
        conditioned fit cannot command the vehicle with residuals it never saw. Unclipped if
        the summary is missing."""
        mean_fn = self.casadi_function(include_variance=False).expand()
        mean = self.training.get("residual_mean")
        std = self.training.get("residual_std")
        if mean is None or std is None:
            return mean_fn
        lo = np.asarray(mean, dtype=float) - bound_std * np.asarray(std, dtype=float)
        hi = np.asarray(mean, dtype=float) + bound_std * np.asarray(std, dtype=float)
        z = ca.SX.sym("z", mean_fn.numel_in(0))
        g = ca.fmin(ca.fmax(mean_fn(z), ca.DM(lo)), ca.DM(hi))
        return ca.Function("gp_residual_bounded", [z], [g], ["z"], ["mean"])

    def to_dict(self) -> dict[str, object]:
        return {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "model_type": self.model_type,
            "feature_definition": self.features.to_dict(),
            "hyperparameters": [
                {
                    "output": name,
                    "lengthscales": self.posterior.lengthscales[j].tolist(),
                    "signal_variance": float(self.posterior.variance[j]),
                    "noise_variance": float(self.noise_variance[j]),
                    "mean_offset": float(self.posterior.y_offset[j]),
                }
                for j, name in enumerate(self.features.outputs)
            ],
            "inducing": dict(self.inducing),
            "training_data": dict(self.training),
        }


def model_paths(path: str | Path) -> tuple[Path, Path]:
    """(json, npz) paths of a model: ``out/model`` or ``out/model.json`` -> model.json/.npz."""
    p = Path(path)
    stem = p.with_suffix("") if p.suffix == ".json" else p
    return stem.with_name(stem.name + ".json"), stem.with_name(stem.name + ".npz")


def save_model(path: str | Path, model: ResidualModel) -> Path:
    """Write the model's JSON and arrays; returns the JSON path."""
    json_path, npz_path = model_paths(path)
    json_path.parent.mkdir(parents=True, exist_ok=True)
    doc = model.to_dict()
    doc["arrays"] = npz_path.name
    np.savez(
        npz_path,
        noise_variance=model.noise_variance,
        **{k: getattr(model.posterior, k) for k in _ARRAYS},
    )
    json_path.write_text(json.dumps(doc, indent=2) + "\n")
    return json_path


def load_model(path: str | Path, expected: FeatureDefinition | None = None) -> ResidualModel:
    """Read a model file.

    Args:
        path: the JSON file (or its path without suffix).
        expected: the feature definition the caller will feed; a different one is an error.

    Raises:
        ModelFileError: one line saying what is wrong (missing, corrupt, version, features).
    """
    json_path, _ = model_paths(path)
    if not json_path.is_file():
        raise ModelFileError(f"{json_path}: no such model file; train one with fit-gp")
    try:
        doc = json.loads(json_path.read_text())
    except json.JSONDecodeError as exc:
        raise ModelFileError(
            f"{json_path}: not valid JSON ({exc.msg} at line {exc.lineno})"
        ) from None
    if doc.get("format") != FORMAT or doc.get("format_version") != FORMAT_VERSION:
        raise ModelFileError(
            f"{json_path}: format {doc.get('format')!r} version {doc.get('format_version')!r}, "
            f"this reader understands {FORMAT!r} version {FORMAT_VERSION}; refit with fit-gp"
        )
    try:
        features = FeatureDefinition.from_dict(doc["feature_definition"])
        npz_path = json_path.with_name(doc["arrays"])
        with np.load(npz_path) as arrays:
            posterior = Posterior(**{k: arrays[k] for k in _ARRAYS})
            noise = arrays["noise_variance"]
    except (KeyError, TypeError, ValueError, OSError) as exc:
        raise ModelFileError(
            f"{json_path}: incomplete or corrupt model ({exc}); refit with fit-gp"
        ) from None
    if expected is not None and expected != features:
        raise ModelFileError(
            f"{json_path}: trained on features {features.describe()}, but the caller expects "
            f"{expected.describe()}; refit with matching --features/--nominal or load another model"
        )
    return ResidualModel(
        features,
        posterior,
        noise,
        str(doc["model_type"]),
        doc.get("inducing", {}),
        doc.get("training_data", {}),
    )
