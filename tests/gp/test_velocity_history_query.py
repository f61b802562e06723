"""A velocity-history GP flies on the query it was trained on: the companion's NMPC builds, at
its first node, the dataset's row (vel[k], vel[k-H]) or (vel[k], vel[k] - vel[k-H]) for the
same log, from the velocities it recorded itself; along the horizon each node's previous
velocity is the node before's."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from gp_synthetic_logs import record_log

from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from gp.datasets import DatasetConfig, residual_dataset
from gp.errors import ModelFileError
from gp.exact_gp import ExactGP
from gp.features import feature_definition
from gp.model_io import ResidualModel
from planners.bspline import BSplineReference
from planners.nominal_models import HISTORY_STATES, VELOCITY_STATES
from planners.reference import PlannerState

PERIOD_S = 0.02  # the log's and the control loop's step [s]
STEPS = 5  # one planner interval (0.1 s) in log steps
_VEL = ("vel_n_mps", "vel_e_mps", "vel_d_mps")


def _fitted(features, log) -> tuple[ResidualModel, np.ndarray]:
    """A small GP on the log's dataset for ``features``, and the dataset's rows X (n, 6)."""
    data = residual_dataset([log], DatasetConfig(features))
    gp = ExactGP(noise_variance=1e-3, optimize=False).fit(data.X[::4], data.Y[::4])
    return ResidualModel.from_estimator(gp, features, training={}), data.X


@pytest.mark.parametrize("name", ["velocity_history", "velocity_change"])
def test_the_planner_queries_the_gp_at_the_datasets_row_for_the_same_log(name):
    features = feature_definition(
        name, "first_order_lag", residual_steps=STEPS, tau_s=0.5, tau_d_s=0.4
    )
    log = record_log(60, dt_s=PERIOD_S)
    model, rows = _fitted(features, log)
    settings = NmpcSettings(speed_limit_mps=4.0, period_s=PERIOD_S, time_budget_s=30.0)
    planner = CompanionNmpc(settings, model)
    names = planner.model.state_names
    vel_idx = [names.index(c) for c in VELOCITY_STATES]
    prev_idx = [names.index(c) for c in HISTORY_STATES]
    z_of = features.planner_map(planner.model)
    ref = BSplineReference(
        np.array([[0.0, 0.0, -5.0], [4.0, 2.0, -5.0], [8.0, 0.0, -5.5], [12.0, -1.0, -5.0]]), 2.0
    )
    vel = log.stack(*_VEL)
    for k in range(3 * STEPS):
        state = PlannerState(np.array([0.0, 0.0, -5.0]), vel[k], 0.0)
        result = planner.plan(state, ref, float(log["t_s"][k]))
        assert result.ok, result.reason
        node0 = result.predicted_trajectory[0]
        z = np.asarray(ca.DM(z_of(ca.DM(node0), ca.DM(result.command)))).ravel()
        if k >= STEPS:  # the dataset's row for log row k (its rows start at the lag)
            np.testing.assert_allclose(z, rows[k - STEPS], atol=1e-12)
        else:  # before one interval is recorded: the oldest velocity, the first row's
            np.testing.assert_allclose(node0[prev_idx], vel[0], atol=1e-12)
        later = result.predicted_trajectory[1:]
        np.testing.assert_allclose(later[:, prev_idx], result.predicted_trajectory[:-1, vel_idx])


def test_a_history_that_does_not_lag_one_planner_interval_is_refused():
    features = feature_definition("velocity_history", "first_order_lag", tau_s=0.5, tau_d_s=0.4)
    model, _ = _fitted(features, record_log(60, dt_s=PERIOD_S))  # lag 1 step: 0.02 s
    settings = NmpcSettings(speed_limit_mps=4.0, period_s=PERIOD_S, time_budget_s=30.0)
    with pytest.raises(ModelFileError, match="interval") as info:
        CompanionNmpc(settings, model)
    assert "\n" not in str(info.value)
