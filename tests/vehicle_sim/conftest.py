"""Fixtures for the vehicle_sim tests."""

from __future__ import annotations

import pytest

from tests.vehicle_sim.sim_flying import hovering


@pytest.fixture
def iris_hover():
    """An Iris hovering at 2.5 m in OFFBOARD, settled."""
    return hovering()
