"""Helpers for the planner tests: a drag-like residual and a closed loop."""

import casadi as ca
import numpy as np

from planners.reference import PlannerState

DT_S = 0.05


def drag_residual_fn(scale: float = 2.0) -> ca.Function:
    """g(v) = scale * (-0.3 v - 0.08 v|v|) [m/s^2] per axis, as a CasADi Function."""
    v = ca.SX.sym("v", 3)
    return ca.Function("drag", [v], [scale * (-0.3 * v - 0.08 * v * ca.fabs(v))])


def drag_residual_np(vel_mps: np.ndarray, scale: float = 2.0) -> np.ndarray:
    return scale * (-0.3 * vel_mps - 0.08 * vel_mps * np.abs(vel_mps))


def closed_loop(planner, reference, plant_step, t_end_s, dt_s=DT_S):
    """Fly a kinematic 4-DOF plant from the reference's start, one plan per ``dt_s``.

    ``plant_step(x, u, dt_s)`` advances the plant. Returns (states (n+1, 4), [PlanResult]).
    """
    x = reference.x_ref(0.0)
    states, results = [x], []
    for k in range(int(round(t_end_s / dt_s))):
        res = planner.plan(PlannerState(x[:3], np.zeros(3), x[3]), reference, k * dt_s)
        results.append(res)
        x = plant_step(x, res.command, dt_s)
        states.append(x)
    return np.array(states), results
