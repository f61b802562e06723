"""The companion's planner with a learned model of the flying shape (first_order_lag + an
SE-kernel GP on state_input features, m = 30 per output) solves its problem as IPOPT does."""

from __future__ import annotations

import dataclasses

import numpy as np

from companion.nmpc_planner import NmpcSettings, load_nmpc
from experiments.bench.nmpc import flying_model
from gp.model_io import save_model
from planners.bspline import BSplineReference
from planners.nmpc import NmpcPlanner
from planners.reference import PlannerState


def test_companion_fast_path_gives_ipopts_command_with_a_learned_model(tmp_path):
    path = save_model(tmp_path / "model", flying_model())
    settings = NmpcSettings(speed_limit_mps=2.5, time_budget_s=30.0, max_iterations=300)
    companion = load_nmpc(settings, path)
    assert companion.augmented
    f = companion._planner.formulation
    ipopt = NmpcPlanner(
        f.model, dataclasses.replace(f.config, solver="ipopt"), f.residual, compile_functions=False
    )
    ref = BSplineReference(np.array([[0.0, 0.0, -2.0], [3.0, 1.0, -2.5], [6.0, 0.0, -2.0]]))
    state = PlannerState(np.array([0.1, -0.2, -2.1]), np.array([0.4, 0.1, 0.0]), 0.05)
    fast_plan = companion.plan(state, ref, 0.5)
    ipopt_plan = ipopt.plan(state, ref, 0.5)
    assert fast_plan.ok and ipopt_plan.ok
    np.testing.assert_allclose(fast_plan.command, ipopt_plan.command, atol=1e-4)
    np.testing.assert_allclose(fast_plan.predicted_inputs, ipopt_plan.predicted_inputs, atol=1e-4)
    # The learned residual matters on this problem: without it the command differs.
    nominal = NmpcPlanner(
        f.model, dataclasses.replace(f.config, solver="ipopt"), None, compile_functions=False
    ).plan(state, ref, 0.5)
    assert np.max(np.abs(nominal.command - fast_plan.command)) > 1e-2
