import numpy as np
import pytest
from scipy.spatial import cKDTree

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


RAMP_JERK_MPS3 = 4.0  # PX4's MPC_JERK_AUTO default


def _ramped_and_plain(max_speed_mps=3.0, max_acc_mps2=2.0):
    plain = BSplineReference(WAYPOINTS, max_speed_mps, max_acc_mps2)
    ramped = BSplineReference(WAYPOINTS, max_speed_mps, max_acc_mps2, ramp_jerk_mps3=RAMP_JERK_MPS3)
    return ramped, plain


def test_no_ramp_is_the_plain_spline_bit_for_bit():
    plain = BSplineReference(WAYPOINTS, 3.0, 2.0)
    explicit = BSplineReference(WAYPOINTS, 3.0, 2.0, ramp_jerk_mps3=None)
    assert plain.ramp_s == 0.0 and plain.duration_s == plain.segment_duration_s * 4
    assert explicit.duration_s == plain.duration_s
    t = np.linspace(-1.0, plain.duration_s + 1.0, 2001)
    a, b = plain.sample(t), explicit.sample(t)
    for field in ("pos_ned_m", "vel_ned_mps", "acc_ned_mps2"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def test_ramped_acceleration_rises_from_zero_with_bounded_jerk():
    ramped, plain = _ramped_and_plain()
    assert np.linalg.norm(plain.sample(1e-6).acc_ned_mps2) > 1.0  # the plain step
    for t in (1e-6, ramped.duration_s - 1e-6):
        assert np.linalg.norm(ramped.sample(t).acc_ned_mps2) < 1e-6
        assert np.linalg.norm(ramped.sample(t).vel_ned_mps) < 1e-6
    t = np.linspace(0.0, ramped.duration_s, 200001)
    smp = ramped.sample(t)
    jerk = np.linalg.norm(np.diff(smp.acc_ned_mps2, axis=0), axis=1) / np.diff(t)
    assert np.max(jerk) <= 1.02 * RAMP_JERK_MPS3  # continuous acceleration, bounded jerk
    in_ramps = (t[1:] < ramped.ramp_s) | (t[:-1] > ramped.duration_s - ramped.ramp_s)
    assert np.max(jerk[in_ramps]) > 0.98 * RAMP_JERK_MPS3  # the ramps as short as the jerk allows
    accel = np.linalg.norm(np.diff(smp.vel_ned_mps, axis=0), axis=1) / np.diff(t)
    assert np.max(accel) <= 2.0 + 1e-6  # continuous velocity


def test_ramped_path_is_the_plain_path():
    ramped, plain = _ramped_and_plain()
    np.testing.assert_array_equal(ramped.control_points_ned_m, plain.control_points_ned_m)
    assert ramped.length_m() == plain.length_m()
    dense = plain.sample(np.linspace(0.0, plain.duration_s, 400001)).pos_ned_m
    pos = ramped.sample(np.linspace(0.0, ramped.duration_s, 997)).pos_ned_m
    gaps, _ = cKDTree(dense).query(pos)  # each point's exact distance to its nearest dense one
    assert max(gaps) < 1e-3  # on the plain path (dense spacing about 0.1 mm)
    np.testing.assert_allclose(pos[[0, -1]], WAYPOINTS[[0, -1]], atol=1e-12)


def test_between_the_ramps_the_plain_reference_delayed_by_a_third_of_a_ramp():
    ramped, plain = _ramped_and_plain()
    assert ramped.segment_duration_s == plain.segment_duration_s  # the limits held as planned
    delay_s = ramped.ramp_s / 3.0
    np.testing.assert_allclose(ramped.duration_s, plain.duration_s + 2.0 * delay_s)
    t = np.linspace(ramped.ramp_s, ramped.duration_s - ramped.ramp_s, 101)
    a, b = ramped.sample(t), plain.sample(t - delay_s)
    np.testing.assert_allclose(a.pos_ned_m, b.pos_ned_m, atol=1e-9)
    np.testing.assert_allclose(a.vel_ned_mps, b.vel_ned_mps, atol=1e-9)
    np.testing.assert_allclose(a.acc_ned_mps2, b.acc_ned_mps2, atol=1e-9)


@pytest.mark.parametrize("max_speed_mps, max_acc_mps2", [(1.5, 1.0), (0.5, 0.2), (3.0, 5.0)])
def test_ramped_reference_respects_limits(max_speed_mps, max_acc_mps2):
    ref = BSplineReference(WAYPOINTS, max_speed_mps, max_acc_mps2, ramp_jerk_mps3=RAMP_JERK_MPS3)
    smp = ref.sample(np.linspace(0.0, ref.duration_s, 20001))
    assert np.linalg.norm(smp.vel_ned_mps, axis=1).max() <= max_speed_mps + 1e-9
    assert np.linalg.norm(smp.acc_ned_mps2, axis=1).max() <= max_acc_mps2 + 1e-9


@pytest.mark.parametrize("jerk", [0.0, float("nan"), float("inf")])
def test_bad_ramp_jerk_raises(jerk):
    """An infinite jerk passed "> 0" and made a zero-length ramp: a NaN duration."""
    with pytest.raises(ValueError, match="ramp_jerk_mps3"):
        BSplineReference(WAYPOINTS, ramp_jerk_mps3=jerk)
