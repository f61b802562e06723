import numpy as np
import pytest

from planners.trajectory_generator import TrajectorySpec, generate_trajectories


@pytest.fixture(scope="module")
def twenty():
    return generate_trajectories(20, seed=7)


def test_same_seed_same_trajectories(twenty):
    again = generate_trajectories(20, seed=7)
    for a, b in zip(twenty, again, strict=True):
        np.testing.assert_array_equal(a.waypoints_ned_m, b.waypoints_ned_m)
    other = generate_trajectories(1, seed=8)[0]
    assert not np.allclose(other.waypoints_ned_m, twenty[0].waypoints_ned_m)


def test_lengths_in_range_and_speed_limit(twenty):
    lengths = np.array([t.length_m() for t in twenty])
    assert np.all((lengths >= 40.0 - 1e-6) & (lengths <= 60.0 + 1e-6))
    assert lengths.std() > 1.0  # drawn, not constant
    for t in twenty:
        smp = t.sample(np.linspace(0.0, t.duration_s, 4001))
        assert np.linalg.norm(smp.vel_ned_mps, axis=1).max() <= 1.5 + 1e-9
        assert np.all(smp.pos_ned_m[:, 2] < 0.0)  # above ground (NED down negative)


def test_trajectories_are_distinct(twenty):
    shapes = [t.sample(np.linspace(0.0, t.duration_s, 50)).pos_ned_m for t in twenty]
    for i in range(len(shapes)):
        for j in range(i):
            assert np.max(np.linalg.norm(shapes[i] - shapes[j], axis=1)) > 1.0


def test_bad_spec_raises():
    with pytest.raises(ValueError, match="length_range_m"):
        TrajectorySpec(length_range_m=(60.0, 40.0))
