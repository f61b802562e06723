"""SparseGP as an estimator: recovery of a known residual, inducing strategies, errors."""

import numpy as np
import pytest
from sklearn.base import clone

from gp.errors import GPInputError
from gp.exact_gp import ExactGP
from gp.inducing import InducingConfig
from gp.kernels import SquaredExponentialARD
from gp.not_fitted import NotFittedError
from gp.sparse_gp import SparseGP

NOISE_STD = 0.05


def drag_residual(vel_mps):
    return -0.3 * vel_mps - 0.08 * vel_mps * np.abs(vel_mps)


def test_known_residual_is_recovered_below_the_noise_level():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(3000, 3)) * np.array([1.0, 1.0, 0.4])
    Y = drag_residual(X) + NOISE_STD * rng.normal(size=X.shape)
    model = SparseGP(inducing=InducingConfig(m=30), n_restarts=2).fit(X, Y)
    X_test = rng.normal(size=(1000, 3)) * np.array([1.0, 1.0, 0.4])
    mean, std = model.predict(X_test)
    rmse = np.sqrt(np.mean((mean - drag_residual(X_test)) ** 2, axis=0))
    assert np.all(rmse < 0.5 * NOISE_STD), rmse
    np.testing.assert_allclose(np.sqrt(model.noise_variances_), NOISE_STD, rtol=0.1)
    assert np.all(np.median(std, axis=0) < 0.5 * NOISE_STD)


def _low_speed_residual(v):
    return drag_residual(v) + 0.2 * np.sin(5 * v) * np.exp(-(v**2) / 2)


def test_low_speed_inducing_beats_cluster_on_data_concentrated_at_low_speed():
    rmse = {"low_speed": [], "cluster": []}
    for seed in range(4):
        rng = np.random.default_rng(seed)
        X = rng.normal(0.0, 0.7, size=(2000, 1))
        y = _low_speed_residual(X[:, 0]) + 0.03 * rng.normal(size=2000)
        X_test = rng.normal(0.0, 0.7, size=(3000, 1))
        for strategy, errors in rmse.items():
            inducing = InducingConfig(strategy=strategy, m=8)
            model = SparseGP(inducing=inducing, n_restarts=2, random_state=seed).fit(X, y)
            mean, _ = model.predict(X_test)
            errors.append(np.sqrt(np.mean((mean[:, 0] - _low_speed_residual(X_test[:, 0])) ** 2)))
    assert np.mean(rmse["low_speed"]) < 0.7 * np.mean(rmse["cluster"]), rmse


def test_optimising_inducing_positions_does_not_lower_the_bound():
    rng = np.random.default_rng(5)
    X = rng.uniform(-3, 3, size=(800, 1))
    y = np.sin(2 * X[:, 0]) + 0.05 * rng.normal(size=800)
    fixed = SparseGP(inducing=InducingConfig("random", m=6), n_restarts=1).fit(X, y)
    moved = SparseGP(
        inducing=InducingConfig("random", m=6, optimize_positions=True), n_restarts=1
    ).fit(X, y)
    assert moved.objective_[0] > fixed.objective_[0]
    assert not np.allclose(moved.inducing_points_, fixed.inducing_points_)


def _sine(seed: int, n: int = 300) -> tuple[np.ndarray, np.ndarray]:
    """y = sin(6 x) + N(0, NOISE_STD^2) on x in [0, 5] m: a period of 1.05 m."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(0.0, 5.0, (n, 1))
    return X, np.sin(6.0 * X[:, 0]) + NOISE_STD * rng.normal(size=n)


def test_restarts_escape_a_start_that_explains_everything_as_noise():
    """From a 100 m lengthscale over 5 m of data and the whole variance as noise, L-BFGS-B
    stays where it starts (flat in the lengthscale); a random restart finds the sine, and the
    noise it leaves is the noise that was added."""
    X, y = _sine(0)
    poor = {"kernel": SquaredExponentialARD(np.array([100.0]), 0.01), "noise_variance": 0.5}
    model = SparseGP(
        **poor, inducing=InducingConfig("random", m=30), n_restarts=3, random_state=0
    ).fit(X, y)
    np.testing.assert_allclose(np.sqrt(model.noise_variances_), NOISE_STD, rtol=0.2)
    assert model.kernels_[0].lengthscales[0] < 1.0  # shorter than the period


def test_a_fit_on_a_restart_subsample_reports_the_bound_on_all_rows():
    """The restarts run on a subsample (100 of 300 rows), but the model is then refined on
    every row: its bound is the one a fit without subsampling reaches, not the subsample's."""
    X, y = _sine(1)
    fits = [
        SparseGP(inducing=InducingConfig("random", m=30), restart_subsample=rows).fit(X, y)
        for rows in (100, 2000)
    ]
    assert fits[0].objective_[0] == pytest.approx(fits[1].objective_[0], rel=1e-4)


def test_estimator_api_stores_params_and_returns_self_with_fixed_shapes():
    kern = SquaredExponentialARD(np.ones(2), 1.0)
    inducing = InducingConfig("random", m=5)
    model = SparseGP(kernel=kern, inducing=inducing, n_restarts=1, random_state=3)
    assert model.kernel is kern and model.inducing is inducing and model.random_state == 3
    rng = np.random.default_rng(0)
    X = rng.normal(size=(50, 2))
    assert model.fit(X, X[:, 0]) is model
    for n in (1, 7):
        mean, std = model.predict(rng.normal(size=(n, 2)))
        assert mean.shape == (n, 1) and std.shape == (n, 1)
    assert model.inducing_points_.shape == (1, 5, 2)
    assert model.get_params()["kernel"] is kern
    params = clone(model).get_params()
    np.testing.assert_array_equal(params["kernel"].lengthscales, kern.lengthscales)
    assert params["n_restarts"] == 1 and params["random_state"] == 3
    assert not hasattr(clone(model), "posterior_")


def test_same_seed_gives_same_model():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(400, 2))
    Y = np.column_stack([np.sin(X[:, 0]), X[:, 1] ** 2]) + 0.1 * rng.normal(size=(400, 2))
    a = SparseGP(inducing=InducingConfig(m=10), n_restarts=2, random_state=4).fit(X, Y)
    b = SparseGP(inducing=InducingConfig(m=10), n_restarts=2, random_state=4).fit(X, Y)
    np.testing.assert_array_equal(a.predict(X[:20])[0], b.predict(X[:20])[0])


@pytest.mark.parametrize("estimator", [SparseGP, ExactGP])
def test_predict_before_fit_says_to_fit(estimator):
    with pytest.raises(NotFittedError, match=r"not fitted yet; call fit\(X, Y\)"):
        estimator().predict(np.zeros((1, 3)))


@pytest.mark.parametrize(
    ("X", "message"),
    [
        (np.zeros((4, 2)), r"has 2 features but the model was fitted with 3"),
        (np.zeros(3), r"must be 2-D .* reshape a single sample"),
        (np.array([[0.0, np.nan, 1.0]]), r"X\[0, 1\] is nan; remove or impute"),
        (np.zeros((0, 3)), r"has no rows"),
    ],
)
def test_bad_prediction_inputs_give_one_line_errors(X, message):
    rng = np.random.default_rng(0)
    model = SparseGP(inducing=InducingConfig("random", m=4), n_restarts=1)
    model.fit(rng.normal(size=(30, 3)), rng.normal(size=30))
    with pytest.raises(GPInputError, match=message) as info:
        model.predict(X)
    assert "\n" not in str(info.value)


def test_bad_training_data_give_one_line_errors():
    X = np.random.default_rng(0).normal(size=(20, 2))
    with pytest.raises(GPInputError, match=r"Y has 19 rows but X has 20"):
        SparseGP().fit(X, np.zeros(19))
    with pytest.raises(GPInputError, match=r"Y\[3, 0\] is inf"):
        SparseGP().fit(X, np.where(np.arange(20) == 3, np.inf, 0.0))
    with pytest.raises(GPInputError, match=r"30 inducing points requested but .* 20 distinct"):
        SparseGP(inducing=InducingConfig(m=30)).fit(X, np.zeros(20))
    with pytest.raises(GPInputError, match=r"kernel has 3 lengthscales but X has 2"):
        SparseGP(kernel=SquaredExponentialARD(np.ones(3), 1.0), inducing=InducingConfig(m=4)).fit(
            X, np.zeros(20)
        )
