"""The demo's report says which model the second flight flew, as its two checks decided: the
learned model, its structure alone (the GP left out), or nominal (the model refused)."""

from __future__ import annotations

import pytest

from experiments.bench.nmpc import flying_model
from experiments.study.mavlink_demo import what_flew_second
from gp.prediction_check import PredictionCheck
from gp.training import TrainingResult


def check(candidate_rmse_m: float, incumbent_rmse_m: float) -> PredictionCheck:
    return PredictionCheck("learned", "other", candidate_rmse_m, incumbent_rmse_m, 2.0, 66)


@pytest.mark.parametrize(
    ("against_nominal", "against_structure", "expected"),
    [
        (check(0.03, 0.42), check(0.02, 0.03), "augmented with `gp.npz`: the lag plus a sparse"),
        (check(0.03, 0.42), check(0.03, 0.02), "augmented with the lag alone (from `gp.npz`)"),
        (check(0.50, 0.42), None, "with the nominal planner again: the learned model (`gp.npz`"),
    ],
)
def test_the_report_names_the_model_the_checks_let_fly(
    against_nominal, against_structure, expected
):
    fit = TrainingResult(
        model=flying_model(features_name="velocity"),
        train=None,  # the sentence reads only the model and the two verdicts
        test=None,
        metrics={},
        check=against_nominal,
        structure_check=against_structure,
    )
    sentence = what_flew_second(fit, "gp.npz", "the lag")
    assert sentence.startswith(expected)
    assert "a sparse GP on `velocity` features" in sentence
