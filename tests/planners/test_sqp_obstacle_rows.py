"""One real-time SQP iteration keeps the linearised clearance of every obstacle within the
screen distance: a single step from rest does not plan through an obstacle ahead.

The vehicle (kinematic_4dof) rests at the origin and the reference sits 3 m north, behind a
cylinder of radius 0.5 m centred 1.4 m north: 0.9 m of clearance, inside the 1 m screen
distance. Linearised at the origin, the clearance row is the tangent plane pos_n <= 0.9 m, and
the inputs (1.5 m/s over 2 s) could carry the plan 3 m: the step stops on the plane.
"""

from __future__ import annotations

import numpy as np
import pytest

from planners.nmpc_formulation import NmpcConfig, NmpcFormulation, slot_clearance_m
from planners.nominal_models import kinematic_4dof
from planners.sqp_solver import LINEARISATIONS, GaussNewtonSqp, SqpOptions

CYLINDER = np.array([1.4, 0.0, 0.0, 1.0, 1.0, 0.0, 0.5])  # centre n, e, d; axis weights; radius


@pytest.mark.parametrize("linearisation", LINEARISATIONS)
def test_one_iteration_from_rest_stops_on_the_tangent_plane_of_a_near_obstacle(linearisation):
    formulation = NmpcFormulation(kinematic_4dof(0.1), NmpcConfig(n_obstacles=1))
    n, nx, nu = formulation.config.horizon_steps, formulation.model.nx, formulation.model.nu
    x_ref = np.zeros((n + 1, nx))
    x_ref[:, 0] = 3.0
    u_ref = np.zeros((n, nu))
    p = formulation.pack_parameters(np.zeros(nx), x_ref, u_ref, np.tile(CYLINDER, (n, 1, 1)))
    w0 = formulation.pack_w(np.zeros((n + 1, nx)), u_ref)
    solver = GaussNewtonSqp(formulation, SqpOptions(linearisation=linearisation))
    out = solver.solve(w0, p, time_budget_s=10.0)
    assert out.ok and out.iterations == 1
    states, _ = formulation.split_w(out.w)
    assert states[:, 0].max() == pytest.approx(0.9, abs=1e-6)  # pulled onto the plane
    assert slot_clearance_m(states[:, :3], CYLINDER).min() >= -1e-6
