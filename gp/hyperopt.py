"""Hyperparameter (and inducing-point) optimisation by L-BFGS-B on log parameters, with restarts.

The optimiser maximises an objective (log marginal likelihood or the SGPR bound) over
``theta = [log lengthscales (d), log variance, log noise_variance, Z.ravel() (optional)]``
inside box bounds scaled to the data, from seeded random starting points.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from gp.errors import GPInputError
from gp.kernels import SquaredExponentialARD


@dataclass(frozen=True, eq=False)
class ObjectiveValue:
    """An objective (nats) and its gradients.

    Attributes:
        value: the objective, to be maximised.
        grad_log_lengthscales: (d,); grad_log_variance, grad_log_noise: scalars.
        grad_support: dF/dZ (m, d) for objectives with inducing points, else None.
    """

    value: float
    grad_log_lengthscales: np.ndarray
    grad_log_variance: float
    grad_log_noise: float
    grad_support: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Hyperparameters:
    """Kernel and Gaussian noise variance (output units squared) of one output."""

    kernel: SquaredExponentialARD
    noise_variance: float


Objective = Callable[[SquaredExponentialARD, float, np.ndarray | None], ObjectiveValue]


@dataclass(frozen=True, eq=False)
class DataScales:
    """Per-feature input spread (d,) and target variance, used for bounds and initial guesses."""

    x_scale: np.ndarray
    y_var: float

    @classmethod
    def of(cls, X: np.ndarray, y: np.ndarray) -> DataScales:
        x_scale = X.std(axis=0)
        x_scale[~(x_scale > 0)] = 1.0
        return cls(x_scale, max(float(np.var(y)), 1e-12))

    def log_bounds(self) -> list[tuple[float, float]]:
        """Box bounds on [log lengthscales, log variance, log noise variance]."""
        ls = [(np.log(1e-2 * s), np.log(1e3 * s)) for s in self.x_scale]
        yv = np.log(self.y_var)
        return [*ls, (yv + np.log(1e-6), yv + np.log(1e2)), (yv + np.log(1e-6), yv + np.log(10.0))]

    def initial_guesses(self, n: int, rng: np.random.Generator) -> list[Hyperparameters]:
        """``n`` starting points: a data-scaled default first, then seeded random ones.

        Lengthscales start at sqrt(d) times each feature's spread, so that typical pairs of
        points are about one lengthscale apart whatever the dimension d.
        """
        ls0 = self.x_scale * np.sqrt(self.x_scale.shape[0])
        guesses = [Hyperparameters(SquaredExponentialARD(ls0, self.y_var), 0.1 * self.y_var)]
        for _ in range(n - 1):
            ls = ls0 * np.exp(rng.uniform(-1.0, 1.0, ls0.shape))
            kern = SquaredExponentialARD(ls, self.y_var * np.exp(rng.uniform(-1.0, 1.0)))
            guesses.append(Hyperparameters(kern, self.y_var * np.exp(rng.uniform(-5.0, -1.0))))
        return guesses


def maximize(
    objective: Objective,
    start: Hyperparameters,
    scales: DataScales,
    support: np.ndarray | None = None,
    optimize_support: bool = False,
    max_iter: int = 200,
    rel_tol: float = 1e-9,
) -> tuple[Hyperparameters, np.ndarray | None, float]:
    """Maximise ``objective`` from ``start`` with L-BFGS-B.

    Args:
        objective: (kernel, noise_variance, support) -> ObjectiveValue.
        start: initial hyperparameters (clipped into the bounds).
        scales: data scales that set the box bounds.
        support: inducing points (m, d) passed to the objective; optimised if
            ``optimize_support`` (needs an objective returning grad_support).
        max_iter: L-BFGS-B iteration limit.
        rel_tol: stop when an iteration improves the objective by less than this fraction.

    Returns:
        (hyperparameters, support, objective value) at the optimum found.
    """
    d = scales.x_scale.shape[0]
    bounds = scales.log_bounds()
    theta0 = np.concatenate([start.kernel.log_params(), [np.log(start.noise_variance)]])
    theta0 = np.clip(theta0, [b[0] for b in bounds], [b[1] for b in bounds])
    n_hyp = theta0.shape[0]
    if optimize_support:
        assert support is not None
        theta0 = np.concatenate([theta0, support.ravel()])
        bounds = bounds + [(None, None)] * support.size

    def unpack(theta: np.ndarray) -> tuple[SquaredExponentialARD, float, np.ndarray | None]:
        kern = SquaredExponentialARD.from_log_params(theta[: d + 1])
        z = theta[n_hyp:].reshape(support.shape) if optimize_support else support
        return kern, float(np.exp(theta[d + 1])), z

    def negative(theta: np.ndarray) -> tuple[float, np.ndarray]:
        try:
            res = objective(*unpack(theta))
        except GPInputError:
            return np.inf, np.zeros_like(theta)
        grad = [res.grad_log_lengthscales, [res.grad_log_variance, res.grad_log_noise]]
        if optimize_support:
            grad.append(res.grad_support.ravel())
        return -res.value, -np.concatenate(grad)

    result = optimize.minimize(
        negative,
        theta0,
        jac=True,
        method="L-BFGS-B",
        bounds=bounds,
        options={"maxiter": max_iter, "ftol": rel_tol},
    )
    theta = result.x if np.isfinite(result.fun) else theta0
    kern, noise, z = unpack(theta)
    value = -float(result.fun) if np.isfinite(result.fun) else objective(kern, noise, z).value
    return Hyperparameters(kern, noise), z, value


def start_from(
    kernel: SquaredExponentialARD | None, noise_variance: float | None, scales: DataScales
) -> Hyperparameters:
    """The user's initial hyperparameters, missing parts filled from the data scales."""
    if kernel is not None and kernel.n_features != scales.x_scale.shape[0]:
        raise GPInputError(
            f"kernel has {kernel.n_features} lengthscales but X has {scales.x_scale.shape[0]} "
            "features; pass one lengthscale per feature or kernel=None"
        )
    if noise_variance is not None and not noise_variance > 0:
        raise GPInputError(f"noise_variance must be > 0, got {noise_variance}")
    default = scales.initial_guesses(1, np.random.default_rng(0))[0]
    return Hyperparameters(
        kernel if kernel is not None else default.kernel,
        float(noise_variance) if noise_variance is not None else default.noise_variance,
    )
