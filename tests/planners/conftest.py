"""Shared fixtures for the planner tests."""

import numpy as np
import pytest

from planners.bspline import BSplineReference


@pytest.fixture(scope="session")
def short_reference() -> BSplineReference:
    """About 9 m in 3-D with turns, at most 1.2 m/s."""
    wp = np.array([[0.0, 0.0, -2.0], [3.0, 1.0, -2.5], [5.0, 4.0, -3.0], [8.0, 4.5, -2.5]])
    return BSplineReference(wp, max_speed_mps=1.2, max_acc_mps2=1.0, yaw_rad=0.3)
