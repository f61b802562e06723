"""The fast path's batched linearisation plans what the symbolic one plans, on a learned model.

A sparse GP on position_velocity features (the wind_field regime's shape) is fitted to a
seeded spatial disturbance (a shear layer whose strength, width and offset are drawn at random)
and flown as the companion flies it: first_order_lag + the clipped GP mean. Over a closed loop
of plans with obstacles on the path, both linearisations must give the same QP data and the
same commands.
"""

from __future__ import annotations

import numpy as np
import pytest

from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from gp.features import feature_definition
from gp.inducing import InducingConfig
from gp.model_io import ResidualModel
from gp.sparse_gp import SparseGP
from planners.bspline import BSplineReference
from planners.nmpc import NmpcPlanner
from planners.obstacles import Cylinder, ObstacleWorld
from planners.reference import PlannerState
from planners.sqp_solver import GaussNewtonSqp, SqpOptions

SEED = 20261123


def _learned_wind_model(rng: np.random.Generator) -> ResidualModel:
    """An SGPR (m = 20 per output) fitted to a drawn shear layer's residual on (pos_n, pos_e,
    vel_n, vel_e, vel_d)."""
    strength = rng.uniform(1.0, 3.0)  # [m/s^2]
    width = rng.uniform(1.5, 4.0)  # [m]
    offset = rng.uniform(-1.0, 1.0)  # [m]
    x = np.column_stack(
        [rng.uniform(-2, 12, 400), rng.uniform(-6, 6, 400), rng.normal(0, 1.0, (400, 3))]
    )
    shear = strength * np.tanh((x[:, 1] - offset) / width)
    y = np.column_stack([shear - 0.3 * x[:, 2], 0.4 * shear, -0.2 * x[:, 4]])
    y += rng.normal(0.0, 0.05, y.shape)
    features = feature_definition("position_velocity", "first_order_lag", tau_s=0.7, tau_d_s=0.4)
    gp = SparseGP(
        inducing=InducingConfig("random", m=20), n_restarts=1, max_iter=60, random_state=SEED
    ).fit(x, y)
    training = {"residual_mean": y.mean(axis=0).tolist(), "residual_std": y.std(axis=0).tolist()}
    return ResidualModel.from_estimator(gp, features, training=training)


@pytest.fixture(scope="module")
def planners():
    rng = np.random.default_rng(SEED)
    model = _learned_wind_model(rng)
    settings = NmpcSettings(speed_limit_mps=4.0, time_budget_s=30.0, n_obstacles=4)
    companion = CompanionNmpc(settings, model)
    f = companion._planner.formulation
    assert f.residual is not None and f.residual.batch is not None  # the GP flies
    world = ObstacleWorld([Cylinder((rng.uniform(4.0, 6.0), rng.uniform(0.5, 1.5)), 0.5)])
    built = {}
    for kind in ("batched", "symbolic"):
        built[kind] = NmpcPlanner(
            f.model,
            f.config,
            f.residual,
            world,
            solver_factory=lambda form, k=kind: GaussNewtonSqp(form, SqpOptions(linearisation=k)),
        )
    return built, rng


def test_batched_qp_data_equals_the_symbolic_linearisation(planners):
    built, rng = planners
    f = built["batched"].formulation
    for _ in range(3):
        w = rng.normal(0.0, 2.0, f.n_w)
        p = rng.normal(0.0, 2.0, f.n_p)
        p[-f.config.n_obstacles * f.config.horizon_steps * 7 :] = np.tile(
            [5.0, 1.0, -3.0, 1.0, 1.0, 0.0, 1.0], f.config.n_obstacles * f.config.horizon_steps
        )
        batched = built["batched"]._solver._lin(w, p)
        symbolic = built["symbolic"]._solver._lin(w, p)
        for got, want in zip(batched, symbolic, strict=True):
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def test_batched_plans_equal_the_symbolic_plans_in_closed_loop(planners):
    built, _ = planners
    ref = BSplineReference(
        np.array([[0.0, 0.0, -3.0], [4.0, 2.0, -3.0], [8.0, 0.0, -3.5], [12.0, -1.0, -3.0]]), 2.0
    )
    commands = {}
    for kind, planner in built.items():
        planner.reset()
        pos, vel, out = np.array([0.0, 0.0, -3.0]), np.zeros(3), []
        for k in range(60):
            result = planner.plan(PlannerState(pos.copy(), vel.copy(), 0.0), ref, 0.1 * k)
            assert result.ok, result.reason
            out.append(result.command)
            vel = vel + 0.1 * (result.command[:3] - vel) / 0.7
            pos = pos + 0.1 * vel
        commands[kind] = np.array(out)
    # rounding (1e-15 in the QP data) can tip an early stop or an active set: 1e-5 m/s
    np.testing.assert_allclose(commands["batched"], commands["symbolic"], atol=1e-5)
    # the obstacle and the learned residual shape the plan: it is not the reference velocity
    assert np.max(np.abs(commands["batched"][:, :3])) > 0.5
