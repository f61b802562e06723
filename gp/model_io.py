"""Versioned residual-model files: one self-describing ``MODEL.npz``.

The file holds the cached posterior's arrays and a ``header`` entry: a JSON document recording
the format and its version, the model type, the feature definition (with the nominal model and
its parameters), hyperparameters per output, the inducing-point choice and a training-data
summary. It is written atomically (a reader never sees half a model) and read without pickle.
Loading checks the format version and, if the caller says which features it will feed, that
they are the ones the model was trained on.
"""

from __future__ import annotations

import io
import json
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from flightlog.atomic_output import write_bytes_atomic
from gp.batched_mean import BatchedMean
from gp.casadi_export import posterior_function
from gp.errors import ModelFileError
from gp.features import FeatureDefinition
from gp.posterior import Posterior

if TYPE_CHECKING:  # a model file flies without the estimators (and scikit-learn) loaded
    from gp.base import IndependentOutputGP

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

    def flight_mean_function(
        self, bound_std: float = RESIDUAL_BOUND_STD, expand: bool = True
    ) -> ca.Function:
        """The mean g(z) as it flies: clipped per axis to the training residuals' mean
        +- ``bound_std`` std (the training summary's residual_mean/std), so that a badly
        conditioned fit cannot command the vehicle with residuals it never saw. Unclipped if
        the summary is missing. ``expand``: an SX Function (scalar operations); else MX, dense
        matrix operations, about 3x faster to evaluate point by point (a rollout) and expanded
        to the same SX wherever it is called with SX arguments."""
        mean_fn = self.casadi_function(include_variance=False)
        if expand:
            mean_fn = mean_fn.expand()
        mean = self.training.get("residual_mean")
        std = self.training.get("residual_std")
        if mean is None or std is None:
            return mean_fn
        lo = np.asarray(mean, dtype=float) - bound_std * np.asarray(std, dtype=float)
        hi = np.asarray(mean, dtype=float) + bound_std * np.asarray(std, dtype=float)
        z = (ca.SX if expand else ca.MX).sym("z", mean_fn.numel_in(0))
        g = ca.fmin(ca.fmax(mean_fn(z), ca.DM(lo)), ca.DM(hi))
        return ca.Function("gp_residual_bounded", [z], [g], ["z"], ["mean"])

    def flight_mean_batch(self, bound_std: float = RESIDUAL_BOUND_STD) -> BatchedMean:
        """The mean of :meth:`flight_mean_function` (the same clipping) and its Jacobian,
        evaluated in NumPy at many feature rows at once (the NMPC fast path's linearisation)."""
        mean = self.training.get("residual_mean")
        std = self.training.get("residual_std")
        if mean is None or std is None:
            return BatchedMean(self.posterior)
        mean, std = np.asarray(mean, dtype=float), np.asarray(std, dtype=float)
        return BatchedMean(self.posterior, mean - bound_std * std, mean + bound_std * std)

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


MODEL_SUFFIX = ".npz"


def model_path(path: str | Path) -> Path:
    """The model file for ``path``: ``out/model``, ``out/model.npz`` -> ``out/model.npz``."""
    p = Path(path)
    return p if p.suffix == MODEL_SUFFIX else p.with_name(p.name + MODEL_SUFFIX)


def save_model(path: str | Path, model: ResidualModel) -> Path:
    """Write the model as one file (atomically); returns its path.

    Raises:
        OutputError: the file cannot be written there (one line).
    """
    out = model_path(path)
    buffer = io.BytesIO()
    np.savez(
        buffer,
        header=np.array(json.dumps(model.to_dict(), indent=2)),
        noise_variance=model.noise_variance,
        **{k: getattr(model.posterior, k) for k in _ARRAYS},
    )
    return write_bytes_atomic(out, buffer.getvalue())


def read_model_header(path: str | Path) -> dict[str, object]:
    """The JSON header of a model file (what it is, how it was trained).

    Raises:
        ModelFileError: one line saying what is wrong (missing, corrupt, not a model file).
    """
    return _read(model_path(path))[0]


def _read(path: Path) -> tuple[dict[str, object], dict[str, np.ndarray]]:
    given = path.with_suffix("")  # what was passed, when model_path added the suffix
    if not path.is_file() and given.is_file():
        raise ModelFileError(
            f"{given}: not a model file (a model is the {MODEL_SUFFIX} file fit-gp writes); "
            "pass that file, or fit one with fit-gp"
        )
    if not path.is_file():
        old = path.with_suffix(".json")
        hint = (
            f"; {old.name} is an older two-file model: refit it with fit-gp"
            if old.is_file()
            else "; train one with fit-gp"
        )
        raise ModelFileError(f"{path}: no such model file{hint}")
    try:
        with path.open("rb") as fh:
            if fh.read(2) != b"PK":  # np.load would take an .npy or any other bytes too
                raise ValueError(f"not a {MODEL_SUFFIX} archive as fit-gp writes")
        with np.load(path, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
    except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
        reason = "holds Python objects" if "pickle" in str(exc) else str(exc)
        raise ModelFileError(
            f"{path}: not a readable model file ({reason}); refit with fit-gp"
        ) from None
    if "header" not in arrays:
        raise ModelFileError(f"{path}: no model header inside; refit with fit-gp")
    try:
        doc = json.loads(str(arrays.pop("header")))
    except json.JSONDecodeError as exc:
        raise ModelFileError(
            f"{path}: model header is not valid JSON ({exc.msg}); refit with fit-gp"
        ) from None
    return doc, arrays


def load_model(path: str | Path, expected: FeatureDefinition | None = None) -> ResidualModel:
    """Read a model file.

    Args:
        path: the model file (or its path without suffix).
        expected: the feature definition the caller will feed; a different one is an error.

    Raises:
        ModelFileError: one line saying what is wrong (missing, corrupt, version, features).
    """
    path = model_path(path)
    doc, arrays = _read(path)
    if doc.get("format") != FORMAT or doc.get("format_version") != FORMAT_VERSION:
        raise ModelFileError(
            f"{path}: format {doc.get('format')!r} version {doc.get('format_version')!r}, "
            f"this reader understands {FORMAT!r} version {FORMAT_VERSION}; refit with fit-gp"
        )
    try:
        features = FeatureDefinition.from_dict(doc["feature_definition"])
        posterior = Posterior(**{k: arrays[k] for k in _ARRAYS})
        noise = arrays["noise_variance"]
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(
            f"{path}: incomplete or corrupt model ({exc}); refit with fit-gp"
        ) from None
    if expected is not None and expected != features:
        raise ModelFileError(
            f"{path}: trained on features {features.describe()}, but the caller expects "
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
