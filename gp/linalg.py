"""Cholesky factorisation with a jitter that grows until the matrix is numerically positive."""

from __future__ import annotations

import numpy as np
from scipy import linalg

from gp.errors import GPInputError

_MAX_TRIES = 6


def jittered_cholesky(K: np.ndarray, jitter: float) -> tuple[np.ndarray, float]:
    """Lower Cholesky factor of ``K + jitter * I`` (K (m, m) symmetric).

    The jitter is multiplied by 10 (up to 5 times) while factorisation fails.

    Returns:
        (L, jitter_used): L (m, m) lower triangular with L @ L.T = K + jitter_used * I.
    """
    eye = np.eye(K.shape[0])
    for _ in range(_MAX_TRIES):
        try:
            return linalg.cholesky(K + jitter * eye, lower=True, check_finite=False), jitter
        except linalg.LinAlgError:
            jitter *= 10.0
    raise GPInputError(
        f"covariance matrix is not positive definite even with jitter {jitter:.1e}; "
        "remove duplicate inputs or increase the noise variance"
    )


def solve_lower(L: np.ndarray, B: np.ndarray) -> np.ndarray:
    """L^-1 B for lower-triangular L."""
    return linalg.solve_triangular(L, B, lower=True, check_finite=False)


def solve_upper_t(L: np.ndarray, B: np.ndarray) -> np.ndarray:
    """L^-T B for lower-triangular L."""
    return linalg.solve_triangular(L, B, lower=True, trans="T", check_finite=False)
