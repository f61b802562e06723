"""Frame helpers against scipy's rotation code and hand-worked cases."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vehicle_sim.jsbsim_backend.frames import (
    ecef_to_ned_matrix,
    ned_to_body_matrix,
    quat_wxyz_from_dcm,
)


@pytest.mark.parametrize("seed", range(6))
def test_quat_from_dcm_matches_scipy(seed):
    rng = np.random.default_rng(seed)
    rotations = Rotation.random(50, random_state=rng)
    for rot in rotations:
        x, y, z, w = rot.as_quat()
        expected = np.array([w, x, y, z]) * (1.0 if w >= 0 else -1.0)
        np.testing.assert_allclose(quat_wxyz_from_dcm(rot.as_matrix()), expected, atol=1e-12)


@pytest.mark.parametrize("axis", [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0]])
def test_quat_from_dcm_half_turns(axis):
    """Half turns have w = 0, where the trace-based formula alone breaks down."""
    rot = Rotation.from_rotvec(np.pi * np.asarray(axis, float) / np.linalg.norm(axis))
    q = quat_wxyz_from_dcm(rot.as_matrix())
    assert Rotation.from_quat([q[1], q[2], q[3], q[0]]).approx_equal(rot, atol=1e-12)


def test_ecef_to_ned_at_equator_and_prime_meridian():
    """At (0, 0): north is ECEF +z, east is ECEF +y, down is ECEF -x."""
    np.testing.assert_allclose(
        ecef_to_ned_matrix(0.0, 0.0), [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], atol=1e-15
    )


def test_ecef_to_ned_down_points_to_the_axis_at_the_pole():
    r = ecef_to_ned_matrix(np.pi / 2, 0.3)
    np.testing.assert_allclose(r[2], [0, 0, -1], atol=1e-15)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(r) == pytest.approx(1.0)


@pytest.mark.parametrize("seed", range(4))
def test_ned_to_body_matches_scipy_zyx_euler(seed):
    roll, pitch, yaw = np.random.default_rng(seed).uniform([-3, -1.5, -3], [3, 1.5, 3])
    body_to_ned = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()
    np.testing.assert_allclose(ned_to_body_matrix(roll, pitch, yaw), body_to_ned.T, atol=1e-12)
