"""The multi-step prediction check: a learned model flies only if it predicts better."""

import numpy as np
import pytest
from gp_synthetic_logs import lag_plant_log

from gp.prediction_check import Predictor, check_prediction, refusal, split_logs
from gp.training import TrainingConfig, train_residual_model
from planners.nominal_models import first_order_lag, kinematic_4dof


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
