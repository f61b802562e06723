"""The learning-disabled pass of a scheduled regime ([Ostafew16] Fig. 11's comparison); the
within-trial safety governor on a pass too fast for its model."""

from dataclasses import replace

import numpy as np
import pytest

from experiments.rover.learner import make_history_gp
from experiments.rover.report import learning_disabled_pass, same_schedule_figures
from experiments.rover.scenarios import scenario
from experiments.rover.trial import run_trial, run_trials


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


def test_safety_governor_keeps_a_pass_too_fast_for_its_model_near_the_path() -> None:
    # experiment 2's robot at 1.2 m/s everywhere on its first pass, nothing learned: without the
    # governor the plain unicycle NMPC swings off the path (measured 1.35 m); with it the robot
    # drops to v_init where the errors pass twice the scheduler's thresholds
    base = replace(scenario("rover_exp2"), learning=False)
    fast = np.full(len(base.path), 1.2)
    free = run_trial(replace(base, governor_trip_factor=None), make_history_gp(), fast, 0)
    governed = run_trial(base, make_history_gp(), fast, 0)
    assert free.safety_trips == 0 and free.max_e_lat_m > 1.0
    assert governed.safety_trips >= 1 and governed.completed
    assert np.min(governed.v_cmd_mps) == base.scheduler.v_init_mps
    assert governed.max_e_lat_m < 0.5 * free.max_e_lat_m


@pytest.mark.slow
def test_trials_figure_counts_trials_in_whole_numbers_and_names_each_schedule() -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from experiments.rover.report import trials_figure

    sc = scenario("rover_exp1", seed=0).with_trials(2)
    records = run_trials(sc)
    fig = trials_figure(records, sc.path.s_m, "rover_exp1")
    FigureCanvasAgg(fig).draw()
    errors, speeds, times = fig.axes
    for ax in (errors, times):
        lo, hi = ax.get_xlim()
        ticks = [t for t in ax.get_xticks() if lo <= t <= hi]
        assert ticks == [1.0, 2.0], ticks  # no trial 1.25
    assert [t.get_text() for t in speeds.get_legend().get_texts()] == ["trial 1", "trial 2"]
