"""The companion flies the NMPC (real CasADi solver, real simulator) and logs its predictions;
bad residual model files are refused before anything flies; planner failures give the safe
command."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from companion.app import CompanionConfig, CompanionInputError, run_companion
from companion.decision import CommandLimits
from companion.inprocess_link import link_state_of
from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from companion.planner_policy import PlannerPolicy
from experiments.study.metrics import residual_rmse_mps, tracking_rmse_m
from flightlog.schema import read_flight_log
from gp.features import feature_definition
from gp.inducing import InducingConfig
from gp.model_io import ResidualModel, save_model
from gp.sparse_gp import SparseGP
from planners.bspline import BSplineReference
from scripts.companion_cli import main as companion_main
from vehicle_sim import Simulator, load_sim_config

REPO = Path(__file__).resolve().parents[2]
LINE = REPO / "missions" / "line_20m.toml"
S_CURVE = REPO / "missions" / "s_curve.toml"  # a B-spline: a reference the NMPC can track
PRED = ("pred_vel_n_mps", "pred_vel_e_mps", "pred_vel_d_mps")
CMD = ("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps")


def _tiny_model(features: str = "velocity", nominal: str = "kinematic_4dof", **params: float):
    """A real (small) SGPR residual model on seeded synthetic data."""
    fd = feature_definition(features, nominal, **params)
    rng = np.random.default_rng(0)
    X = rng.uniform(-1.5, 1.5, (200, fd.n_features))
    Y = -0.3 * X[:, :3] + 0.01 * rng.standard_normal((200, 3))
    gp = SparseGP(inducing=InducingConfig(m=8), n_restarts=1, random_state=0).fit(X, Y)
    return ResidualModel.from_estimator(gp, fd)


def test_nmpc_flies_a_mission_in_process_and_logs_its_one_step_predictions(tmp_path):
    config = CompanionConfig(
        mission_path=S_CURVE,
        link="inprocess",
        planner="nmpc",
        log_path=tmp_path / "nmpc.csv",
        vehicle="iris_study",
    )
    result = run_companion(config, lambda message: None)
    assert result.outcome.status == "completed", result.outcome.detail
    log = read_flight_log(result.log_path)
    assert log.metadata["planner"] == "nmpc" and log.metadata["gp_model"] is None
    assert log.metadata["planner_model"] == "kinematic_4dof(residual_dt_s=0.02)"
    assert log.has(*PRED) and np.all(log["planner_ok"][log["mode"] == "OFFBOARD"] > 0.5)
    # the nominal kinematic model predicts that the vehicle flies the command it was sent
    np.testing.assert_allclose(log.stack(*PRED), log.stack(*CMD), atol=1e-9)
    assert tracking_rmse_m(log) < 0.3
    assert 0.0 < residual_rmse_mps(log) < 0.5


def test_augmented_prediction_adds_the_learned_residual():
    model = _tiny_model(residual_dt_s=0.02)
    planner = CompanionNmpc(NmpcSettings(2.0, compile_functions=False), model)
    cmd = np.array([1.0, -0.5, 0.2])
    g, _ = model.predict(cmd[None, :])
    predicted = planner.one_step_velocity(np.zeros(3), cmd)
    np.testing.assert_allclose(predicted, cmd + 0.02 * g[0], atol=1e-9)


def test_one_step_prediction_evaluates_a_position_residual_where_the_vehicle_is():
    """A residual on position features (a wind field) must be evaluated at the vehicle's
    position, not at the origin, or the logged residual of the model that flew is wrong."""
    fd = feature_definition("position_velocity", "first_order_lag", tau_s=0.5)
    rng_seed = 3
    rng = np.random.default_rng(rng_seed)
    X = rng.uniform(-20.0, 20.0, (300, fd.n_features))
    X[:, 2:] = rng.uniform(-1.5, 1.5, (300, 3))
    width = rng.uniform(3.0, 6.0)
    Y = np.zeros((300, 3))
    Y[:, 1] = np.exp(-((X[:, 0] / width) ** 2))  # an eastward push near the line n = 0
    gp = SparseGP(inducing=InducingConfig(m=20), n_restarts=1, random_state=rng_seed).fit(X, Y)
    model = ResidualModel.from_estimator(gp, fd)
    planner = CompanionNmpc(NmpcSettings(2.0, compile_functions=False), model)
    vel, cmd = np.array([0.5, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])
    for pos in (np.array([0.0, 3.0, -3.0]), np.array([15.0, -4.0, -3.0])):
        z = np.concatenate([pos[:2], vel])
        g, _ = model.predict(z[None, :])
        lag_only = vel + (cmd - vel) * (1.0 - np.exp(-0.02 / 0.5))
        predicted = planner.one_step_velocity(vel, cmd, pos)
        np.testing.assert_allclose(predicted, lag_only + 0.02 * g[0], atol=2e-4)


@pytest.mark.parametrize(
    ("write", "message"),
    [
        (lambda p: p.with_suffix(".npz").write_bytes(b"{not a model"), "not a readable model"),
        (lambda p: save_model(p, _tiny_model(residual_dt_s=0.05)), "every 0.02 s"),
        (lambda p: save_model(p, _tiny_model("history", residual_dt_s=0.02)), "cannot feed"),
        (lambda p: None, "no such model file"),
    ],
    ids=["corrupt", "other-rate", "other-features", "missing"],
)
def test_bad_model_file_is_a_one_line_error_before_flight(tmp_path, write, message):
    model_path = tmp_path / "model"
    write(model_path)
    log_path = tmp_path / "flight.csv"
    config = CompanionConfig(
        mission_path=LINE,
        link="inprocess",
        planner="nmpc",
        log_path=log_path,
        gp_model=model_path.with_suffix(".npz"),
    )
    with pytest.raises(CompanionInputError, match=message) as err:
        run_companion(config, lambda message: None)
    assert "\n" not in str(err.value)
    assert not log_path.exists()


def test_cli_refuses_a_corrupt_model_with_exit_code_2(tmp_path, capsys):
    model = tmp_path / "model.npz"
    np.savez(model, header=np.array(json.dumps({"format": "residual-gp", "format_version": 99})))
    code = companion_main(
        [
            str(LINE),
            "--link",
            "inprocess",
            "--planner",
            "nmpc",
            "--gp-model",
            str(model),
            "--log",
            str(tmp_path / "f.csv"),
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "version 99" in err[0]


def test_a_plan_late_on_a_busy_computer_is_flown_not_braked_on():
    sim = Simulator(load_sim_config("iris_study"), seed=0)
    state = link_state_of(sim.state)
    reference = BSplineReference(np.array([[0.0, 0.0, -3.0], [10.0, 0.0, -3.0]]), 1.5)
    # a time budget no solver meets: every plan is "late", but solved from this tick's state
    # well within LATE_FALLBACK_S, so it is flown (braking on each would stop the flight)
    planner = CompanionNmpc(NmpcSettings(2.0, time_budget_s=1e-9))
    policy = PlannerPolicy(planner, reference, 0.0, CommandLimits(2.0))
    decision = policy.decide(state, 1.0)
    assert decision.ok, decision.reason
    assert decision.command.vel_ned_mps[0] > 0.1  # north, along the reference
    assert decision.pred_vel_ned_mps is not None
