"""Taught path, [Ostafew16] errors, the speed scheduler (eq. 31) and the unicycle NMPC."""

import math

import numpy as np
import pytest

from planners.rover.path import LocalisationQuality, TaughtPath, project_arc_length
from planners.rover.speed_scheduler import TABLE_I, SpeedSchedulerConfig, next_schedule
from planners.rover.unicycle_nmpc import (
    ConstantDisturbance,
    UnicycleNmpc,
    UnicycleNmpcConfig,
    rollout,
    unicycle_rollout,
)


def test_errors_against_the_nearest_vertex_follow_the_paper_sign_convention() -> None:
    path = TaughtPath.from_segments([(10.0, 0.0)])
    fix = path.localise(4.0, 0.3, 0.1)  # left of the path, nose turned left
    assert fix.vertex == 16
    assert fix.e_lat_m == pytest.approx(-0.3)  # x_d - x in the vertex frame
    assert fix.e_head_rad == pytest.approx(-0.1)


def test_errors_on_the_path_carry_no_vertex_spacing_on_a_turn() -> None:
    # A robot exactly on a 1 1/m arc, facing along it, midway between two 0.25 m vertices: the
    # nearest vertex's heading differs from the robot's by curvature * 0.125 m; the path pose
    # at its projection ([Ostafew16] "when passing the vertex") does not.
    path = TaughtPath.from_segments([(1.0, 0.0), (math.pi / 2, 1.0), (1.0, 0.0)])
    i = int(np.searchsorted(path.s_m, 1.5))
    s = 0.5 * (path.s_m[i] + path.s_m[i + 1])  # on the arc, midway between two vertices
    x, y = 1.0 + math.sin(s - 1.0), 1.0 - math.cos(s - 1.0)
    fix, on_path = path.localise(x, y, s - 1.0), path.localise_on_path(x, y, s - 1.0)
    assert abs(fix.e_head_rad) == pytest.approx(path.spacing_m / 2, abs=0.01)
    assert on_path.e_head_rad == pytest.approx(0.0, abs=0.01)
    sagitta = path.spacing_m**2 / 8  # the chord between the vertices lies this far inside
    assert on_path.e_lat_m == pytest.approx(sagitta, abs=0.002)
    assert on_path.s_m == pytest.approx(s, abs=0.01)
    left = path.localise_on_path(x - 0.1 * math.sin(s - 1.0), y + 0.1 * math.cos(s - 1.0), s - 1.0)
    # the paper's sign, as localise's: left of the path is negative
    assert left.e_lat_m == pytest.approx(sagitta - 0.1, abs=0.002)


@pytest.mark.parametrize("radius", [0.7, 1.3])
def test_a_fix_off_an_arc_projects_along_the_radius(radius: float) -> None:
    """A robot 0.3 m inside or outside a 1 m-radius left arc, on the radius through the
    midpoint between two vertices, projects onto that midpoint (the chord's perpendicular
    bisector), although the nearest vertex's tangent puts it radius * sin(0.125) - 0.125 =
    -0.038 or +0.037 m along; e_L is the offset (positive outside: right of a left turn) plus
    the chord's sagitta spacing^2 / 8."""
    path = TaughtPath.from_segments([(1.0, 0.0), (math.pi / 2, 1.0), (1.0, 0.0)])
    i = int(np.searchsorted(path.s_m, 1.5))
    s = 0.5 * (path.s_m[i] + path.s_m[i + 1])
    x, y = 1.0 + radius * math.sin(s - 1.0), 1.0 - radius * math.cos(s - 1.0)
    assert abs(path.localise(x, y, s - 1.0).s_m - s) > 0.03
    fix = path.localise_on_path(x, y, s - 1.0)
    assert fix.s_m == pytest.approx(s, abs=0.005)
    assert fix.e_lat_m == pytest.approx(radius - 1.0 + path.spacing_m**2 / 8, abs=0.002)


def test_arc_length_of_points_beside_a_path_heading_north() -> None:
    """On a straight path from (0, 0) north to (0, 10), a point's arc length is its north
    coordinate [m], whatever its sideways offset."""
    path = TaughtPath.from_csv_text("0,0\n0,5\n0,10\n")
    points = np.array([[0.0, 2.3], [0.4, 2.3], [-0.4, 6.61]])
    np.testing.assert_allclose(project_arc_length(path, points, hint=0), [2.3, 2.3, 6.61])


def test_path_from_csv_text_and_bad_rows() -> None:
    path = TaughtPath.from_csv_text("x_m,y_m\n0,0\n1,0\n2,0\n", spacing_m=0.5)
    assert len(path) == 5 and path.length_m == pytest.approx(2.0)
    with pytest.raises(ValueError, match="line 2"):
        TaughtPath.from_csv_text("0,0\n1,a\n2,0\n")
    # a non-finite coordinate is named by its line, not as "needs >= 3 rows, got (3, 2)"
    for bad in ("nan", "inf"):
        with pytest.raises(ValueError, match=r"line 3: .*not finite"):
            TaughtPath.from_csv_text(f"x_m,y_m\n0,0\n1,{bad}\n2,0\n")
    # only the first line may be a header: a later 'nan,...' row is not skipped as one
    with pytest.raises(ValueError, match=r"line 3: .*not finite"):
        TaughtPath.from_csv_text("x_m,y_m\n0,0\nnan,1\n2,0\n3,0\n")
    # nor is a later row of words (a second header pasted in, a note): it is named, not dropped
    with pytest.raises(ValueError, match="line 3"):
        TaughtPath.from_csv_text("x_m,y_m\n0,0\nnorth,1\n2,0\n3,0\n")
    # a path that never moves has no heading to repeat
    with pytest.raises(ValueError, match="zero length"):
        TaughtPath.from_csv_text("0,0\n0,0\n0,0\n")


def test_the_nearest_vertex_is_searched_a_quarter_window_behind_the_hint() -> None:
    """On a straight 10 m path with 0.25 m vertices (vertex i at x = 0.25 i m), a robot at
    x = 4 m is at vertex 16: found from a hint of 20 (the search starts 40 // 4 = 10 vertices
    back), not from a hint of 30 (it starts at vertex 20, the nearest it can see)."""
    path = TaughtPath.from_segments([(10.0, 0.0)])
    assert path.nearest(4.0, 0.1, hint=20) == 16
    assert path.localise(4.0, 0.1, 0.0, hint=20).vertex == 16
    assert path.nearest(4.0, 0.1, hint=30) == 20


def test_the_matched_feature_count_follows_light_errors_and_speed() -> None:
    """count = 120 lighting exp(-(e_L / 0.5)^2 - (e_H / 0.35)^2) / (1 + (v / 1.5)^2): in half
    light at rest on the path, 60; at 1.5 m/s (blur halves it), 30; 0.5 m off the path in
    full light at rest, 120 / e; 0.35 rad off in heading, the same."""
    q = LocalisationQuality()
    assert q.count(0.5, 0.0, 0.0, 0.0) == pytest.approx(60.0)
    assert q.count(0.5, 0.0, 0.0, 1.5) == pytest.approx(30.0)
    assert q.count(1.0, 0.5, 0.0, 0.0) == pytest.approx(120.0 / math.e)
    assert q.count(1.0, 0.0, -0.35, 0.0) == pytest.approx(120.0 / math.e)


def test_arc_curvature() -> None:
    path = TaughtPath.from_segments([(2.0, 0.0), (math.pi, 0.5), (2.0, 0.0)])
    assert np.max(np.abs(path.curvature_1pm())) == pytest.approx(0.5, abs=0.02)


def test_scheduler_raises_lowers_and_keeps_by_eq_31() -> None:
    c = TABLE_I["experiment_2"]
    v = np.full(4, 0.5)
    el = np.array([0.05, 0.2, 0.16, 0.05])  # ok, too big, in the deadband, ok
    eh = np.zeros(4)
    om = np.array([0.1, 0.1, 0.1, 0.1])
    feats = np.array([100.0, 100.0, 100.0, 10.0])  # last: too few features
    out = next_schedule(v, el, eh, om, feats, c)
    assert out == pytest.approx([0.65, 0.4, 0.5, 0.4])


def test_feature_counts_in_the_deadband_keep_the_speed() -> None:
    """Eq. 31 with lambda_F = 30 and lambda_db = 1.1: more than 30 features (the rest small)
    raise the speed, fewer than 30 / 1.1 = 27.3 lower it, 28 and 30 keep it."""
    c = TABLE_I["experiment_2"]
    feats = np.array([31.0, 30.0, 28.0, 27.0])
    small = np.full(4, 0.01)
    out = next_schedule(np.full(4, 0.5), small, small, small, feats, c)
    assert out == pytest.approx([0.5 + c.gamma_up_mps, 0.5, 0.5, 0.5 - c.gamma_down_mps])


def test_scheduler_never_schedules_below_the_first_trials_speed() -> None:
    # [Ostafew16] reports no scheduled speed below 0.35 m/s; errors everywhere keep v_init
    for c in TABLE_I.values():
        v = np.array([c.v_init_mps, c.v_init_mps + 0.05, 1.0])
        out = next_schedule(v, np.full(3, 0.5), np.full(3, 0.5), np.full(3, 2.0),
                            np.full(3, 1.0), c)  # fmt: skip
        assert out == pytest.approx([c.v_init_mps, c.v_init_mps, 1.0 - c.gamma_down_mps])


def test_the_scheduler_judges_errors_and_turn_commands_by_their_size_on_either_side() -> None:
    """Eq. 31 compares |e_L|, |e_H| and |omega_cmd| with their thresholds: 0.3 m to the left
    of the path (e_L = -0.3 m, twice lambda_L = 0.15 m) lowers the speed as 0.3 m to the right
    does, and so do a heading error of -20 deg (lambda_H 10 deg) and a -2 rad/s turn command
    (lambda_omega 1 rad/s)."""
    c = TABLE_I["experiment_2"]
    small = np.full(4, 0.01)
    el, eh, om = small.copy(), small.copy(), small.copy()
    el[0], el[1], eh[2], om[3] = -0.3, 0.3, -math.radians(20.0), -2.0
    out = next_schedule(np.full(4, 0.5), el, eh, om, np.full(4, 100.0), c)
    assert out == pytest.approx(np.full(4, 0.5 - c.gamma_down_mps))


def test_a_turn_command_in_the_deadband_or_an_error_at_its_threshold_keeps_the_speed() -> None:
    """Eq. 31 raises a vertex's speed only where every record is under its threshold: a turn
    command of 1.05 rad/s (over lambda_omega = 1 rad/s, under 1.1 x 1 in the deadband) keeps
    the speed although errors and features are fine; so does e_L equal to lambda_L = 0.15 m
    (not under it, and not over 1.1 x 0.15 m); all small raises it."""
    c = TABLE_I["experiment_2"]
    el = np.array([0.01, 0.15, 0.01])
    om = np.array([1.05, 0.01, 0.01])
    out = next_schedule(np.full(3, 0.5), el, np.full(3, 0.01), om, np.full(3, 100.0), c)
    assert out == pytest.approx([0.5, 0.5, 0.5 + c.gamma_up_mps])


def test_a_vertex_with_any_record_missing_keeps_its_speed() -> None:
    """A vertex the pass has no full record of (NaN: never passed, or its errors not measured
    there) keeps its speed, even when the one record it has, here 5 matched features (under
    lambda_F / lambda_db = 27), would lower it; a vertex fully recorded with as few features is
    lowered by gamma_down = 0.1 m/s."""
    c = TABLE_I["experiment_2"]
    nan = np.array([math.nan, 0.01])
    out = next_schedule(np.full(2, 0.8), nan, nan, nan, np.array([5.0, 5.0]), c)
    assert out == pytest.approx([0.8, 0.7])


@pytest.mark.parametrize("v_init", [0.3, 1.3])
def test_a_first_trial_speed_outside_the_schedules_bounds_is_refused(v_init: float) -> None:
    """The schedule is kept in [v_min, v_max] = [0.35, 1.2] m/s from the first trial on, so a
    first-trial speed under or over them (0.3 or 1.3 m/s) is refused, not flown once."""
    with pytest.raises(ValueError, match="v_init_mps"):
        SpeedSchedulerConfig(v_init_mps=v_init, v_min_mps=0.35, v_max_mps=1.2)


def test_nmpc_turns_towards_a_path_on_its_left_and_learned_drift_changes_the_answer() -> None:
    nmpc = UnicycleNmpc()
    K = nmpc.config.horizon
    v = np.full(K, 0.5)
    ref = np.column_stack([0.05 * np.arange(1, K + 1), np.full(K, 0.3), np.zeros(K)])
    w0 = nmpc.solve(np.zeros(3), v, ref, 0.0)
    assert w0[0] > 0
    drift = ConstantDisturbance((0.0, 0.2, 0.0))  # a learned push to the left: turn less
    nmpc.reset()
    w1 = nmpc.solve(np.zeros(3), v, ref, 0.0, model=drift)
    assert w1[0] < w0[0]
    assert nmpc.last_rollout is not None  # the plan was predicted with the learned push
    np.testing.assert_allclose(nmpc.last_rollout.g, np.tile([0.0, 0.2, 0.0], (K, 1)))


@pytest.mark.parametrize("heading", [0.0, math.pi / 2])
def test_rollout_adds_the_disturbance_in_the_robot_frame(heading: float) -> None:
    """0.5 m/s ahead plus a 0.2 m/s push to the robot's left for 1.5 s, no turning: 0.75 m
    along the heading and 0.3 m to its left; a yaw disturbance of 0.1 rad/s turns it 0.15 rad."""
    K, dt = 15, 0.1
    c, s = math.cos(heading), math.sin(heading)
    poses = unicycle_rollout(
        np.array([1.0, 2.0, heading]),
        np.full(K, 0.5),
        np.zeros(K),
        np.tile([0.0, 0.2, 0.0], (K, 1)),
        dt,
    )
    np.testing.assert_allclose(
        poses[-1], [1.0 + 0.75 * c - 0.3 * s, 2.0 + 0.75 * s + 0.3 * c, heading], atol=1e-12
    )
    turned = unicycle_rollout(
        np.zeros(3), np.zeros(K), np.zeros(K), np.tile([0.0, 0.0, 0.1], (K, 1)), dt
    )
    np.testing.assert_allclose(turned[-1], [0.0, 0.0, 0.15], atol=1e-12)


class _LinearYawModel:
    """g_yaw = c . a: a disturbance that depends on the query, to check the chain rule."""

    has_jacobian = True

    def __init__(self, c: np.ndarray) -> None:
        self.c = c

    def mean_and_jacobian(self, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        J = np.zeros((3, 8))
        J[2] = self.c
        J[1] = 0.5 * self.c
        return np.array([0.0, 0.5 * self.c @ query, self.c @ query]), J


def test_rollout_derivatives_match_finite_differences_through_the_learned_model() -> None:
    rng = np.random.default_rng(4)
    K = 8
    model = _LinearYawModel(rng.normal(0, 0.3, 8))
    x0, prev = np.array([0.2, -0.1, 0.3]), np.array([0.17, -0.11, 0.28])
    v, w = np.full(K, 0.6), rng.normal(0, 0.4, K)
    ref = np.column_stack([0.06 * np.arange(K), 0.1 * np.ones(K), 0.05 * np.ones(K)])
    ro = rollout(x0, prev, 2.0, v, w, 0.1, 0.1, model, ref)
    num = np.empty_like(ro.d_poses)
    for j in range(K):
        e = np.zeros(K)
        e[j] = 1e-6
        hi = rollout(x0, prev, 2.0, v, w + e, 0.1, 0.1, model, ref).poses
        lo = rollout(x0, prev, 2.0, v, w - e, 0.1, 0.1, model, ref).poses
        num[:, :, j] = (hi - lo) / 2e-6
    assert np.abs(num - ro.d_poses).max() < 1e-7
    assert np.abs(ro.d_poses).max() > 0.01


class _NoChainModel(_LinearYawModel):
    """The same disturbance, its Jacobian declared zero: the solver takes the closed form."""

    has_jacobian = False


class _ZeroJacobianModel(_LinearYawModel):
    """The same disturbance with a zero Jacobian declared: the step-by-step recursion."""

    def mean_and_jacobian(self, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return super().mean_and_jacobian(query)[0], np.zeros((3, 8))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_closed_form_derivatives_equal_the_step_by_step_recursion_bit_for_bit(seed: int) -> None:
    # Without dg/du, rollout fills d pose / d omega by cumulative sums after the loop (the fast
    # path of every experiment without gp_jacobian); it must give the very numbers the general
    # per-step recursion gives, so that the commands do not change.
    rng = np.random.default_rng(seed)
    K = 25
    c = rng.normal(0, 0.3, 8)
    x0, prev = rng.normal(0, 0.2, 3), rng.normal(0, 0.2, 3)
    v, w = rng.uniform(0.3, 1.2, K), rng.normal(0, 0.6, K)
    ref = np.column_stack([0.05 * np.arange(K), rng.normal(0, 0.1, K), rng.normal(0, 0.1, K)])
    fast = rollout(x0, prev, 2.0, v, w, 0.3, 0.1, _NoChainModel(c), ref)
    slow = rollout(x0, prev, 2.0, v, w, 0.3, 0.1, _ZeroJacobianModel(c), ref)
    assert np.array_equal(fast.poses, slow.poses) and np.array_equal(fast.g, slow.g)
    assert np.array_equal(fast.d_poses, slow.d_poses)
    assert np.abs(fast.d_poses[:, :2]).max() > 0.01
    plain = rollout(x0, prev, 2.0, v, w, 0.3, 0.1)  # no model at all
    assert np.array_equal(unicycle_rollout(x0, v, w, np.zeros((K, 3)), 0.1), plain.poses)
    assert np.array_equal(unicycle_rollout(x0, v, w, slow.g, 0.1), slow.poses)


def test_turn_rate_penalty_from_the_path_feedforward_keeps_a_heavy_r_omega_on_an_arc() -> None:
    cfg = UnicycleNmpcConfig(r_omega=10.0, r_delta=1.0, q_lat=10.0, q_head=1.0)
    K, v, curv = cfg.horizon, 0.5, 0.4
    s = v * cfg.dt_s * np.arange(1, K + 1)
    ref = np.column_stack([np.sin(curv * s) / curv, (1 - np.cos(curv * s)) / curv, curv * s])
    plain = UnicycleNmpc(cfg).solve(np.zeros(3), np.full(K, v), ref, v * curv)
    ff = UnicycleNmpc(cfg).solve(
        np.zeros(3), np.full(K, v), ref, v * curv, omega_ref_radps=np.full(K, v * curv)
    )
    assert abs(ff[0] - v * curv) < 0.01  # on the arc already: keep turning at v * curvature
    assert plain[0] < 0.8 * v * curv  # u^T R u pulls the turn rate towards zero (inside the arc)
