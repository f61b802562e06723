"""Inducing-point strategies: counts, placement and errors."""

import numpy as np
import pytest

from gp.errors import GPInputError
from gp.inducing import (
    InducingConfig,
    histogram_medians,
    low_speed_weights,
    select_inducing_points,
)


def test_histogram_medians_are_bin_medians_over_the_range():
    x = np.concatenate([np.full(5, 0.1), np.full(3, 0.4), [0.95, 0.97, 0.99]])
    x = np.concatenate([x, [0.0, 1.0]])
    medians = histogram_medians(x, 3)
    np.testing.assert_allclose(medians, [0.1, 0.4, 0.98])


def test_histogram_medians_split_the_fullest_group_until_m_are_filled():
    x = np.array([0.0, 0.01, 0.02, 0.03, 10.0])
    np.testing.assert_allclose(histogram_medians(x, 3), [0.005, 0.025, 10.0])


@pytest.mark.parametrize("strategy", ["low_speed", "cluster", "random"])
@pytest.mark.parametrize("d", [1, 3])
def test_every_strategy_gives_m_distinct_points_in_the_data_range(strategy, d):
    X = np.random.default_rng(0).normal(size=(500, d))
    Z = select_inducing_points(X, InducingConfig(strategy, m=12), seed=1)
    assert Z.shape == (12, d)
    assert np.unique(Z, axis=0).shape[0] == 12
    lo, hi = X.min(0) - 1e-12, X.max(0) + 1e-12
    assert np.all(Z - lo >= 0) and np.all(hi - Z >= 0)
    np.testing.assert_array_equal(Z, select_inducing_points(X, InducingConfig(strategy, m=12), 1))


@pytest.mark.parametrize("d", [1, 2])
def test_low_speed_puts_more_points_at_low_speed_than_cluster(d):
    X = np.random.default_rng(2).normal(0.0, 2.0, size=(3000, d))
    low = select_inducing_points(X, InducingConfig("low_speed", m=20), 0)
    cluster = select_inducing_points(X, InducingConfig("cluster", m=20), 0)
    slow = lambda Z: np.sum(np.linalg.norm(Z, axis=1) < 1.5)  # noqa: E731
    assert slow(low) >= slow(cluster) + 2, (slow(low), slow(cluster))


def test_low_speed_uses_only_the_speed_columns():
    """A velocity column [m/s] beside a large other one (100-200, say an altitude): the weight
    is the Cauchy weight of the velocity alone, and nine in ten points sit at its low speeds
    (the norm of both columns taken for the speed puts half there, random picks three in
    eight)."""
    rng = np.random.default_rng(3)
    X = np.column_stack([rng.uniform(-4, 4, 3000), rng.uniform(100, 200, 3000)])
    scale_mps = rng.uniform(0.5, 2.0)
    weights = low_speed_weights(X, (0,), scale_mps)
    np.testing.assert_allclose(weights, 1.0 / (1.0 + (X[:, 0] / scale_mps) ** 2), rtol=1e-12)
    Z = select_inducing_points(X, InducingConfig("low_speed", m=20, speed_columns=(0,)), 0)
    assert np.sum(np.abs(Z[:, 0]) < 1.5) >= 18, np.sort(Z[:, 0])


def test_bad_config_lists_the_valid_choices():
    with pytest.raises(ValueError, match="choose one of low_speed, cluster, random"):
        InducingConfig("kmeans")
    with pytest.raises(ValueError, match="m must be a positive integer"):
        InducingConfig(m=0)


def test_too_few_distinct_rows_is_an_error():
    X = np.repeat(np.arange(5.0)[:, None], 10, axis=0)
    with pytest.raises(GPInputError, match="only 5 distinct rows; lower m"):
        select_inducing_points(X, InducingConfig("random", m=6))
