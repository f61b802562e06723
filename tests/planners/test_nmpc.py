import dataclasses

import casadi as ca
import numpy as np
import pytest
from planner_test_helpers import DT_S, closed_loop, drag_residual_fn, drag_residual_np

from planners.bspline import BSplineReference
from planners.nmpc import NmpcPlanner
from planners.nmpc_formulation import NmpcConfig
from planners.nominal_models import first_order_lag, kinematic_4dof
from planners.obstacle_map import PointObstacleMap
from planners.obstacles import Cylinder, ObstacleWorld, Sphere
from planners.reference import PlannerState
from planners.residual import ResidualTerm

RESIDUAL_DT_S = 0.1
MODEL = kinematic_4dof(RESIDUAL_DT_S)
STRAIGHT = BSplineReference(np.array([[0.0, 0.0, -2.0], [4.0, 0.0, -2.0], [8.0, 0.0, -2.0]]))


def nominal_plant(x, u, dt_s):
    return MODEL.step_np(x, u, dt_s)


def augmented_plant(x, u, dt_s):
    """The true vehicle: flies the command corrected by the drag residual."""
    vel = u[:3] + RESIDUAL_DT_S * drag_residual_np(u[:3])
    return x + dt_s * np.append(vel, u[3])


def planner(config=None, residual=False, world=None):
    """An NMPC planner with a generous time budget: tests must not depend on machine load."""
    config = config or NmpcConfig()
    if config.time_budget_s == NmpcConfig().time_budget_s:
        config = dataclasses.replace(config, time_budget_s=30.0)
    term = ResidualTerm.of_velocity(drag_residual_fn(), MODEL) if residual else None
    return NmpcPlanner(MODEL, config, term, world, compile_functions=False)


def tracking_rmse(states, reference):
    t = DT_S * np.arange(states.shape[0])
    return float(np.sqrt(np.mean(np.sum((states[:, :3] - reference.x_ref(t)[:, :3]) ** 2, 1))))


def test_tracks_bspline_on_nominal_model(short_reference):
    states, results = closed_loop(planner(), short_reference, nominal_plant, 10.0)
    assert all(r.ok for r in results), [r.reason for r in results if not r.ok][:3]
    assert tracking_rmse(states, short_reference) < 0.01
    np.testing.assert_allclose(states[-1, 3], 0.3, atol=1e-3)  # yaw follows the reference


def test_residual_prediction_matches_augmented_simulation(short_reference):
    res = planner(residual=True).plan(
        PlannerState(np.array([0.0, 0.0, -2.0]), np.zeros(3), 0.3), short_reference, 2.0
    )
    assert res.ok
    x, sim = res.predicted_trajectory[0], [res.predicted_trajectory[0]]
    for u in res.predicted_inputs:  # independent NumPy simulation of eq. 1, 0.1 s steps
        x = x + 0.1 * np.append(u[:3] + RESIDUAL_DT_S * drag_residual_np(u[:3]), u[3])
        sim.append(x)
    np.testing.assert_allclose(res.predicted_trajectory, np.array(sim), atol=1e-9)
    nominal = res.predicted_trajectory[0] + 0.1 * np.cumsum(res.predicted_inputs, axis=0)
    assert np.max(np.abs(nominal - res.predicted_trajectory[1:])) > 0.01  # residual matters


def test_residual_compensates_augmented_plant(short_reference):
    without, _ = closed_loop(planner(), short_reference, augmented_plant, 10.0)
    with_res, results = closed_loop(planner(residual=True), short_reference, augmented_plant, 10.0)
    assert all(r.ok for r in results)
    rmse_without = tracking_rmse(without, short_reference)
    rmse_with = tracking_rmse(with_res, short_reference)
    assert rmse_with < 0.01
    assert rmse_with < 0.4 * rmse_without


def test_bounds_hold():
    fast_ref = BSplineReference(
        np.array([[0.0, 0.0, -2.0], [6.0, 0.0, -0.5], [12.0, 0.0, -2.0]]), max_speed_mps=1.5
    )
    inf = np.inf
    cfg = NmpcConfig(
        input_max=(0.8, 0.8, 0.8, 0.5),
        state_min=(-inf, -inf, -inf, -inf),
        state_max=(inf, inf, -1.5, inf),
    )
    states, results = closed_loop(planner(cfg), fast_ref, nominal_plant, 8.0)
    assert all(r.ok for r in results)
    inputs = np.array([r.command for r in results])
    assert np.all(np.abs(inputs) <= np.array([0.8, 0.8, 0.8, 0.5]) + 1e-6)
    assert np.abs(inputs[:, 0]).max() > 0.79  # the bound is active, so it was tested
    predicted = np.vstack([r.predicted_trajectory[1:] for r in results])
    assert predicted[:, 2].max() <= -1.5 + 1e-6
    assert states[:, 2].max() <= -1.5 + 1e-6  # and the reference wanted -0.5


def test_plan_check_rejects_a_state_bound_violation_when_a_bound_is_finite():
    """The check skips the state bounds only when all are infinite (nothing to violate)."""
    inf = np.inf
    bounded = planner(NmpcConfig(state_min=(-inf,) * 4, state_max=(inf, inf, -1.5, inf)))
    predicted = np.tile([0.0, 0.0, -1.0, 0.0], (21, 1))  # 0.5 m above the ceiling
    inputs, no_slots = np.zeros((20, 4)), np.zeros((20, 0, 7))
    assert bounded._check(predicted, inputs, no_slots) == "plan violates state bounds"
    assert planner()._check(predicted, inputs, no_slots) == ""


@pytest.mark.parametrize("solver", ["fast", pytest.param("ipopt", marks=pytest.mark.slow)])
def test_no_predicted_node_within_safe_distance(solver):
    world = ObstacleWorld([Cylinder((4.0, 0.1), 0.4), Sphere((7.0, -0.2, -2.0), 0.3)])
    cfg = NmpcConfig(solver=solver, safe_distance_m=0.5, max_iterations=30)
    states, results = closed_loop(planner(cfg, world=world), STRAIGHT, nominal_plant, 9.0, 0.1)
    assert all(r.ok for r in results), [r.reason for r in results if not r.ok][:3]
    predicted = np.vstack([r.predicted_trajectory[1:, :3] for r in results])
    assert world.clearance_m(predicted).min() >= 0.5 - 1e-3
    assert world.clearance_m(states[:, :3]).min() >= 0.5 - 0.02  # chords between nodes
    assert world.clearance_m(states[:, :3]).min() < 0.52  # it had to go around
    assert np.linalg.norm(states[-1, :3] - STRAIGHT.x_ref(9.0)[:3]) < 0.05


def test_fast_and_ipopt_agree():
    world = ObstacleWorld([Cylinder((1.5, 0.2), 0.4), Sphere((3.0, -0.9, -2.0), 0.3)])
    state = PlannerState(np.array([0.2, 0.0, -2.0]), np.zeros(3), 0.1)
    plans = {}
    for solver in ("fast", "ipopt"):
        cfg = NmpcConfig(solver=solver, max_iterations=300, time_budget_s=30.0)
        plans[solver] = planner(cfg, residual=True, world=world).plan(state, STRAIGHT, 1.0)
    assert plans["fast"].ok and plans["ipopt"].ok
    np.testing.assert_allclose(
        plans["fast"].predicted_inputs, plans["ipopt"].predicted_inputs, atol=1e-4
    )
    np.testing.assert_allclose(
        plans["fast"].predicted_trajectory, plans["ipopt"].predicted_trajectory, atol=1e-4
    )
    clearance = world.clearance_m(plans["fast"].predicted_trajectory[1:, :3])
    assert clearance.min() < 0.5 + 1e-3  # an obstacle constraint is active


def assert_safe(res, reason_part):
    assert not res.ok
    assert reason_part in res.reason
    np.testing.assert_array_equal(res.command, np.zeros(4))
    assert res.predicted_trajectory.shape == (0, 4)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_state_gives_safe_command(bad):
    res = planner().plan(PlannerState(np.array([0.0, bad, -2.0]), np.zeros(3), 0.0), STRAIGHT, 0.0)
    assert_safe(res, "non-finite")


def test_start_inside_obstacle_gives_safe_command():
    world = ObstacleWorld([Sphere((1.0, 0.0, -2.0), 0.5)])
    res = planner(world=world).plan(
        PlannerState(np.array([1.2, 0.0, -2.0]), np.zeros(3), 0.0), STRAIGHT, 0.0
    )
    assert_safe(res, "inside an obstacle")


def test_a_point_map_world_gives_the_same_plans_as_the_same_cylinders():
    """A world other than an ObstacleWorld (a map of points learnt from scans, duck-typed:
    clearance_m and slots) is checked and sliced through its own methods; its points as
    cylinders in an ObstacleWorld give the same plans, and a start inside one is refused."""
    points = np.array([[3.0, 0.3, -2.0], [5.0, -0.4, -2.0]])
    point_map = PointObstacleMap(point_radius_m=0.2)
    point_map.add_points(points)
    cylinders = ObstacleWorld([Cylinder((p[0], p[1]), 0.2) for p in points])
    cfg = NmpcConfig(n_obstacles=2)
    by_map, by_world = planner(cfg, world=point_map), planner(cfg, world=cylinders)
    state = PlannerState(np.array([0.0, 0.0, -2.0]), np.zeros(3), 0.0)
    for t in (0.0, 0.1, 0.2):
        a, b = by_map.plan(state, STRAIGHT, t), by_world.plan(state, STRAIGHT, t)
        assert a.ok and b.ok
        np.testing.assert_allclose(a.predicted_trajectory, b.predicted_trajectory, atol=1e-9)
    inside = PlannerState(np.array([3.0, 0.35, -2.0]), np.zeros(3), 0.0)
    assert_safe(by_map.plan(inside, STRAIGHT, 0.3), "inside an obstacle")


def test_infeasible_qp_gives_safe_command():
    # 0.6 m inside the 1 m safe zone: one 0.1 s step at 1.5 m/s cannot get out.
    world = ObstacleWorld([Sphere((1.0, 0.0, -2.0), 0.2)])
    cfg = NmpcConfig(safe_distance_m=1.0)
    res = planner(cfg, world=world).plan(
        PlannerState(np.array([1.6, 0.0, -2.0]), np.zeros(3), 0.0), STRAIGHT, 0.0
    )
    assert_safe(res, "clearance")


@pytest.mark.parametrize(
    "cfg, reason",
    [
        (NmpcConfig(solver="ipopt", max_iterations=1), "Maximum_Iterations_Exceeded"),
        (NmpcConfig(solver="fast", time_budget_s=1e-9), "late"),
        (NmpcConfig(solver="ipopt", time_budget_s=1e-9), "solver failed"),
    ],
)
def test_forced_solver_failure_gives_safe_command(cfg, reason):
    world = ObstacleWorld([Cylinder((4.0, 0.1), 0.4)])
    res = planner(cfg, world=world).plan(
        PlannerState(np.array([3.0, 0.0, -2.0]), np.zeros(3), 0.0), STRAIGHT, 3.0
    )
    assert_safe(res, reason)


def test_reference_error_gives_safe_command():
    class Broken:
        duration_s = 1.0

        def sample(self, t_s):
            raise RuntimeError("map server gone")

    res = planner().plan(PlannerState(np.zeros(3), np.zeros(3), 0.0), Broken(), 0.0)
    assert_safe(res, "map server gone")


def test_yaw_is_compared_on_the_reference_branch(short_reference):
    yaw = 0.3 + 2 * np.pi  # same heading as the reference, one turn apart
    res = planner().plan(
        PlannerState(np.array([0.0, 0.0, -2.0]), np.zeros(3), yaw), short_reference, 0.0
    )
    assert res.ok
    assert abs(res.command[3]) < 1e-6


def test_first_order_lag_model_plans(short_reference):
    model = first_order_lag(0.3)
    lag = NmpcPlanner(
        model,
        NmpcConfig(state_weights=(10, 10, 10, 1, 1, 1, 10), time_budget_s=30.0),
        compile_functions=False,
    )
    res = lag.plan(PlannerState(np.array([0.0, 0.0, -2.0]), np.zeros(3), 0.3), short_reference, 1.0)
    assert res.ok
    assert res.predicted_trajectory.shape == (21, 7)
    assert res.command[0] > 0.3  # it speeds up towards the moving reference


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"solver": "acados"}, "choose one of fast, ipopt"),
        ({"horizon_steps": 0}, "horizon_steps"),
        ({"dt_s": 0.0}, "dt_s"),
        ({"max_iterations": 0}, "max_iterations"),
    ],
)
def test_bad_config_raises(kwargs, match):
    with pytest.raises(ValueError, match=match):
        NmpcConfig(**kwargs)


def test_wrong_sizes_raise():
    with pytest.raises(ValueError, match="state_weights must have 4"):
        planner(NmpcConfig(state_weights=(1.0, 1.0)))
    v = ca.SX.sym("v", 2)
    with pytest.raises(ValueError, match="3-vector"):
        ResidualTerm.of_velocity(ca.Function("bad", [v], [v]), MODEL)
    z = ca.SX.sym("z", 5)
    with pytest.raises(ValueError, match="expects z of size 5"):
        NmpcPlanner(
            MODEL,
            residual=ResidualTerm.of_velocity(ca.Function("g", [z], [z[:3]]), MODEL),
            compile_functions=False,
        )


def test_residual_with_variance_output_uses_the_mean(short_reference):
    v = ca.SX.sym("v", 3)
    mean = drag_residual_fn()(v)
    with_var = ca.Function("mean_var", [v], [mean, ca.DM.ones(3) * 7.0])
    state = PlannerState(np.array([0.0, 0.0, -2.0]), np.zeros(3), 0.3)
    plans = [
        NmpcPlanner(
            MODEL, NmpcConfig(time_budget_s=30.0), ResidualTerm.of_velocity(fn, MODEL)
        ).plan(state, short_reference, 2.0)
        for fn in (drag_residual_fn(), with_var)  # a generous budget: independent of load
    ]
    np.testing.assert_allclose(plans[0].predicted_trajectory, plans[1].predicted_trajectory)


def test_plans_without_obstacle_slots(short_reference):
    res = planner(NmpcConfig(n_obstacles=0)).plan(
        PlannerState(np.array([0.0, 0.0, -2.0]), np.zeros(3), 0.3), short_reference, 1.0
    )
    assert res.ok
    np.testing.assert_allclose(res.predicted_trajectory[-1], short_reference.x_ref(3.0), atol=0.05)
