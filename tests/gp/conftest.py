"""Shared fixtures for the gp tests."""

import numpy as np
import pytest
from gp_synthetic_logs import drag_residual


@pytest.fixture(scope="module")
def small_model():
    """A fitted SparseGP on 3-D velocity data (3 outputs, m = 12)."""
    from gp.inducing import InducingConfig
    from gp.sparse_gp import SparseGP

    rng = np.random.default_rng(0)
    X = rng.normal(size=(600, 3))
    Y = drag_residual(X) + 0.05 * rng.normal(size=X.shape)
    return SparseGP(inducing=InducingConfig(m=12), n_restarts=1).fit(X, Y)
