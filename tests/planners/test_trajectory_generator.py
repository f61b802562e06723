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


def test_bad_floor_raises():
    with pytest.raises(ValueError, match="min_altitude_m"):
        TrajectorySpec(start_ned_m=(0.0, 0.0, -2.0), min_altitude_m=2.5)


def test_default_floor_is_px4_takeoff_altitude():
    assert TrajectorySpec().min_altitude_m == 2.5  # MIS_TAKEOFF_ALT's PX4 default [m]


def test_no_reference_flies_below_the_floor_over_many_seeds():
    """Random specs (lengths, climbs, start and floor drawn, seeded) over many generator
    seeds: every sampled reference point is at or above the floor, lengths stay in range."""
    rng = np.random.default_rng(17)
    lowest_margin = np.inf
    lifted = 0
    for seed in range(120):
        lo = rng.uniform(20.0, 80.0)
        start_alt = rng.uniform(1.5, 4.0)
        spec = TrajectorySpec(
            length_range_m=(lo, lo + rng.uniform(0.0, 40.0)),
            max_speed_mps=rng.uniform(1.0, 6.0),
            max_acc_mps2=rng.uniform(1.0, 4.0),
            start_ned_m=(0.0, 0.0, -start_alt),
            max_climb_m=rng.uniform(0.3, 1.5),
            min_altitude_m=start_alt - rng.uniform(0.0, 1.0),
        )
        free = TrajectorySpec(**{**spec.__dict__, "min_altitude_m": -np.inf})
        for ref, unbounded in zip(
            generate_trajectories(2, seed, spec), generate_trajectories(2, seed, free), strict=True
        ):
            pos = ref.sample(np.linspace(0.0, ref.duration_s, 4001)).pos_ned_m
            lowest_margin = min(lowest_margin, float(-pos[:, 2].max()) - spec.min_altitude_m)
            assert spec.length_range_m[0] - 1e-6 <= ref.length_m() <= spec.length_range_m[1] + 1e-6
            np.testing.assert_allclose(ref.waypoints_ned_m[0], spec.start_ned_m)
            free_pos = unbounded.sample(np.linspace(0.0, unbounded.duration_s, 4001)).pos_ned_m
            if -free_pos[:, 2].max() >= spec.min_altitude_m:  # never came down: untouched
                np.testing.assert_array_equal(ref.waypoints_ned_m, unbounded.waypoints_ned_m)
            else:
                lifted += 1
    assert lowest_margin >= -1e-9
    assert lifted > 20  # the floor was met often enough to test it


def test_a_jerk_limited_start_keeps_the_paths_and_ramps_the_acceleration():
    plain = generate_trajectories(2, seed=3)
    ramped = generate_trajectories(2, seed=3, spec=TrajectorySpec(ramp_jerk_mps3=4.0))
    for a, b in zip(plain, ramped, strict=True):
        np.testing.assert_array_equal(a.waypoints_ned_m, b.waypoints_ned_m)
        assert a.ramp_s == 0.0 and b.ramp_s > 0.0 and b.duration_s > a.duration_s
        assert np.linalg.norm(b.sample(1e-6).acc_ned_mps2) < 1e-6
