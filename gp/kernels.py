"""Squared-exponential kernel with automatic relevance determination (SE-ARD).

    k(a, b) = variance * exp(-0.5 * sum_d (a_d - b_d)^2 / lengthscales_d^2)

Lengthscales are in the units of each input feature (m/s for velocities); ``variance`` is the
signal variance in output units squared ((m/s^2)^2 for acceleration residuals). Optimisers work
on the log parameters ``[log lengthscales (d), log variance]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class SquaredExponentialARD:
    """SE-ARD kernel.

    Attributes:
        lengthscales: shape (d,), > 0, one per input feature, in that feature's units.
        variance: signal variance > 0, output units squared.
    """

    lengthscales: np.ndarray
    variance: float

    def __post_init__(self) -> None:
        ls = np.atleast_1d(np.asarray(self.lengthscales, dtype=np.float64))
        if ls.ndim != 1 or not np.all(np.isfinite(ls)) or np.any(ls <= 0):
            raise ValueError(f"lengthscales must be a 1-D array of positive numbers, got {ls}")
        if not (np.isfinite(self.variance) and self.variance > 0):
            raise ValueError(f"variance must be a positive number, got {self.variance}")
        ls.setflags(write=False)
        object.__setattr__(self, "lengthscales", ls)
        object.__setattr__(self, "variance", float(self.variance))

    @property
    def n_features(self) -> int:
        return int(self.lengthscales.shape[0])

    def __call__(self, A: np.ndarray, B: np.ndarray) -> np.ndarray:
        """Covariance matrix K(A, B), A (p, d), B (q, d) -> (p, q).

        Uses |a|^2 + |b|^2 - 2 a.b (one matrix product; absolute error ~1e-15 * |a|^2), the
        fast form for training; :func:`scaled_sqdist` is the exact form used for prediction.
        """
        a = A / self.lengthscales
        b = B / self.lengthscales
        d2 = a @ b.T
        d2 *= -2.0
        d2 += (a * a).sum(1)[:, None]
        d2 += (b * b).sum(1)[None, :]
        np.maximum(d2, 0.0, out=d2)
        d2 *= -0.5
        np.exp(d2, out=d2)
        d2 *= self.variance
        return d2

    def diag(self, A: np.ndarray) -> np.ndarray:
        """k(a_i, a_i) for each row of A (p, d) -> (p,)."""
        return np.full(A.shape[0], self.variance)

    def log_params(self) -> np.ndarray:
        """``[log lengthscales, log variance]``, shape (d + 1,)."""
        return np.concatenate([np.log(self.lengthscales), [np.log(self.variance)]])

    @classmethod
    def from_log_params(cls, theta: np.ndarray) -> SquaredExponentialARD:
        """Inverse of :meth:`log_params`."""
        theta = np.asarray(theta, dtype=np.float64)
        return cls(np.exp(theta[:-1]), float(np.exp(theta[-1])))


def scaled_sqdist(A: np.ndarray, B: np.ndarray, lengthscales: np.ndarray) -> np.ndarray:
    """Squared distances sum_d (a_d - b_d)^2 / l_d^2, A (p, d), B (q, d) -> (p, q), >= 0."""
    d2 = np.zeros((A.shape[0], B.shape[0]))
    for j, ell in enumerate(lengthscales):
        diff = (A[:, j, None] - B[None, :, j]) / ell
        d2 += diff * diff
    return d2


def se_ard_gradients(
    G: np.ndarray, K: np.ndarray, A: np.ndarray, B: np.ndarray, lengthscales: np.ndarray
) -> tuple[np.ndarray, float, np.ndarray]:
    """Chain rule through K = k(A, B) for an objective F with dF/dK = G.

    Args:
        G: dF/dK, shape (p, q).
        K: k(A, B), shape (p, q) (a jitter on the diagonal of k(A, A) is allowed: it scales
            with the variance and does not change the other gradients).
        A: (p, d) first argument; B: (q, d) second argument.
        lengthscales: (d,).

    Returns:
        dF/dlog(lengthscales) (d,), dF/dlog(variance) (scalar), dF/dA (p, d) with B held fixed.
    """
    return se_ard_gradients_from_sums(A, *se_ard_gradient_sums(G * K, B), lengthscales)


def se_ard_gradient_sums(H: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sufficient sums of H = G * K over the columns (rows of B), additive over column blocks.

    Returns:
        h_rows = H.sum(1) (p,), col_sq = H.sum(0) @ B**2 (d,), HB = H @ B (p, d).
    """
    return H.sum(1), H.sum(0) @ (B * B), H @ B


def se_ard_gradients_from_sums(
    A: np.ndarray,
    h_rows: np.ndarray,
    col_sq: np.ndarray,
    HB: np.ndarray,
    lengthscales: np.ndarray,
) -> tuple[np.ndarray, float, np.ndarray]:
    """Finish :func:`se_ard_gradients` from (possibly block-accumulated) sums."""
    inv_l2 = 1.0 / lengthscales**2
    sq = h_rows @ (A * A) + col_sq - 2.0 * (A * HB).sum(0)
    return sq * inv_l2, float(h_rows.sum()), -(A * h_rows[:, None] - HB) * inv_l2
