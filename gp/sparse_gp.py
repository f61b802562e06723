"""Sparse variational GP regression (SGPR, Titsias 2009), one GP per output column.

Fitting, per output:
1. inducing points from the configured strategy (shared start for all outputs);
2. ``n_restarts`` L-BFGS-B runs on the collapsed bound from seeded starting hyperparameters,
   on a seeded subsample of at most ``restart_subsample`` rows (cheap), inducing points fixed;
3. the best start refined on all rows (and, with ``inducing.optimize_positions``, the inducing
   points with it);
4. the optimal q(u) cached as a :class:`Posterior` (O(m^2) per prediction).
"""

from __future__ import annotations

import numpy as np

from gp.base import IndependentOutputGP, OutputFit
from gp.hyperopt import DataScales, Objective, maximize, start_from
from gp.inducing import InducingConfig, select_inducing_points
from gp.kernels import SquaredExponentialARD
from gp.sgpr_bound import sgpr_bound, sgpr_posterior
from gp.validation import check_inputs


class SparseGP(IndependentOutputGP):
    """SGPR estimator with SE-ARD kernels and independent outputs.

    Args (keyword-only, stored unchanged):
        kernel: initial (or, with ``optimize=False``, fixed) SE-ARD kernel; None derives one
            from the data scales.
        noise_variance: initial or fixed noise variance, output units squared; None: 10 % of
            the target variance.
        inducing: an :class:`InducingConfig` (strategy, m, refinement), or fixed inducing
            points as an array (m, d) (never moved).
        optimize: maximise the bound over the hyperparameters.
        n_restarts: starting points for the hyperparameters (first: the given/derived guess).
        max_iter: L-BFGS-B iterations per run.
        tol: relative improvement of the bound below which L-BFGS-B stops (1e-6 of
            a bound of ~1e4 nats is far below what changes predictions).
        restart_subsample: rows used by the restarts (the final refinement uses all rows).
        jitter: added to Kuu's diagonal, relative to the kernel variance.
        center_y: use the training mean of each output as a constant prior mean.
        random_state: seed for inducing selection, subsampling and restarts.

    Fitted attributes: those of :class:`IndependentOutputGP` (``objective_`` holds the bound),
    plus ``inducing_points_`` (n_outputs, m, d).
    """

    def __init__(
        self,
        *,
        kernel: SquaredExponentialARD | None = None,
        noise_variance: float | None = None,
        inducing: InducingConfig | np.ndarray = InducingConfig(),  # noqa: B008 (frozen)
        optimize: bool = True,
        n_restarts: int = 3,
        max_iter: int = 200,
        tol: float = 1e-6,
        restart_subsample: int = 2000,
        jitter: float = 1e-6,
        center_y: bool = True,
        random_state: int = 0,
    ) -> None:
        self.kernel = kernel
        self.noise_variance = noise_variance
        self.inducing = inducing
        self.optimize = optimize
        self.n_restarts = n_restarts
        self.max_iter = max_iter
        self.tol = tol
        self.restart_subsample = restart_subsample
        self.jitter = jitter
        self.center_y = center_y
        self.random_state = random_state

    def fit(self, X: np.ndarray, Y: np.ndarray) -> SparseGP:
        """Fit one SGPR per column of Y; X (n, d), Y (n, n_out) or (n,). Returns self."""
        super().fit(X, Y)
        self.inducing_points_ = self.posterior_.support.copy()
        return self

    def _prepare(self, X: np.ndarray) -> np.ndarray:
        """Initial inducing points (m, d), shared by all outputs."""
        if isinstance(self.inducing, InducingConfig):
            return select_inducing_points(X, self.inducing, self.random_state)
        return check_inputs(self.inducing, "inducing", X.shape[1])

    def _fit_output(
        self, X: np.ndarray, y: np.ndarray, rng: np.random.Generator, context: object
    ) -> OutputFit:
        z = np.asarray(context)
        scales = DataScales.of(X, y)
        hyp = start_from(self.kernel, self.noise_variance, scales)
        move_z = isinstance(self.inducing, InducingConfig) and self.inducing.optimize_positions
        objective = _bound_of(X, y, self.jitter)
        if not self.optimize:
            value = objective(hyp.kernel, hyp.noise_variance, z).value
        else:
            rows = _subsample(X.shape[0], self.restart_subsample, rng)
            sub_objective = _bound_of(X[rows], y[rows], self.jitter)
            starts = [hyp, *scales.initial_guesses(self.n_restarts, rng)[1:]]
            runs = [
                maximize(sub_objective, s, scales, z, max_iter=self.max_iter, rel_tol=self.tol)
                for s in starts
            ]
            hyp, _, value = max(runs, key=lambda r: r[2])
            if rows.shape[0] < X.shape[0] or move_z:
                hyp, z, value = maximize(objective, hyp, scales, z, move_z, self.max_iter, self.tol)
        alpha, R = sgpr_posterior(X, y, z, hyp.kernel, hyp.noise_variance, self.jitter)
        return OutputFit(hyp, z.copy(), alpha, R, value)


def _bound_of(X: np.ndarray, y: np.ndarray, jitter: float) -> Objective:
    """The objective closure (kernel, noise, Z) -> ObjectiveValue for fixed data."""
    return lambda kern, noise, z: sgpr_bound(X, y, z, kern, noise, jitter)


def _subsample(n: int, size: int, rng: np.random.Generator) -> np.ndarray:
    """Sorted row indices of a seeded subsample of at most ``size`` of ``n`` rows."""
    if n <= size:
        return np.arange(n)
    return np.sort(rng.choice(n, size, replace=False))
