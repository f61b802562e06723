"""px4_velocity_pi: the PI loop's response against the exact solution of its linear ODE, the
integrator's zero cost weight, and the batched linearisation equal to the symbolic one."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from planners.nmpc import NmpcPlanner
from planners.nmpc_formulation import NmpcConfig, NmpcFormulation
from planners.nominal_models import INTEGRATOR_STATES, make_model, px4_velocity_pi
from planners.sqp_solver import GaussNewtonSqp, SqpOptions

SEED = 20261123


def _drawn_gains(rng: np.random.Generator) -> dict[str, float]:
    """Gains inside PX4's bounds ([PX4-params]) and a drag, drawn at random."""
    return {
        "vel_p_xy": rng.uniform(1.2, 5.0),
        "vel_i_xy": rng.uniform(0.1, 2.0),
        "vel_d_xy": rng.uniform(0.1, 1.0),
        "vel_p_z": rng.uniform(2.0, 8.0),
        "vel_i_z": rng.uniform(0.2, 3.0),
        "vel_d_z": rng.uniform(0.0, 0.5),
        "drag_xy_per_s": rng.uniform(0.0, 0.4),
        "drag_z_per_s": rng.uniform(0.0, 0.2),
    }


def test_step_response_matches_the_exact_solution_of_the_pi_loop():
    rng = np.random.default_rng(SEED)
    g = _drawn_gains(rng)
    model = px4_velocity_pi(**g)
    x0 = np.zeros(10)
    x0[3:6] = rng.normal(0.0, 1.0, 3)
    x0[6:9] = rng.normal(0.0, 0.5, 3)
    u = np.append(rng.uniform(-3.0, 3.0, 3), 0.0)
    dt_s, n = 0.05, 80
    x = x0.copy()
    for _ in range(n):
        x = model.step_np(x, u, dt_s)
    axes = (("xy", 0), ("xy", 1), ("z", 2))
    for plane, i in axes:
        kp, ki = g[f"vel_p_{plane}"], g[f"vel_i_{plane}"]
        m, c = 1.0 + g[f"vel_d_{plane}"], g[f"drag_{plane}_per_s"]
        # z = (p, v, I, 1): p' = v, m v' = kp (u - v) + I - c v, I' = ki (u - v)
        a = np.array(
            [
                [0.0, 1.0, 0.0, 0.0],
                [0.0, -(kp + c) / m, 1.0 / m, kp * u[i] / m],
                [0.0, -ki, 0.0, ki * u[i]],
                [0.0, 0.0, 0.0, 0.0],
            ]
        )
        z = expm(a * n * dt_s) @ np.array([x0[i], x0[3 + i], x0[6 + i], 1.0])
        np.testing.assert_allclose(x[[i, 3 + i, 6 + i]], z[:3], rtol=1e-5, atol=1e-6)
    # settled: the velocity on its command, the integrator holding the drag
    for _ in range(2000):
        x = model.step_np(x, u, dt_s)
    np.testing.assert_allclose(x[3:6], u[:3], atol=1e-6)
    drag = np.array([g["drag_xy_per_s"], g["drag_xy_per_s"], g["drag_z_per_s"]])
    np.testing.assert_allclose(x[6:9], drag * u[:3], atol=1e-6)


def test_the_integrator_has_no_reference_and_costs_nothing_by_default():
    model = make_model("px4_velocity_pi", vel_p_xy=2.0, vel_d_xy=0.5, vel_p_z=4.0)
    f = NmpcFormulation(model, NmpcConfig(n_obstacles=0))
    rows = [model.state_names.index(s) for s in INTEGRATOR_STATES]
    assert np.all(f.q_diag[rows] == 0.0) and np.all(np.delete(f.q_diag, rows) == 10.0)
    assert model.velocity_lead_s == pytest.approx((0.75, 0.75, 0.25))
    with pytest.raises(ValueError, match="vel_p_xy must be > 0"):
        px4_velocity_pi(vel_p_xy=0.0)


def test_batched_linearisation_equals_the_symbolic_one():
    rng = np.random.default_rng(SEED + 1)
    model = px4_velocity_pi(**_drawn_gains(rng))
    config = NmpcConfig(n_obstacles=2)
    built = {
        kind: NmpcPlanner(
            model,
            config,
            solver_factory=lambda form, k=kind: GaussNewtonSqp(form, SqpOptions(linearisation=k)),
        )
        for kind in ("batched", "symbolic")
    }
    f = built["batched"].formulation
    for _ in range(3):
        w = rng.normal(0.0, 2.0, f.n_w)
        p = rng.normal(0.0, 2.0, f.n_p)
        p[-config.n_obstacles * config.horizon_steps * 7 :] = np.tile(
            [5.0, 1.0, -3.0, 1.0, 1.0, 0.0, 1.0], config.n_obstacles * config.horizon_steps
        )
        batched = built["batched"]._solver._lin(w, p)
        symbolic = built["symbolic"]._solver._lin(w, p)
        for got, want in zip(batched, symbolic, strict=True):
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
