"""The learning-disabled pass of a scheduled regime ([Ostafew16] Fig. 11's comparison)."""

import numpy as np
import pytest

from experiments.rover.report import learning_disabled_pass, same_schedule_figures
from experiments.rover.scenarios import scenario
from experiments.rover.trial import run_trials


@pytest.mark.slow
def test_learning_disabled_pass_repeats_the_last_trial_without_the_gp() -> None:
    sc = scenario("rover_exp2", seed=3).with_trials(2)
    records = run_trials(sc)
    assert records[1].n_local.max() > 0  # the second trial drew on the first's experience
    off = learning_disabled_pass(sc, records)
    np.testing.assert_array_equal(off.schedule_mps, records[1].schedule_mps)
    assert off.n_local.max() == 0
    # same trial index: the same start pose, so the same errors before the first command
    assert off.e_lat_m[0] == pytest.approx(records[1].e_lat_m[0], abs=1e-12)
    assert off.e_head_rad[0] == pytest.approx(records[1].e_head_rad[0], abs=1e-12)
    figs = same_schedule_figures(records[1], off)
    assert figs["learning_disabled_max_e_lat_m"] == off.max_e_lat_m
    assert figs["max_lateral_reduction_vs_learning_disabled"] == pytest.approx(
        1.0 - records[1].max_e_lat_m / off.max_e_lat_m
    )
