"""A model that carries the velocity one planner interval ago along the NMPC's horizon.

[Ostafew16]'s history features a_k = (x_k, v_{k-1}, ...) ask, at every node of the horizon, for
the velocity one interval before it. :func:`with_velocity_history` adds it to a model that
carries the velocity as three more states, HISTORY_STATES [m/s] (last in the state), held
within an interval (x_dot = 0, no residual) and shifted at its end
(NominalModel.interval_step): node j + 1's previous velocity is node j's velocity, node 0's
the velocity measured one interval before now (the companion keeps it,
companion.velocity_buffer). Their cost weight defaults to 0 (untracked).
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np

from planners.nominal_models import HISTORY_STATES, VELOCITY_STATES, NominalModel


def with_velocity_history(model: NominalModel) -> NominalModel:
    """``model`` with HISTORY_STATES appended (nx + 3 states); raises ValueError for a model
    without a velocity state (its velocity is its command: history would be a lagged input)."""
    if not model.carries_velocity:
        raise ValueError(
            f"{model.name} has no velocity state to carry one interval along the horizon; "
            "use first_order_lag or px4_velocity_pi"
        )
    nx = model.nx
    x = ca.SX.sym("x", nx + 3)
    u = ca.SX.sym("u", model.nu)
    inner = x[:nx]
    f = ca.Function(
        f"{model.name}_velocity_history",
        [x, u],
        [ca.vertcat(model.f(inner, u), ca.SX.zeros(3))],
        ["x", "u"],
        ["x_dot"],
    )
    vel = ca.Function(
        f"{model.name}_velocity_history_velocity",
        [x, u],
        [model.velocity_of(inner, u)],
        ["x", "u"],
        ["vel"],
    )
    sources = [model.state_names.index(c) for c in VELOCITY_STATES]
    return replace(
        model,
        state_names=(*model.state_names, *HISTORY_STATES),
        f=f,
        residual_map=np.vstack([model.residual_map, np.zeros((3, 3))]),
        velocity_of=vel,
        untracked_states=(*model.untracked_states, *HISTORY_STATES),
        history=tuple((nx + i, s) for i, s in enumerate(sources)),
    )
