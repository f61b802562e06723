"""train_residual_model on synthetic logs: every feature set learns the known residual."""

import numpy as np
import pytest
from gp_synthetic_logs import record_log

from gp.training import TrainingConfig, train_residual_model


@pytest.mark.parametrize(
    ("features", "nominal", "params"),
    [
        ("velocity", "kinematic_4dof", ()),
        ("state_input", "kinematic_4dof", ()),
        ("history", "kinematic_4dof", ()),
        ("state_input", "first_order_lag", (("tau_s", 0.3),)),
    ],
)
def test_every_feature_set_halves_the_held_out_nominal_error(features, nominal, params):
    logs = [record_log(500, seed=s, noise_mps=0.002) for s in range(2)]
    config = TrainingConfig(
        features=features, nominal=nominal, nominal_params=params, m=20, restarts=2, seed=1
    )
    messages = []
    result = train_residual_model(logs, config, messages.append)
    nominal_rmse = np.array(result.metrics["nominal_rmse_mps"])
    augmented_rmse = np.array(result.metrics["augmented_rmse_mps"])
    assert np.all(augmented_rmse < 0.5 * nominal_rmse), (nominal_rmse, augmented_rmse)
    assert result.model.features.name == features
    assert dict(result.model.features.nominal_params).get("residual_dt_s", 0.05) == 0.05
    assert any("held out" in m for m in messages)


@pytest.mark.parametrize(
    ("beats_nominal", "beats_structure", "closed_loop_chose_structure", "flown"),
    [
        (True, True, False, "learned"),
        (True, False, False, "structure"),  # the GP does not beat the structure alone
        (True, True, True, "structure"),  # the closed-loop check chose the structure
        (False, True, False, "nominal"),  # refused, whatever else
        (False, False, True, "nominal"),
    ],
)
def test_what_flies_follows_the_checks_in_their_order(
    beats_nominal, beats_structure, closed_loop_chose_structure, flown
):
    from dataclasses import replace

    from experiments.bench.nmpc import flying_model
    from gp.prediction_check import PredictionCheck
    from gp.training import TrainingResult

    def check(passes: bool) -> PredictionCheck:  # candidate RMSE below the incumbent's: passes
        return PredictionCheck("learned", "other", 0.02 if passes else 0.05, 0.03, 2.0, 66)

    model = flying_model(features_name="velocity")
    if closed_loop_chose_structure:
        model = replace(model, training={"closed_loop_check": {"structure_flies": True}})
    fit = TrainingResult(
        model, None, None, {}, check=check(beats_nominal), structure_check=check(beats_structure)
    )
    assert fit.flown == flown
