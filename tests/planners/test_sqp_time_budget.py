"""The fast path's time budget, on a clock that moves one second per reading (no real timing):
a cold start stops before an iteration that would end after the budget."""

from __future__ import annotations

import numpy as np

from planners import sqp_solver
from planners.nmpc_formulation import OBSTACLE_SLOT_SIZE, NmpcConfig, NmpcFormulation
from planners.nominal_models import kinematic_4dof
from planners.sqp_solver import GaussNewtonSqp, SqpOptions


class SteppingClock:
    """``perf_counter()`` returns 0, 1, 2, ... [s]: every iteration of the SQP reads it twice,
    so each iteration lasts one second."""

    def __init__(self) -> None:
        self.readings = 0

    def perf_counter(self) -> float:
        self.readings += 1
        return float(self.readings - 1)


def _cold_start_problem(formulation: NmpcFormulation) -> tuple[np.ndarray, np.ndarray]:
    """(w0, p): hover at the origin, the reference 5 m away flying at 1 m/s north; w0 is the
    reference itself (a cold start far from the solution, so the SQP does not converge
    within a few iterations)."""
    n, nx, nu = formulation.config.horizon_steps, formulation.model.nx, formulation.model.nu
    t = formulation.config.dt_s * np.arange(n + 1)
    x_ref = np.zeros((n + 1, nx))
    x_ref[:, 0] = 5.0 + t
    x_ref[:, 2] = -3.0
    u_ref = np.zeros((n, nu))
    u_ref[:, 0] = 1.0
    x_now = np.array([0.0, 0.0, -3.0, 0.0])
    slots = np.zeros((n, formulation.config.n_obstacles, OBSTACLE_SLOT_SIZE))
    p = formulation.pack_parameters(x_now, x_ref, u_ref, slots)
    return formulation.pack_w(x_ref, u_ref), p


def test_cold_start_stops_before_an_iteration_that_would_overrun_the_budget(monkeypatch):
    formulation = NmpcFormulation(kinematic_4dof(0.05), NmpcConfig(n_obstacles=0))
    solver = GaussNewtonSqp(formulation, SqpOptions(cold_start_iterations=10, step_tol=0.0))
    w0, p = _cold_start_problem(formulation)
    clock = SteppingClock()
    monkeypatch.setattr(sqp_solver, "time", clock)
    out = solver.solve(w0, p, time_budget_s=6.5, cold_start=True)
    # Iterations end at 2, 4, 6 s (start read at 0); a fourth would end at 8 s > 6.5 s.
    assert out.ok
    assert out.iterations == 3
    assert clock.readings - 1 <= 6.5
