"""The previous velocity along the horizon: held within an interval, shifted at its end, and
linearised alike by the batched and the symbolic path; a model without history steps as
before."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gp.features import feature_definition
from planners.nmpc_formulation import NmpcConfig, NmpcFormulation
from planners.nominal_models import HISTORY_STATES, VELOCITY_STATES, first_order_lag
from planners.residual import ResidualTerm
from planners.sqp_solver import GaussNewtonSqp, SqpOptions
from planners.velocity_history import with_velocity_history

SEED = 20261127


def _formulation(rng: np.random.Generator, batch: bool = False) -> NmpcFormulation:
    """first_order_lag with velocity history and a drawn smooth residual g(vel, vel_prev) =
    tanh(W z); with ``batch``, also given in NumPy form (g and dg/dz = (1 - g^2) W at many rows),
    as a GP's mean flies, so the fast path's own NumPy RK4 and history shift linearise it."""
    features = feature_definition(
        "velocity_history", "first_order_lag", residual_steps=5, tau_s=0.7, tau_d_s=0.4
    )
    model = features.planner_model()
    z = ca.SX.sym("z", 6)
    weights = ca.DM(rng.normal(0.0, 0.5, (3, 6)))
    fn = ca.Function("g", [z], [ca.tanh(weights @ z)])
    config = NmpcConfig(horizon_steps=8, n_obstacles=2)

    def g_batch(zs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        g = np.tanh(zs @ np.asarray(weights).T)  # (n, 3)
        return g, (1.0 - g**2)[:, :, None] * np.asarray(weights)[None, :, :]

    residual = ResidualTerm(fn, features.planner_map(model), g_batch if batch else None)
    return NmpcFormulation(model, config, residual)


def test_the_step_shifts_the_velocity_into_the_history():
    rng = np.random.default_rng(SEED)
    f = _formulation(rng)
    names = f.model.state_names
    x, u = rng.normal(size=f.model.nx), rng.normal(size=f.model.nu)
    x_next = np.asarray(f.step(x, u)).ravel()
    vel = [names.index(c) for c in VELOCITY_STATES]
    np.testing.assert_array_equal(x_next[[names.index(c) for c in HISTORY_STATES]], x[vel])
    assert not np.allclose(x_next[vel], x[vel])  # the velocity itself moved on


@pytest.mark.parametrize("batch", [False, True])
def test_batched_qp_data_equals_the_symbolic_linearisation_with_history(batch):
    rng = np.random.default_rng(SEED)
    f = _formulation(rng, batch)
    lins = {
        kind: GaussNewtonSqp(f, SqpOptions(linearisation=kind))._lin
        for kind in ("batched", "symbolic")
    }
    slots = f.config.n_obstacles * f.config.horizon_steps
    for _ in range(3):
        w = rng.normal(0.0, 2.0, f.n_w)
        p = rng.normal(0.0, 2.0, f.n_p)
        p[-slots * 7 :] = np.tile([5.0, 1.0, -3.0, 1.0, 1.0, 0.0, 1.0], slots)
        for got, want in zip(lins["batched"](w, p), lins["symbolic"](w, p), strict=True):
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("residual", [False, True])
def test_a_model_without_history_steps_exactly_by_rk4(residual):
    model = first_order_lag(0.6, 0.3)
    x, u = ca.SX.sym("x", model.nx), ca.SX.sym("u", model.nu)
    term = (lambda xs, us: ca.sin(xs[3:6])) if residual else None
    a = ca.Function("a", [x, u], [model.interval_step(x, u, 0.1, term)])
    b = ca.Function("b", [x, u], [model.rk4_step(x, u, 0.1, term)])
    rng = np.random.default_rng(SEED)
    xv, uv = rng.normal(size=model.nx), rng.normal(size=model.nu)
    np.testing.assert_array_equal(np.asarray(a(xv, uv)), np.asarray(b(xv, uv)))
    assert with_velocity_history(model).nx == model.nx + 3
