"""Paper 004's experience bins and sliding local GP."""

import numpy as np
import pytest

from gp.exact_gp import ExactGP
from gp.kernels import SquaredExponentialARD
from gp.local_gp import ExperienceBinsConfig, LocalGP

KERNEL = SquaredExponentialARD(np.array([0.5, 0.5]), 0.2)


def _local(config=None):
    return LocalGP([KERNEL], [0.01], config or ExperienceBinsConfig())


def test_full_bin_discards_its_oldest_experience():
    gp = _local(ExperienceBinsConfig(bin_capacity=3, vertex_window=0, speed_window=0))
    for k in range(5):
        gp.add(vertex=4, speed_mps=1.0, query=[k, 0.0], disturbance=[float(k)])
    X, Y = gp.local_data(4, 1.0)
    np.testing.assert_array_equal(Y[:, 0], [2.0, 3.0, 4.0])
    assert len(gp) == 3


def test_local_dataset_draws_only_from_neighbouring_vertices_and_speeds():
    config = ExperienceBinsConfig(
        speed_bin_mps=0.5, bin_capacity=2, vertex_window=1, speed_window=1
    )
    gp = _local(config)
    for vertex in range(10):
        for speed in (0.2, 0.7, 1.2, 1.7, 2.2):
            gp.add(vertex, speed, [vertex, speed], [vertex * 10 + speed])
    X, _ = gp.local_data(5, 1.2)
    assert set(X[:, 0]) == {4.0, 5.0, 6.0} and set(X[:, 1]) == {0.7, 1.2, 1.7}
    assert X.shape[0] <= config.max_local_points


def test_reversing_and_driving_forward_slowly_are_different_speed_bins():
    """Bin l holds speeds in [l w, (l + 1) w): -0.1 m/s is bin -1, +0.1 m/s bin 0, so a slow
    reverse never lends its experience to a slow forward pass (speed window 0)."""
    gp = _local(ExperienceBinsConfig(speed_bin_mps=0.25, vertex_window=0, speed_window=0))
    gp.add(3, -0.1, [0.0, 0.0], [1.0])
    gp.add(3, 0.1, [0.0, 0.0], [2.0])
    np.testing.assert_array_equal(gp.local_data(3, 0.2)[1][:, 0], [2.0])
    np.testing.assert_array_equal(gp.local_data(3, -0.2)[1][:, 0], [1.0])


def test_prediction_equals_exact_gp_on_the_local_data():
    rng = np.random.default_rng(0)
    gp = _local()
    for _ in range(200):
        vertex, speed = int(rng.integers(0, 20)), float(rng.uniform(0, 2))
        a = rng.normal(size=2)
        gp.add(vertex, speed, a, [np.sin(a[0]) + 0.1 * rng.normal()])
    X, Y = gp.local_data(10, 1.0)
    assert 0 < X.shape[0] < 200
    ref = ExactGP(kernel=KERNEL, noise_variance=0.01, optimize=False, center_y=False).fit(X, Y)
    queries = rng.normal(size=(5, 2))
    for got, want in zip(gp.predict(10, 1.0, queries), ref.predict(queries), strict=True):
        np.testing.assert_allclose(got, want, atol=1e-10)


def test_no_experience_predicts_the_prior():
    mean, std = _local().predict(3, 1.0, np.zeros((2, 2)))
    np.testing.assert_array_equal(mean, 0.0)
    np.testing.assert_allclose(std, np.sqrt(0.2))


def test_bad_experience_shapes_are_one_line_errors():
    with pytest.raises(ValueError, match="query has 3 features but the model was fitted with 2"):
        _local().add(0, 1.0, [1.0, 2.0, 3.0], [0.0])
