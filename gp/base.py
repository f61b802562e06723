"""Shared estimator logic for independent-output GPs: validation, centring, predict."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np
from sklearn.base import BaseEstimator
from threadpoolctl import threadpool_limits

from gp.hyperopt import Hyperparameters
from gp.not_fitted import check_fitted
from gp.posterior import Posterior
from gp.validation import check_inputs, check_targets


@dataclass(frozen=True, eq=False)
class OutputFit:
    """What fitting one output produces.

    Attributes:
        hyperparameters: kernel and noise variance.
        support: (m, d) support points (inducing points or training inputs).
        alpha: (m,) mean weights; var_factor: (m, m), see :class:`Posterior`.
        objective: final objective value (log marginal likelihood or bound), nats.
    """

    hyperparameters: Hyperparameters
    support: np.ndarray
    alpha: np.ndarray
    var_factor: np.ndarray
    objective: float


class IndependentOutputGP(BaseEstimator, ABC):
    """Base of the estimators: one GP per output column, sharing inputs.

    scikit-learn's BaseEstimator supplies get_params/set_params/clone from ``__init__``.

    Fitted attributes (set by :meth:`fit`): ``n_features_in_``, ``n_outputs_``, ``kernels_``
    (tuple of SE-ARD kernels), ``noise_variances_`` (n_outputs,), ``y_offset_`` (n_outputs,),
    ``objective_`` (n_outputs,) final log marginal likelihood or bound in nats, and
    ``posterior_`` (the cached :class:`Posterior`).
    """

    center_y: bool
    random_state: int

    def fit(self, X: np.ndarray, Y: np.ndarray) -> IndependentOutputGP:
        """Fit one GP per column of ``Y``.

        Args:
            X: (n, d) inputs in feature units.
            Y: (n, n_out) targets (a 1-D Y is one output).

        Returns:
            self.
        """
        X = check_inputs(X, "X")
        Y = check_targets(Y, X.shape[0], "Y")
        offset = Y.mean(axis=0) if self.center_y else np.zeros(Y.shape[1])
        rng = np.random.default_rng(self.random_state)
        # m-sized linear algebra and k-means gain nothing from BLAS/OpenMP threads, and
        # spinning threads slow them down 10-20x when the cores are shared with other work.
        with threadpool_limits(limits=1):
            context = self._prepare(X)
            fits = [
                self._fit_output(X, Y[:, j] - offset[j], rng, context) for j in range(Y.shape[1])
            ]
        self.n_features_in_ = X.shape[1]
        self.n_outputs_ = Y.shape[1]
        self.kernels_ = tuple(f.hyperparameters.kernel for f in fits)
        self.noise_variances_ = np.array([f.hyperparameters.noise_variance for f in fits])
        self.y_offset_ = offset
        self.objective_ = np.array([f.objective for f in fits])
        self.posterior_ = Posterior(
            support=np.stack([f.support for f in fits]),
            lengthscales=np.stack([k.lengthscales for k in self.kernels_]),
            variance=np.array([k.variance for k in self.kernels_]),
            alpha=np.stack([f.alpha for f in fits]),
            var_factor=np.stack([f.var_factor for f in fits]),
            y_offset=offset.copy(),
        )
        return self

    def predict(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Latent mean and standard deviation, each (n, n_outputs), output units."""
        check_fitted(self)
        return self.posterior_.predict(X)

    def _prepare(self, X: np.ndarray) -> object:
        """Work shared by all outputs (e.g. initial inducing points), passed to _fit_output."""
        return None

    @abstractmethod
    def _fit_output(
        self, X: np.ndarray, y: np.ndarray, rng: np.random.Generator, context: object
    ) -> OutputFit:
        """Fit one centred output y (n,)."""
