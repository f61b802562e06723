"""Titsias' bound: below the exact evidence, equal to it at Z = X, and correct gradients."""

import numpy as np
import pytest

from gp.exact_gp import ExactGP, exact_log_marginal_likelihood
from gp.kernels import SquaredExponentialARD
from gp.sgpr_bound import sgpr_bound
from gp.sparse_gp import SparseGP


def _data(seed, n=80, d=2):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, d))
    return rng, X, np.sin(2 * X[:, 0]) * np.cos(X[:, -1]) + 0.1 * rng.normal(size=n)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("m", [3, 10, 30])
def test_bound_never_exceeds_exact_log_marginal_likelihood(seed, m):
    rng, X, y = _data(seed)
    kern = SquaredExponentialARD(np.exp(rng.uniform(-1, 1, 2)), float(np.exp(rng.uniform(-1, 1))))
    noise = float(np.exp(rng.uniform(-5, 0)))
    Z = rng.normal(size=(m, 2))
    bound = sgpr_bound(X, y, Z, kern, noise).value
    exact = exact_log_marginal_likelihood(X, y, kern, noise).value
    assert bound <= exact + 1e-8


def test_bound_with_inducing_points_at_the_data_equals_exact_evidence():
    _, X, y = _data(7, n=30)
    kern = SquaredExponentialARD(np.array([0.9, 1.3]), 1.2)
    bound = sgpr_bound(X, y, X, kern, 0.05, jitter=1e-10).value
    exact = exact_log_marginal_likelihood(X, y, kern, 0.05).value
    assert bound == pytest.approx(exact, abs=1e-5)


def test_sgpr_with_inducing_points_at_the_data_predicts_like_exact_gp():
    rng, X, y = _data(8, n=30)
    kern = SquaredExponentialARD(np.array([0.9, 1.3]), 1.2)
    common = {"kernel": kern, "noise_variance": 0.05, "optimize": False, "center_y": False}
    sparse = SparseGP(inducing=X, jitter=1e-10, **common).fit(X, y)
    exact = ExactGP(**common).fit(X, y)
    X_test = 1.5 * rng.normal(size=(40, 2))
    mean_s, std_s = sparse.predict(X_test)
    mean_e, std_e = exact.predict(X_test)
    np.testing.assert_allclose(mean_s, mean_e, atol=1e-6)
    np.testing.assert_allclose(std_s, std_e, atol=1e-5)


def test_bound_gradients_match_finite_differences():
    rng, X, y = _data(9, n=70, d=3)
    Z = rng.normal(size=(7, 3))
    theta = np.log([0.8, 1.4, 2.0, 1.3, 0.05])

    def bound(t, z):
        kern = SquaredExponentialARD(np.exp(t[:3]), np.exp(t[3]))
        return sgpr_bound(X, y, z, kern, np.exp(t[4]))

    res = bound(theta, Z)
    h = 1e-6
    analytic = np.r_[res.grad_log_lengthscales, res.grad_log_variance, res.grad_log_noise]
    numeric = [
        (bound(theta + h * e, Z).value - bound(theta - h * e, Z).value) / (2 * h) for e in np.eye(5)
    ]
    np.testing.assert_allclose(analytic, numeric, rtol=1e-5, atol=1e-5)
    numeric_z = np.zeros_like(Z)
    for idx in np.ndindex(Z.shape):
        dz = np.zeros_like(Z)
        dz[idx] = h
        numeric_z[idx] = (bound(theta, Z + dz).value - bound(theta, Z - dz).value) / (2 * h)
    np.testing.assert_allclose(res.grad_support, numeric_z, rtol=1e-5, atol=1e-5)


def test_bound_is_consistent_across_data_blocks(monkeypatch):
    import gp.sgpr_bound as module

    rng, X, y = _data(10, n=300)
    Z = rng.normal(size=(9, 2))
    kern = SquaredExponentialARD(np.array([0.7, 1.1]), 0.8)
    whole = sgpr_bound(X, y, Z, kern, 0.02)
    monkeypatch.setattr(module, "BLOCK_ROWS", 64)
    blocked = sgpr_bound(X, y, Z, kern, 0.02)
    assert blocked.value == pytest.approx(whole.value, rel=1e-12)
    np.testing.assert_allclose(blocked.grad_support, whole.grad_support, rtol=1e-9, atol=1e-9)
