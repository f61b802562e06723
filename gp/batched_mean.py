"""The posterior mean and its Jacobian at many feature rows at once, in NumPy.

The NMPC's fast path linearises the model at every node of its horizon; evaluating the GP
there as a symbolic CasADi graph (expanded per node, per RK4 stage and per derivative
direction) costs tens of milliseconds for m = 60 points on 5 features, and compiling that
graph to C minutes per model. The SE-ARD mean and its gradient are a few dense array
operations over all rows together (O(n m d) per output), with the posterior's arrays as data:
no graph, nothing to compile, the same code for every model.

    mean_j(z) = y_offset_j + sum_i alpha_ji s_j^2 exp(-0.5 |(z - Z_ji) / l_j|^2)
    d mean_j / d z = -sum_i alpha_ji k_ji (z - Z_ji) / l_j^2

optionally clipped per output to [lower_j, upper_j] (zero gradient where clipped), as
:meth:`gp.model_io.ResidualModel.flight_mean_function` clips the mean that flies.
"""

from __future__ import annotations

import numpy as np

from gp.posterior import Posterior


class BatchedMean:
    """z (n, d) -> (mean (n, n_out), Jacobian (n, n_out, d)) of a posterior's mean.

    Args:
        posterior: the cached posterior (support, lengthscales, variance, alpha, y_offset).
        lower, upper: (n_out,) clipping bounds in output units, or None for an unclipped mean.
    """

    def __init__(
        self,
        posterior: Posterior,
        lower: np.ndarray | None = None,
        upper: np.ndarray | None = None,
    ) -> None:
        self._support = np.asarray(posterior.support, dtype=float)  # (n_out, m, d)
        self._inv_l = 1.0 / np.asarray(posterior.lengthscales, dtype=float)  # (n_out, d)
        self._weights = (
            np.asarray(posterior.alpha, dtype=float)
            * np.asarray(posterior.variance, dtype=float)[:, None]
        )  # alpha_ji s_j^2, (n_out, m)
        self._offset = np.asarray(posterior.y_offset, dtype=float)
        scaled = self._support * self._inv_l[:, None, :]  # Z / l, (n_out, m, d)
        self._scaled_support_t = np.transpose(scaled, (0, 2, 1))  # (n_out, d, m)
        self._support_sq = np.sum(scaled * scaled, axis=2)  # |Z / l|^2, (n_out, m)
        self._lower = None if lower is None else np.asarray(lower, dtype=float)
        self._upper = None if upper is None else np.asarray(upper, dtype=float)

    def __call__(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean (n, n_out) and its Jacobian d mean / d z (n, n_out, d) at rows z (n, d).

        In scaled coordinates (z / l) the squared distances are |z|^2 - 2 z.Z + |Z|^2 and
        sum_i w_i (z - Z_i) = z sum_i w_i - w @ Z: small matrix products, no (n, m, d) arrays.
        """
        z = np.asarray(z, dtype=float)
        zs = z[None, :, :] * self._inv_l[:, None, :]  # (o, n, d)
        sq = (
            np.sum(zs * zs, axis=2)[:, :, None]
            - 2.0 * zs @ self._scaled_support_t
            + self._support_sq[:, None, :]
        )  # (o, n, m)
        weighted = self._weights[:, None, :] * np.exp(-0.5 * np.maximum(sq, 0.0))
        mean = (self._offset[:, None] + np.sum(weighted, axis=2)).T  # (n, o)
        pulled = z[None, :, :] * np.sum(weighted, axis=2)[:, :, None] - weighted @ self._support
        jac = np.transpose(-pulled * self._inv_l[:, None, :] ** 2, (1, 0, 2))  # (n, o, d)
        if self._lower is not None and self._upper is not None:
            clipped = (mean < self._lower) | (mean > self._upper)
            mean = np.clip(mean, self._lower, self._upper)
            jac = np.where(clipped[:, :, None], 0.0, jac)
        return mean, jac
