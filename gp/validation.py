"""Input checks shared by the GP estimators: shapes, dtype and finiteness, one-line errors."""

from __future__ import annotations

import numpy as np

from gp.errors import GPInputError


def check_inputs(X: object, name: str = "X", n_features: int | None = None) -> np.ndarray:
    """Return ``X`` as a float64 array of shape (n, d), or raise GPInputError.

    A 1-D array is accepted only when ``n_features`` is 1 (then it is read as one column).
    """
    try:
        arr = np.asarray(X, dtype=np.float64)
    except (TypeError, ValueError):
        raise GPInputError(f"{name} must be numeric, got {type(X).__name__}") from None
    if arr.ndim == 1 and n_features == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise GPInputError(
            f"{name} must be 2-D of shape (n_samples, n_features), got shape {arr.shape}; "
            "reshape a single sample with x.reshape(1, -1)"
        )
    if arr.shape[0] == 0:
        raise GPInputError(f"{name} has no rows; pass at least one sample")
    if n_features is not None and arr.shape[1] != n_features:
        raise GPInputError(
            f"{name} has {arr.shape[1]} features but the model was fitted with {n_features}; "
            "pass features in the model's feature order"
        )
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        i, j = bad[0]
        raise GPInputError(
            f"{name}[{i}, {j}] is {arr[i, j]}; remove or impute non-finite values before calling"
        )
    return arr


def check_targets(Y: object, n_samples: int, name: str = "Y") -> np.ndarray:
    """Return ``Y`` as float64 of shape (n_samples, n_outputs); a 1-D Y becomes one column."""
    if np.ndim(Y) == 1:
        Y = np.asarray(Y)[:, None]
    arr = check_inputs(Y, name)
    if arr.shape[0] != n_samples:
        raise GPInputError(
            f"{name} has {arr.shape[0]} rows but X has {n_samples}; pass one target row per sample"
        )
    return arr
