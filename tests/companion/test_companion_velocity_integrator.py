"""The companion keeps the autopilot's velocity integrator itself (px4_velocity_pi): zero at
the first plan, I += Ki (u_sent - v) dt after, restarted after a gap; when a learned residual
flies the plan starts from it, when none does (no model file, or one whose GP was refused) from
0 (offset-free: the integrator's value is held as the disturbance it cancels); the gains come
from the parameters the autopilot reports."""

from __future__ import annotations

import numpy as np
import pytest

from companion.autopilot_gains import velocity_loop_gains
from companion.inprocess_link import InProcessLink
from companion.nmpc_planner import INTEGRATOR_GAP_S, CompanionNmpc, NmpcSettings
from gp.exact_gp import ExactGP
from gp.features import feature_definition
from gp.model_io import ResidualModel
from planners.bspline import BSplineReference
from planners.nominal_models import INTEGRATOR_STATES
from planners.reference import PlannerState
from vehicle_sim import Simulator, load_sim_config

SEED = 20261123


def _residual_on(
    params: dict[str, float], rng: np.random.Generator, gp_refused: bool
) -> ResidualModel:
    """A small GP residual on px4_velocity_pi with ``params``, on random data (its values do
    not matter here, only whether the planner flies it); ``gp_refused``: its file records that
    the GP did not beat the structure alone, so the structure flies without it."""
    features = feature_definition("velocity", "px4_velocity_pi", **params)
    x = rng.normal(0.0, 1.0, (30, features.n_features))
    y = 0.01 * rng.normal(0.0, 1.0, (30, len(features.outputs)))
    gp = ExactGP(noise_variance=1e-4, optimize=False).fit(x, y)
    training = {"prediction_check_structure": {"passed": False}} if gp_refused else {}
    return ResidualModel.from_estimator(gp, features, training=training)


@pytest.mark.parametrize(
    "model_file", [None, "gp_flies", "gp_refused"], ids=["no_model", "learned", "structure_only"]
)
def test_integrator_is_integrated_from_the_commands_and_measured_velocity(model_file):
    rng = np.random.default_rng(SEED)
    ki_xy, ki_z = rng.uniform(0.2, 2.0), rng.uniform(0.2, 3.0)
    params = {"vel_p_xy": rng.uniform(1.2, 3.0), "vel_i_xy": ki_xy, "vel_i_z": ki_z}
    settings = NmpcSettings(
        speed_limit_mps=3.0, time_budget_s=30.0, nominal_model="px4_velocity_pi",
        nominal_params=tuple(params.items()),
    )  # fmt: skip
    residual = None
    if model_file is not None:
        residual = _residual_on(params, rng, gp_refused=model_file == "gp_refused")
    planner = CompanionNmpc(settings, residual)
    learned = model_file == "gp_flies"
    said = {None: "px4_velocity_pi(", "gp_flies": " + GP on velocity", "gp_refused": " alone ("}
    assert planner.flown_model.startswith("px4_velocity_pi(vel_i_xy=")
    assert said[model_file] in planner.flown_model  # what the flight log records
    ref = BSplineReference(
        np.array([[0.0, 0.0, -3.0], [4.0, 2.0, -3.0], [8.0, 0.0, -3.5], [12.0, -1.0, -3.0]]), 2.0
    )
    ki = np.array([ki_xy, ki_xy, ki_z])
    rows = [planner.model.state_names.index(s) for s in INTEGRATOR_STATES]
    expected, prev = np.zeros(3), None
    t_s = 0.0
    for _ in range(40):
        vel = rng.normal(0.0, 1.0, 3)
        if prev is not None:
            t_prev, vel_prev, command = prev
            expected = expected + ki * (command - 0.5 * (vel + vel_prev)) * (t_s - t_prev)
        result = planner.plan(PlannerState(rng.normal(0.0, 0.3, 3), vel, 0.0), ref, t_s)
        assert result.ok, result.reason
        np.testing.assert_allclose(planner.velocity_integrator_mps2, expected, atol=1e-12)
        planned = expected if learned else np.zeros(3)
        np.testing.assert_allclose(result.predicted_trajectory[0, rows], planned, atol=1e-12)
        prev = (t_s, vel, np.asarray(result.command[:3], dtype=float))
        t_s += rng.uniform(0.015, 0.03)
    assert np.max(np.abs(expected)) > 0.05  # the drawn errors moved it
    planner.plan(PlannerState(np.zeros(3), np.zeros(3), 0.0), ref, t_s + INTEGRATOR_GAP_S + 0.1)
    np.testing.assert_array_equal(planner.velocity_integrator_mps2, np.zeros(3))


def test_gains_are_the_autopilots_parameters():
    """Each gain comes from its own PX4 parameter ([PX4-params]): values drawn within PX4's
    ranges, set on the autopilot, come back under px4_velocity_pi's names."""
    rng = np.random.default_rng(SEED)
    drawn = {
        "MPC_XY_VEL_P_ACC": ("vel_p_xy", rng.uniform(1.2, 5.0)),
        "MPC_XY_VEL_I_ACC": ("vel_i_xy", rng.uniform(0.0, 5.0)),
        "MPC_XY_VEL_D_ACC": ("vel_d_xy", rng.uniform(0.1, 2.0)),
        "MPC_Z_VEL_P_ACC": ("vel_p_z", rng.uniform(2.0, 15.0)),
        "MPC_Z_VEL_I_ACC": ("vel_i_z", rng.uniform(0.2, 3.0)),
        "MPC_Z_VEL_D_ACC": ("vel_d_z", rng.uniform(0.0, 2.0)),
    }
    sim = Simulator(load_sim_config("iris_study"), seed=0)
    for param, (_, value) in drawn.items():
        sim.set_param(param, value)
    gains = dict(velocity_loop_gains(InProcessLink(sim)))
    assert gains == pytest.approx(dict(drawn.values()), rel=1e-6)
