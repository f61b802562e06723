"""The multi-step prediction check: a learned model flies only if it predicts better."""

import numpy as np
import pytest
from gp_synthetic_logs import lag_plant_log, level_flight_row

from flightlog.schema import FlightLogRecorder
from gp.prediction_check import (
    PredictionCheck,
    Predictor,
    check_prediction,
    horizon_prediction_rmse,
    refusal,
    split_logs,
)
from gp.training import TrainingConfig, train_residual_model
from planners.nominal_models import (
    INTEGRATOR_STATES,
    first_order_lag,
    kinematic_4dof,
    px4_velocity_pi,
)


@pytest.fixture(scope="module")
def hidden_plant_logs():
    rng = np.random.default_rng(17)
    tau_s, drag = rng.uniform(0.25, 0.6), rng.uniform(0.05, 0.2)
    return [lag_plant_log(s, tau_s, drag) for s in range(5)]


def test_a_learned_lag_plus_gp_beats_the_kinematic_model_it_replaces(hidden_plant_logs):
    config = TrainingConfig(
        features="state_input", nominal="first_order_lag", m=20, restarts=1, check_horizon_s=2.0
    )
    result = train_residual_model(hidden_plant_logs, config)
    assert result.check is not None and result.may_fly, result.check.describe()
    assert result.check.gain > 2.0
    assert result.model.training["prediction_check"]["passed"] is True
    assert refusal(result.model) is None


def test_a_model_that_predicts_worse_is_refused_in_one_line(hidden_plant_logs):
    _, held = split_logs(hidden_plant_logs)
    truthish = Predictor("lag", first_order_lag(0.4))
    worse = Predictor("kinematic", kinematic_4dof())
    check = check_prediction(worse, truthish, held, horizon_s=2.0)
    assert not check.passed and "does NOT beat" in check.describe()


def test_a_model_that_is_the_truth_predicts_with_no_error_from_every_stride_th_row():
    """A vehicle cruising at (2, -1, 0) m/s under that very command, 101 rows 0.02 s apart:
    the kinematic model predicts its position exactly, so the RMSE over a 1 s horizon (50
    rows, each compared with the row it predicts) is 0; a start k needs rows k+1..k+50, so
    the starts are rows 0, 5, ..., 50: 11 rollouts."""
    rec = FlightLogRecorder({"source": "synthetic"})
    v = np.array([2.0, -1.0, 0.0])
    for k in range(101):
        rec.append(level_flight_row(k * 0.02, np.array([0.0, 0.0, -5.0]) + v * k * 0.02, v, v))
    rmse, starts = horizon_prediction_rmse(
        Predictor("truth", kinematic_4dof()), [rec.to_log()], 1.0
    )
    assert rmse == pytest.approx(0.0, abs=1e-9)
    assert starts == 11


def test_a_candidate_that_only_ties_the_incumbent_does_not_pass():
    """The candidate passes when its error is strictly below the incumbent's."""
    tie = PredictionCheck("learned", "nominal", 0.05, 0.05, 2.0, 10)
    assert not tie.passed and "does NOT beat" in tie.describe()
    assert PredictionCheck("learned", "nominal", 0.049, 0.05, 2.0, 10).passed


def test_a_model_without_a_residual_starts_its_integrator_at_zero():
    """As the companion plans without a residual (offset-free from 0), the rollouts of a model
    with an autopilot integrator state and no residual start it at 0; the other states start
    as measured."""
    model = px4_velocity_pi()
    x = np.arange(1.0, model.nx + 1.0)[:, None] * np.ones((1, 3))  # (nx, 3 starts)
    start = Predictor("pi", model).start_states(x)
    rows = [i for i, c in enumerate(model.state_names) if c in INTEGRATOR_STATES]
    assert len(rows) == 3 and np.all(start[rows] == 0.0)
    others = [i for i in range(model.nx) if i not in rows]
    np.testing.assert_array_equal(start[others], x[others])


def test_a_rollouts_previous_velocity_is_measured_until_it_has_predicted_it():
    """The previous velocity ``lag`` = 3 rows back of rollouts from rows 10 and 20 of a log
    whose north velocity is its row number: before step h it is the velocity at row k0 + h - 3,
    measured for h <= 3 (rows 7, 17 at h = 0; rows 10, 20, the starts, at h = 3), then the
    rollout's own prediction (after step h - 4)."""
    from gp.prediction_check import _History
    from planners.nominal_models import HISTORY_STATES
    from planners.velocity_history import with_velocity_history

    rec = FlightLogRecorder({"source": "synthetic"})
    for k in range(40):
        vel = np.array([float(k), 0.0, 0.0])
        rec.append(level_flight_row(k * 0.02, np.zeros(3), vel, vel))
    model = with_velocity_history(first_order_lag(0.3))
    history = _History(model, rec.to_log(), np.array([10, 20]), 3)
    prev_n = model.state_names.index(HISTORY_STATES[0])
    vel_n = model.state_names.index("vel_n_mps")
    x = np.zeros((model.nx, 2))
    seen = []
    for h in range(5):
        x = history.fill(x, h)
        seen.append(list(x[prev_n]))
        x[vel_n] = [-1.0 - h, -101.0 - h]  # the rollout's prediction after step h
        history.append(x)
    assert seen == [[7, 17], [8, 18], [9, 19], [10, 20], [-1, -101]]


def test_split_logs_holds_out_whole_logs_or_each_log_tail(hidden_plant_logs):
    train, held = split_logs(hidden_plant_logs, 0.25)
    assert len(train) == 4 and len(held) == 1
    train, held = split_logs(hidden_plant_logs[:1], 0.25)
    assert train[0].n_rows + held[0].n_rows == hidden_plant_logs[0].n_rows
    assert held[0]["t_s"][0] > train[0]["t_s"][-1]


def test_split_logs_rotated_holds_out_a_different_quarter_of_each_log(hidden_plant_logs):
    logs = hidden_plant_logs[:4]
    train, held = split_logs(logs, 0.25, rotate=True)
    assert len(held) == 4
    for i, (log, part) in enumerate(zip(logs, held, strict=True)):
        t, quarter = log["t_s"], log.n_rows / 4
        first, last = np.searchsorted(t, part["t_s"][[0, -1]])
        assert abs(first - (3 - i) * quarter) <= 1 and abs(last + 1 - (4 - i) * quarter) <= 1
    # every row is either trained on or held out, exactly once
    assert sum(log.n_rows for log in train + held) == sum(log.n_rows for log in logs)
    (_, [tail]), (_, [plain]) = split_logs(logs[:1], 0.25, rotate=True), split_logs(logs[:1])
    np.testing.assert_array_equal(tail["t_s"], plain["t_s"])  # one log: its tail, as before
    five = split_logs(hidden_plant_logs, 0.25, rotate=True)
    assert [len(x) for x in five] == [4, 1]  # enough logs: whole logs, as without rotation


def test_the_companion_refuses_a_model_file_that_failed_its_check(hidden_plant_logs):
    from dataclasses import replace

    from companion.nmpc_planner import check_residual_model
    from gp.errors import ModelFileError

    config = TrainingConfig(features="state_input", nominal="first_order_lag", m=10, restarts=1)
    model = train_residual_model(hidden_plant_logs[:2], config).model
    failed = {"candidate": "learned", "incumbent": "nominal kinematic_4dof", "passed": False,
              "candidate_rmse_m": 0.5, "incumbent_rmse_m": 0.4, "horizon_s": 2.0}  # fmt: skip
    bad = replace(model, training={**model.training, "prediction_check": failed})
    with pytest.raises(ModelFileError, match="refusing the learned model") as info:
        check_residual_model(bad, period_s=0.02)
    assert "\n" not in str(info.value)
    check_residual_model(model, period_s=0.02)  # an unchecked model is not refused
    # a check without its verdict (a damaged or hand-edited file) cannot vouch for the model
    no_verdict = {k: v for k, v in failed.items() if k != "passed"}
    unknown = replace(model, training={**model.training, "prediction_check": no_verdict})
    with pytest.raises(ModelFileError, match="without its verdict"):
        check_residual_model(unknown, period_s=0.02)
    assert refusal(replace(model, training={**model.training, "prediction_check": {}})) is not None


def test_a_gp_that_does_not_beat_its_structure_flies_without_it(hidden_plant_logs):
    from dataclasses import replace

    from gp.prediction_check import structure_only

    config = TrainingConfig(features="state_input", nominal="first_order_lag", m=10, restarts=1)
    model = train_residual_model(hidden_plant_logs[:2], config).model
    assert not structure_only(model)
    assert Predictor.as_flown(model).residual is model
    worse = {"candidate": "learned", "incumbent": "first_order_lag alone", "passed": False,
             "candidate_rmse_m": 0.2, "incumbent_rmse_m": 0.03, "horizon_s": 2.0}  # fmt: skip
    refused = replace(model, training={**model.training, "prediction_check_structure": worse})
    assert structure_only(refused)
    # a refit is judged against what flew: the structure alone
    flown = Predictor.as_flown(refused)
    assert flown.residual is None and flown.model.name == "first_order_lag"
    # the study's closed-loop check chose the structure alone (experiments.study.closed_loop)
    for chosen in (True, False):
        record = {"flies": "x", "structure_flies": chosen, "comparisons": []}
        trained = {**model.training, "closed_loop_check": record}
        assert structure_only(replace(model, training=trained)) is chosen


def test_a_model_measured_at_another_rate_is_refused_with_the_rate_to_fly(hidden_plant_logs):
    """fit-gp tells a user to fly at the model's rate with companion --rate-hz; the companion's
    refusal only said to refit."""
    from companion.nmpc_planner import check_residual_model
    from gp.errors import ModelFileError

    config = TrainingConfig(features="velocity", nominal="kinematic_4dof", m=10, restarts=1)
    model = train_residual_model(hidden_plant_logs[:2], config).model
    dt_s = dict(model.features.nominal_params)["residual_dt_s"]
    check_residual_model(model, period_s=dt_s)
    with pytest.raises(ModelFileError) as info:
        check_residual_model(model, period_s=2.0 * dt_s)
    assert f"fly at its rate (companion --rate-hz {1.0 / dt_s:.4g}) or refit" in str(info.value)
