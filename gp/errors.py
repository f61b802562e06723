"""Errors raised by the gp package; every message is one line saying what was wrong and the fix.

NotFittedError, scikit-learn's kind, is in gp.not_fitted (it imports scikit-learn).
"""

from __future__ import annotations


class GPInputError(ValueError):
    """Inputs or targets with the wrong shape, dtype or non-finite values."""


class DatasetError(ValueError):
    """A flight log cannot be turned into a residual dataset (NaN, too short, missing column)."""


class ModelFileError(ValueError):
    """A model file is missing, corrupt, of another format version or another feature definition."""
