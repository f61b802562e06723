"""Exact GP against scikit-learn with fixed hyperparameters, and its evidence gradients."""

import numpy as np
import pytest
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel

from gp.exact_gp import ExactGP, exact_log_marginal_likelihood
from gp.kernels import SquaredExponentialARD


@pytest.mark.parametrize(
    ("lengthscales", "variance", "noise"),
    [([0.7], 1.5, 0.02), ([0.5, 2.0, 1.1], 0.3, 0.001), ([3.0, 0.4], 2.0, 0.5)],
)
def test_exact_gp_equals_sklearn_with_fixed_hyperparameters(lengthscales, variance, noise):
    rng = np.random.default_rng(len(lengthscales))
    d = len(lengthscales)
    X = rng.normal(size=(60, d))
    y = np.sin(X.sum(1)) + 0.1 * rng.normal(size=60)
    X_test = 1.5 * rng.normal(size=(25, d))
    kernel = SquaredExponentialARD(np.array(lengthscales), variance)
    ours = ExactGP(kernel=kernel, noise_variance=noise, optimize=False, center_y=False).fit(X, y)
    sk_kernel = ConstantKernel(variance, "fixed") * RBF(lengthscales, "fixed")
    sk = GaussianProcessRegressor(sk_kernel, alpha=noise, optimizer=None).fit(X, y)
    mean, std = ours.predict(X_test)
    sk_mean, sk_std = sk.predict(X_test, return_std=True)
    np.testing.assert_allclose(mean[:, 0], sk_mean, atol=1e-6)
    np.testing.assert_allclose(std[:, 0], sk_std, atol=1e-6)
    np.testing.assert_allclose(
        ours.log_marginal_likelihood()[0], sk.log_marginal_likelihood_value_, atol=1e-6
    )


def test_log_marginal_likelihood_gradients_match_finite_differences():
    rng = np.random.default_rng(3)
    X = rng.normal(size=(40, 2))
    y = np.cos(X[:, 0]) + 0.05 * rng.normal(size=40)
    theta = np.log([0.8, 1.7, 0.9, 0.03])

    def lml(t):
        kern = SquaredExponentialARD(np.exp(t[:2]), np.exp(t[2]))
        return exact_log_marginal_likelihood(X, y, kern, np.exp(t[3]))

    res = lml(theta)
    analytic = np.r_[res.grad_log_lengthscales, res.grad_log_variance, res.grad_log_noise]
    h = 1e-6
    numeric = [(lml(theta + h * e).value - lml(theta - h * e).value) / (2 * h) for e in np.eye(4)]
    np.testing.assert_allclose(analytic, numeric, rtol=1e-5, atol=1e-6)


def test_optimised_exact_gp_finds_noise_level_and_beats_default_evidence():
    rng = np.random.default_rng(4)
    X = rng.uniform(-3, 3, size=(150, 1))
    y = np.sin(2 * X[:, 0]) + 0.1 * rng.normal(size=150)
    fixed = ExactGP(optimize=False).fit(X, y)
    fitted = ExactGP(n_restarts=2).fit(X, y)
    assert fitted.objective_[0] > fixed.objective_[0] + 10.0
    assert np.sqrt(fitted.noise_variances_[0]) == pytest.approx(0.1, rel=0.25)
