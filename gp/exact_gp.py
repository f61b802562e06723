"""Exact GP regression with an SE-ARD kernel and Gaussian noise, O(n^3): the reference model.

Used for small data sets (local GPs over experience bins) and as the ground truth the sparse
model is tested against.
"""

from __future__ import annotations

import numpy as np
from scipy import linalg

from gp.base import IndependentOutputGP, OutputFit
from gp.hyperopt import DataScales, Objective, ObjectiveValue, maximize, start_from
from gp.kernels import SquaredExponentialARD, se_ard_gradients
from gp.linalg import jittered_cholesky, solve_lower
from gp.not_fitted import check_fitted

_LOG_2PI = float(np.log(2.0 * np.pi))


def exact_log_marginal_likelihood(
    X: np.ndarray,
    y: np.ndarray,
    kernel: SquaredExponentialARD,
    noise_variance: float,
    support: np.ndarray | None = None,
) -> ObjectiveValue:
    """log N(y | 0, K + s2 I) and its gradients wrt the log hyperparameters.

    Args:
        X: (n, d) inputs; y: (n,) targets; kernel: SE-ARD; noise_variance: s2 > 0.
        support: ignored (present so the signature matches the sparse bound's).

    Returns:
        ObjectiveValue in nats (grad_support is None).
    """
    n = y.shape[0]
    K = kernel(X, X)
    L, _ = jittered_cholesky(K, noise_variance)
    alpha = linalg.cho_solve((L, True), y, check_finite=False)
    value = -0.5 * float(y @ alpha) - np.log(np.diag(L)).sum() - 0.5 * n * _LOG_2PI
    W = np.outer(alpha, alpha) - linalg.cho_solve((L, True), np.eye(n), check_finite=False)
    gl, gv, _ = se_ard_gradients(0.5 * W, K, X, X, kernel.lengthscales)
    return ObjectiveValue(float(value), gl, gv, 0.5 * noise_variance * float(np.trace(W)))


def exact_posterior(
    X: np.ndarray, y: np.ndarray, kernel: SquaredExponentialARD, noise_variance: float
) -> tuple[np.ndarray, np.ndarray]:
    """alpha = (K + s2 I)^-1 y (n,) and R = L^-1 (n, n), L = chol(K + s2 I), so that
    R^T R = (K + s2 I)^-1; see :class:`Posterior`."""
    L, _ = jittered_cholesky(kernel(X, X), noise_variance)
    alpha = linalg.cho_solve((L, True), y, check_finite=False)
    return alpha, solve_lower(L, np.eye(X.shape[0]))


class ExactGP(IndependentOutputGP):
    """Exact GP regression, one GP per output, hyperparameters by maximising the evidence.

    Args (keyword-only, stored unchanged):
        kernel: initial (or, with ``optimize=False``, fixed) SE-ARD kernel; None derives one
            from the data scales.
        noise_variance: initial or fixed noise variance, output units squared; None: 10 % of
            the target variance.
        optimize: maximise the log marginal likelihood with L-BFGS-B.
        n_restarts: starting points (the first is the given/derived guess, others seeded random).
        max_iter: L-BFGS-B iterations per start.
        tol: relative improvement of the evidence below which L-BFGS-B stops.
        center_y: use the training mean of each output as a constant prior mean.
        random_state: seed for the restarts.
    """

    def __init__(
        self,
        *,
        kernel: SquaredExponentialARD | None = None,
        noise_variance: float | None = None,
        optimize: bool = True,
        n_restarts: int = 3,
        max_iter: int = 200,
        tol: float = 1e-9,
        center_y: bool = True,
        random_state: int = 0,
    ) -> None:
        self.kernel = kernel
        self.noise_variance = noise_variance
        self.optimize = optimize
        self.n_restarts = n_restarts
        self.max_iter = max_iter
        self.tol = tol
        self.center_y = center_y
        self.random_state = random_state

    def log_marginal_likelihood(self) -> np.ndarray:
        """Log evidence per output at the fitted hyperparameters, (n_outputs,) nats."""
        check_fitted(self)
        return self.objective_.copy()

    def _fit_output(
        self, X: np.ndarray, y: np.ndarray, rng: np.random.Generator, context: object
    ) -> OutputFit:
        scales = DataScales.of(X, y)
        start = start_from(self.kernel, self.noise_variance, scales)
        objective = exact_log_marginal_likelihood_of(X, y)
        hyp, value = start, objective(start.kernel, start.noise_variance, None).value
        if self.optimize:
            starts = [start, *scales.initial_guesses(self.n_restarts, rng)[1:]]
            runs = [
                maximize(objective, s, scales, max_iter=self.max_iter, rel_tol=self.tol)
                for s in starts
            ]
            hyp, _, value = max(runs, key=lambda r: r[2])
        alpha, R = exact_posterior(X, y, hyp.kernel, hyp.noise_variance)
        return OutputFit(hyp, X.copy(), alpha, R, value)


def exact_log_marginal_likelihood_of(X: np.ndarray, y: np.ndarray) -> Objective:
    """The objective closure (kernel, noise, support) -> ObjectiveValue for fixed data."""
    return lambda kern, noise, _z: exact_log_marginal_likelihood(X, y, kern, noise)
