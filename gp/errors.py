"""Errors raised by the gp package; every message is one line saying what was wrong and the fix."""

from __future__ import annotations

from sklearn.exceptions import NotFittedError as _SklearnNotFittedError


class NotFittedError(_SklearnNotFittedError):
    """A model was used before ``fit`` (a scikit-learn NotFittedError: ValueError and
    AttributeError)."""


class GPInputError(ValueError):
    """Inputs or targets with the wrong shape, dtype or non-finite values."""


class DatasetError(ValueError):
    """A flight log cannot be turned into a residual dataset (NaN, too short, missing column)."""


class ModelFileError(ValueError):
    """A model file is missing, corrupt, of another format version or another feature definition."""
