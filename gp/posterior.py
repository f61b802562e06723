"""Cached GP posterior for fast repeated prediction (the object the NMPC and export use).

For independent outputs j = 1..n_out, each with its own SE-ARD kernel k_j and support points
Z_j (the inducing points of a sparse GP, or the training inputs of an exact GP):

    mean_j(x) = y_offset_j + k_j(x, Z_j) @ alpha_j
    var_j(x)  = max(variance_j - |R_j k_j(Z_j, x)|^2, 0)

``var`` is the variance of the latent function (without observation noise). The variance is kept
as a square-root factor R (Q = R^T R): |R k|^2 never exceeds the prior variance, so it is
evaluated without the large cancelling terms of k^T Q k. Everything that does not depend on x
is precomputed, so a prediction costs O(m d + m^2) per output.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gp.kernels import SquaredExponentialARD, scaled_sqdist
from gp.validation import check_inputs


@dataclass(frozen=True, eq=False)
class Posterior:
    """Posterior predictive of ``n_out`` independent GPs with ``m`` support points each.

    Attributes:
        support: Z, shape (n_out, m, d), in feature units.
        lengthscales: shape (n_out, d), feature units.
        variance: signal variances, shape (n_out,), output units squared.
        alpha: weights, shape (n_out, m), such that mean = y_offset + k(x, Z) @ alpha.
        var_factor: R, shape (n_out, m, m), such that var = variance - |R k|^2.
        y_offset: constant mean per output, shape (n_out,), output units.
    """

    support: np.ndarray
    lengthscales: np.ndarray
    variance: np.ndarray
    alpha: np.ndarray
    var_factor: np.ndarray
    y_offset: np.ndarray

    def __post_init__(self) -> None:
        n_out, m, d = self.support.shape
        shapes = {
            "lengthscales": (self.lengthscales.shape, (n_out, d)),
            "variance": (self.variance.shape, (n_out,)),
            "alpha": (self.alpha.shape, (n_out, m)),
            "var_factor": (self.var_factor.shape, (n_out, m, m)),
            "y_offset": (self.y_offset.shape, (n_out,)),
        }
        for name, (got, want) in shapes.items():
            if got != want:
                raise ValueError(f"Posterior.{name} has shape {got}, expected {want}")

    @property
    def n_features(self) -> int:
        return int(self.support.shape[2])

    @property
    def n_outputs(self) -> int:
        return int(self.support.shape[0])

    def kernel(self, j: int) -> SquaredExponentialARD:
        """The kernel of output ``j``."""
        return SquaredExponentialARD(self.lengthscales[j], float(self.variance[j]))

    def predict(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of the latent function.

        Args:
            X: (n, d) feature rows (a (d,) vector is not accepted: reshape it to (1, d)).

        Returns:
            mean (n, n_out) and std (n, n_out), output units.
        """
        X = check_inputs(X, "X", self.n_features)
        mean = np.empty((X.shape[0], self.n_outputs))
        var = np.empty_like(mean)
        for j in range(self.n_outputs):
            Kx = self.variance[j] * np.exp(
                -0.5 * scaled_sqdist(X, self.support[j], self.lengthscales[j])
            )
            mean[:, j] = self.y_offset[j] + Kx @ self.alpha[j]
            var[:, j] = self.variance[j] - ((Kx @ self.var_factor[j].T) ** 2).sum(1)
        return mean, np.sqrt(np.maximum(var, 0.0))
