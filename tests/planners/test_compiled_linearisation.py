"""The compiled linearisation plans what the NumPy one plans, serves every model of its shape
from one library, and without a C compiler the planner still flies on the NumPy path.

The problem is the benchmark's shape: kinematic_4dof with an SE-kernel GP-like residual of the
velocity given only as a CasADi Function (no batched form), obstacles on the path, a closed
loop of real-time iterations.
"""

from __future__ import annotations

import os
import shlex
import shutil

import casadi as ca
import numpy as np
import pytest

from planners.bspline import BSplineReference
from planners.compiled_linearisation import CompiledLinearisation
from planners.constants_as_inputs import constants_as_input
from planners.nmpc import NmpcPlanner
from planners.nmpc_formulation import NmpcConfig
from planners.nominal_models import kinematic_4dof
from planners.obstacles import Cylinder, ObstacleWorld
from planners.reference import PlannerState
from planners.residual import ResidualTerm
from planners.sqp_solver import GaussNewtonSqp, SqpOptions

needs_cc = pytest.mark.skipif(
    shutil.which(shlex.split(os.environ.get("CC") or "cc")[0]) is None, reason="needs a C compiler"
)


def gp_like(seed: int) -> ca.Function:
    """g(v) = k(v, Z) alpha [m/s^2]: SE kernel, 12 seeded inducing velocities Z (12, 3) [m/s]."""
    rng = np.random.default_rng(seed)
    inducing, alpha = rng.uniform(-1.5, 1.5, (12, 3)), rng.normal(0.0, 0.5, (12, 3))
    v = ca.SX.sym("v", 3)
    k = 0.5 * ca.exp(-0.5 * ca.sum2((ca.repmat(v.T, 12, 1) - ca.DM(inducing)) ** 2) / 0.49)
    return ca.Function("gp_like", [v], [(k.T @ ca.DM(alpha)).T])


def planner(linearisation: str, seed: int = 1) -> NmpcPlanner:
    model = kinematic_4dof(0.05)
    world = ObstacleWorld([Cylinder((3.0, 0.3), 0.4), Cylinder((5.5, 1.8), 0.5)])
    return NmpcPlanner(
        model,
        NmpcConfig(n_obstacles=2, time_budget_s=30.0),
        ResidualTerm.of_velocity(gp_like(seed), model),
        world,
        solver_factory=lambda f: GaussNewtonSqp(f, SqpOptions(linearisation=linearisation)),
    )


def fly(built: NmpcPlanner, n_plans: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """(commands (n_plans, 4), predicted trajectories) of a closed loop at 10 Hz past the
    cylinders (the vehicle flies its commands)."""
    wp = np.array([[0.0, 0.0, -2.0], [4.0, 0.5, -2.0], [8.0, 1.5, -2.5]])
    reference = BSplineReference(wp, max_speed_mps=1.5, max_acc_mps2=1.0)
    x = reference.x_ref(0.0)
    commands, predicted = [], []
    for k in range(n_plans):
        result = built.plan(PlannerState(x[:3], np.zeros(3), float(x[3])), reference, 0.1 * k)
        assert result.ok, result.reason
        commands.append(result.command)
        predicted.append(result.predicted_trajectory)
        x = x + 0.1 * result.command
    return np.array(commands), np.array(predicted)


def test_constants_as_input_gives_the_same_step_bit_for_bit():
    step = planner("batched").formulation.step
    lifted, theta = constants_as_input(step)
    x, u = np.array([1.0, -2.0, -3.0, 0.4]), np.array([0.7, -1.1, 0.2, 0.3])
    assert np.array_equal(np.asarray(lifted(x, u, theta)), np.asarray(step(x, u)))


@needs_cc
def test_compiled_plans_what_the_numpy_path_plans(tmp_path, monkeypatch):
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    compiled, numpy_path = planner("compiled"), planner("batched")
    assert isinstance(compiled._solver._lin, CompiledLinearisation)
    commands, predicted = fly(compiled)
    numpy_commands, numpy_predicted = fly(numpy_path)
    np.testing.assert_allclose(commands, numpy_commands, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(predicted, numpy_predicted, rtol=0.0, atol=1e-9)


@needs_cc
def test_one_library_serves_every_model_of_the_shape(tmp_path, monkeypatch):
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    first = planner("compiled", seed=1)
    built = sorted(tmp_path.glob("*.so"))
    second = planner("compiled", seed=2)  # other inducing points and weights, same shape
    assert sorted(tmp_path.glob("*.so")) == built and len(built) == 2  # linearisation, rollout
    # and each flies its own model
    assert not np.allclose(fly(first, 10)[0], fly(second, 10)[0], atol=1e-6)


def test_without_a_compiler_the_planner_flies_on_the_numpy_path(tmp_path, monkeypatch):
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    built = planner("compiled")
    assert not isinstance(built._solver._lin, CompiledLinearisation)
    commands, _ = fly(built, 10)
    assert not list(tmp_path.glob("*.so"))
    np.testing.assert_allclose(commands, fly(planner("batched"), 10)[0], rtol=0.0, atol=1e-9)


def test_a_graph_calling_another_function_keeps_its_constants():
    x = ca.SX.sym("x", 2)
    inner = ca.Function("inner", [x], [ca.sin(x) * 3.0], {"never_inline": True})
    outer = ca.Function("outer", [x], [inner(x) * 2.5 + 1.0])
    kept, theta = constants_as_input(outer)
    assert theta.size == 0
    np.testing.assert_array_equal(np.asarray(kept([0.3, -1.0], theta)), outer([0.3, -1.0]))


def test_a_graph_calling_another_function_keeps_its_inputs_in_order():
    x, u = ca.SX.sym("x"), ca.SX.sym("u")
    inner = ca.Function("inner", [x], [3.0 * x], {"never_inline": True})
    outer = ca.Function("outer", [x, u], [inner(x) - u])
    kept, theta = constants_as_input(outer)
    assert float(kept(2.0, 0.5, theta)) == 3.0 * 2.0 - 0.5
