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
    # a slower same-schedule pass is explained by its governor trips, reported beside it
    assert figs["learning_disabled_safety_trips"] == off.safety_trips
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


def test_the_regime_figure_labels_every_axis_and_says_which_line_is_which_trial() -> None:
    """Every panel has its quantity and unit on both axes, trials are whole numbers, and the
    scheduled-speed lines carry a trial colour bar (one line per trial, otherwise unnamed)."""
    import matplotlib.pyplot as plt

    from experiments.rover.report import figure

    sc = scenario("rover_exp1").with_trials(2)
    records = run_trials(sc)
    fig = figure(records, sc.path.s_m, "rover_exp1")
    try:
        errors, along, speeds, times = fig.axes[:4]
        for ax in (errors, along, speeds, times):
            assert ax.get_xlabel() and ax.get_ylabel(), ax
        # [Ostafew16] Figs. 9, 12, 17: e_L along the path, first trial against the last
        labels = [t.get_text() for t in along.get_legend().get_texts()]
        assert labels == ["trial 1", "trial 2"] and "[m]" in along.get_ylabel()
        first = along.get_lines()[0]
        np.testing.assert_array_equal(first.get_ydata(), records[0].e_lat_m)
        assert "[m]" in errors.get_ylabel() and "[rad]" in errors.get_ylabel()
        colour_bars = [ax for ax in fig.axes[4:] if ax.get_ylabel() == "trial"]
        assert len(colour_bars) == 1
        for ax in (errors, times):
            ticks = [t for t in ax.get_xticks() if 1 <= t <= len(records)]
            assert ticks and all(float(t).is_integer() for t in ticks), ticks
    finally:
        plt.close(fig)


def test_a_one_trial_figure_draws_that_trial_once() -> None:
    """`rover --trials 1`: the first trial is the last; e_L along the path is one line with one
    legend entry, not the same trial drawn and named twice."""
    import matplotlib.pyplot as plt

    from experiments.rover.report import figure

    sc = scenario("rover_exp1").with_trials(1)
    fig = figure(run_trials(sc), sc.path.s_m, "rover_exp1")
    try:
        along = fig.axes[1]
        assert [t.get_text() for t in along.get_legend().get_texts()] == ["trial 1"]
    finally:
        plt.close(fig)
