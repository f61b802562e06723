"""The acados peer of `bench --only nmpc` solves our formulation as IPOPT does (when installed:
`make acados`), obstacle constraints included."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from experiments.bench.acados_peer import AcadosSolver, acados_unavailable
from experiments.bench.nmpc import gp_like_residual
from planners.bspline import BSplineReference
from planners.nmpc import NmpcPlanner
from planners.nmpc_formulation import NmpcConfig
from planners.nominal_models import kinematic_4dof
from planners.obstacles import Cylinder, ObstacleWorld, Sphere
from planners.reference import PlannerState
from planners.residual import ResidualTerm


@pytest.mark.skipif(bool(acados_unavailable()), reason=acados_unavailable() or "available")
def test_acados_peer_agrees_with_ipopt_with_an_active_obstacle(tmp_path):
    model = kinematic_4dof(0.05)
    residual = ResidualTerm.of_velocity(gp_like_residual(), model)
    world = ObstacleWorld([Cylinder((1.5, 0.2), 0.4), Sphere((3.0, -0.9, -2.0), 0.3)])
    ref = BSplineReference(np.array([[0.0, 0.0, -2.0], [4.0, 0.0, -2.0], [8.0, 0.0, -2.0]]))
    state = PlannerState(np.array([0.2, 0.0, -2.0]), np.zeros(3), 0.1)
    cfg = NmpcConfig(time_budget_s=30.0)
    peer = NmpcPlanner(
        model, cfg, residual, world, solver_factory=lambda f: AcadosSolver(f, tmp_path)
    )
    ipopt = NmpcPlanner(model, dataclasses.replace(cfg, solver="ipopt"), residual, world)
    # A few plans at the same time: RTI converges over calls from its own warm start.
    for _ in range(3):
        plan = peer.plan(state, ref, 1.0)
    reference_plan = ipopt.plan(state, ref, 1.0)
    assert plan.ok and reference_plan.ok
    np.testing.assert_allclose(plan.predicted_inputs, reference_plan.predicted_inputs, atol=1e-3)
    clearance = world.clearance_m(reference_plan.predicted_trajectory[1:, :3])
    assert clearance.min() < 0.5 + 1e-3  # the obstacle constraint is active
