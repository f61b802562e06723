"""The fast path's condensed QP reports a QP that DAQP cannot solve as failed, never raising.

DAQP factors the Hessian before it starts; when that fails (a Hessian that is not positive
definite) it returns without writing its solution, so the output buffer still holds the
previous QP's answer. That answer must not come back as this QP's solution. Bounds CasADi
refuses (NaN, crossed) make a failed QP too, not an exception out of the SQP.
"""

from __future__ import annotations

import numpy as np
import pytest

from planners.condensed_qp import CondensedQp
from planners.nmpc_formulation import NmpcConfig, NmpcFormulation
from planners.nominal_models import kinematic_4dof, px4_velocity_pi
from planners.sqp_solver import LINEARISATIONS, GaussNewtonSqp, SqpOptions

N_U, N_X_ROWS, N_ROWS = 6, 2, 3


def _qp_data(rng: np.random.Generator) -> dict[str, np.ndarray]:
    """A small feasible QP with a positive definite Hessian."""
    m = rng.normal(size=(N_U, N_U))
    return {
        "hess": m @ m.T + np.eye(N_U),
        "grad": rng.normal(size=N_U),
        "a_x": rng.normal(size=(N_X_ROWS, N_U)),
        "lba_x": -np.ones(N_X_ROWS),
        "uba_x": np.ones(N_X_ROWS),
        "a_h": rng.normal(size=(N_ROWS, N_U)),
        "lba_h": -np.ones(N_ROWS),
        "lbx": -np.ones(N_U),
        "ubx": np.ones(N_U),
    }


def test_a_qp_daqp_cannot_factor_fails_instead_of_returning_the_previous_answer():
    qp = CondensedQp(N_U, N_X_ROWS, N_ROWS, rho=1e5, eps=1.0)
    data = _qp_data(np.random.default_rng(7))
    _, violation = qp.solve(**data)
    assert violation <= 1e-9  # the good QP is solved
    _, violation = qp.solve(**{**data, "hess": -np.eye(N_U)})  # not positive definite
    assert not violation <= 1e-6, "the previous QP's answer came back as this one's"
    du, violation = qp.solve(**data)  # and the next good QP is solved again
    assert violation <= 1e-9 and np.all(np.isfinite(du))


def test_sqp_whose_qps_daqp_cannot_factor_reports_failure():
    """Without the slack's quadratic weight DAQP cannot factor any QP: the solve must say so,
    not return its starting point as a converged plan."""
    formulation = NmpcFormulation(kinematic_4dof(0.05), NmpcConfig(n_obstacles=1))
    n, nx, nu = formulation.config.horizon_steps, formulation.model.nx, formulation.model.nu
    x_ref = np.zeros((n + 1, nx))
    x_ref[:, 0] = 3.0  # 3 m north of the vehicle, which hovers at the origin
    u_ref = np.zeros((n, nu))
    slots = np.tile([1.5, 0.0, 0.0, 1.0, 1.0, 0.0, 0.5], (n, 1, 1))  # a cylinder in between
    p = formulation.pack_parameters(np.zeros(nx), x_ref, u_ref, slots)
    w0 = formulation.pack_w(np.zeros_like(x_ref), u_ref)
    solver = GaussNewtonSqp(formulation, SqpOptions(slack_weight_quadratic=0.0))
    out = solver.solve(w0, p, time_budget_s=10.0, cold_start=True)
    assert not out.ok
    assert "QP failed" in out.reason


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_state_row_the_input_bounds_cannot_meet_is_reported_violated(side):
    """A state row asking for du_0 in [5, 6] (or [-6, -5]) with |du| <= 1: no du meets both,
    so the solution violates one of them by at least 2 (the best split is du_0 = 3: row short
    by 2, bound exceeded by 2), whichever one the solver gives up."""
    qp = CondensedQp(2, 1, 1, rho=1e5, eps=1.0)
    row = side * np.array([5.0, 6.0])
    _, violation = qp.solve(
        hess=np.eye(2),
        grad=np.zeros(2),
        a_x=np.array([[1.0, 0.0]]),
        lba_x=np.array([row.min()]),
        uba_x=np.array([row.max()]),
        a_h=np.zeros((1, 2)),
        lba_h=np.array([-1.0]),
        lbx=-np.ones(2),
        ubx=np.ones(2),
    )
    assert violation >= 2.0 - 1e-9


def test_qp_data_with_nan_or_infinite_bounds_fail_without_raising():
    """DAQP (through CasADi) raises on ill-posed bounds (NaN, lower bound +inf): a solve on
    such data is a failed QP, as the SQP reports it, not an exception."""
    qp = CondensedQp(N_U, N_X_ROWS, N_ROWS, rho=1e5, eps=1.0)
    data = _qp_data(np.random.default_rng(7))
    for name, value in (("lba_x", np.nan), ("uba_x", -np.inf), ("lba_h", np.nan), ("lbx", np.inf)):
        bound = data[name].copy()
        bound[0] = value
        _, violation = qp.solve(**{**data, name: bound})
        assert not violation <= 1e-6, name
    _, violation = qp.solve(**data)
    assert violation <= 1e-9


def test_sqp_on_a_nan_state_with_state_bounds_reports_failure_without_raising():
    model = kinematic_4dof(0.05)
    config = NmpcConfig(n_obstacles=0, state_min=(-100.0,) * 4, state_max=(100.0,) * 4)
    formulation = NmpcFormulation(model, config)
    n = config.horizon_steps
    x_ref, u_ref = np.zeros((n + 1, model.nx)), np.zeros((n, model.nu))
    x_now = np.array([np.nan, 0.0, -3.0, 0.0])
    p = formulation.pack_parameters(x_now, x_ref, u_ref, np.zeros((n, 0, 7)))
    out = GaussNewtonSqp(formulation).solve(formulation.pack_w(x_ref, u_ref), p, 1.0, True)
    assert not out.ok
    assert "QP failed" in out.reason


@pytest.mark.parametrize(
    ("linearisation", "reason"),
    [
        # the batched path's QP sees the NaN itself and says so
        ("batched", "QP failed (constraint violation nan)"),
        # the symbolic path's QP is solved: the step is what is NaN, not "QP failed (... 0)"
        ("symbolic", "non-finite step (NaN or inf in the linearisation at the iterate)"),
    ],
)
def test_sqp_whose_step_is_nan_only_in_an_untracked_state_reports_failure(linearisation, reason):
    """A warm start NaN in an untracked state (cost weight 0) at the last node leaves the QP
    finite on the symbolic path (its cost drops the zero-weight row) but the dynamics gap
    NaN: the step is NaN, so the solve fails instead of returning a NaN iterate as ok, with
    the reason that is true on each path."""
    assert linearisation in LINEARISATIONS
    model = px4_velocity_pi()
    formulation = NmpcFormulation(model, NmpcConfig(n_obstacles=0))
    n = formulation.config.horizon_steps
    x_ref, u_ref = np.zeros((n + 1, model.nx)), np.zeros((n, model.nu))
    p = formulation.pack_parameters(np.zeros(model.nx), x_ref, u_ref, np.zeros((n, 0, 7)))
    states = x_ref.copy()
    states[n, model.state_names.index("vel_int_n_mps2")] = np.nan
    w0 = formulation.pack_w(states, u_ref)
    out = GaussNewtonSqp(formulation, SqpOptions(linearisation=linearisation)).solve(w0, p, 1.0)
    assert not out.ok, "a NaN iterate came back as a converged plan"
    assert out.reason == reason
