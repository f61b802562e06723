import numpy as np
import pytest

from planners.bspline import BSplineReference

WAYPOINTS = np.array(
    [[0.0, 0.0, -2.0], [4.0, 1.0, -2.5], [8.0, -2.0, -3.0], [12.0, 3.0, -2.0], [15.0, 0.0, -2.0]]
)


@pytest.mark.parametrize("max_speed_mps, max_acc_mps2", [(1.5, 1.0), (0.5, 0.2), (3.0, 5.0)])
def test_passes_through_waypoints_at_knots(max_speed_mps, max_acc_mps2):
    ref = BSplineReference(WAYPOINTS, max_speed_mps, max_acc_mps2)
    knots = ref.segment_duration_s * np.arange(len(WAYPOINTS))
    np.testing.assert_allclose(ref.sample(knots).pos_ned_m, WAYPOINTS, atol=1e-9)


@pytest.mark.parametrize("max_speed_mps, max_acc_mps2", [(1.5, 1.0), (0.5, 0.2), (3.0, 5.0)])
def test_respects_limits_and_one_limit_is_tight(max_speed_mps, max_acc_mps2):
    ref = BSplineReference(WAYPOINTS, max_speed_mps, max_acc_mps2)
    smp = ref.sample(np.linspace(0.0, ref.duration_s, 20001))
    speed = np.linalg.norm(smp.vel_ned_mps, axis=1).max()
    acc = np.linalg.norm(smp.acc_ned_mps2, axis=1).max()
    assert speed <= max_speed_mps + 1e-9
    assert acc <= max_acc_mps2 + 1e-9
    assert max(speed / max_speed_mps, acc / max_acc_mps2) > 0.99  # not needlessly slow


def test_derivatives_match_finite_differences():
    ref = BSplineReference(WAYPOINTS, 1.5, 1.0)
    t = np.linspace(0.3, ref.duration_s - 0.3, 97)
    h = 1e-5
    smp = ref.sample(t)
    fd_vel = (ref.sample(t + h).pos_ned_m - ref.sample(t - h).pos_ned_m) / (2 * h)
    fd_acc = (ref.sample(t + h).vel_ned_mps - ref.sample(t - h).vel_ned_mps) / (2 * h)
    np.testing.assert_allclose(smp.vel_ned_mps, fd_vel, atol=1e-6)
    np.testing.assert_allclose(smp.acc_ned_mps2, fd_acc, atol=1e-4)


def test_starts_and_ends_at_rest_and_holds_outside():
    ref = BSplineReference(WAYPOINTS)
    smp = ref.sample(np.array([-1.0, 0.0, ref.duration_s, ref.duration_s + 5.0]))
    np.testing.assert_allclose(smp.vel_ned_mps, 0.0, atol=1e-12)
    np.testing.assert_allclose(smp.pos_ned_m[:2], WAYPOINTS[[0, 0]], atol=1e-12)
    np.testing.assert_allclose(smp.pos_ned_m[2:], WAYPOINTS[[-1, -1]], atol=1e-12)


def test_x_ref_u_ref_shapes_and_yaw():
    ref = BSplineReference(WAYPOINTS, yaw_rad=0.7)
    assert ref.x_ref(1.0).shape == (4,)
    assert ref.u_ref(np.array([1.0, 2.0])).shape == (2, 4)
    assert ref.x_ref(1.0)[3] == 0.7
    np.testing.assert_allclose(ref.u_ref(2.0)[:3], ref.sample(2.0).vel_ned_mps[0])


@pytest.mark.parametrize(
    "waypoints, match",
    [(np.zeros((1, 3)), "shape"), (np.zeros((3, 2)), "shape"), (np.full((2, 3), np.nan), "finite")],
)
def test_bad_waypoints_raise(waypoints, match):
    with pytest.raises(ValueError, match=match):
        BSplineReference(waypoints)
