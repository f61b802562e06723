"""rover-path repeat's report: its lines, JSON and figure, on a drive made by hand."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from experiments.rover.link_drive import LinkDrive
from experiments.rover.repeat import Trial
from experiments.rover.repeat_report import figure, history_row, trial_line


def _trial(number: int, speed_mps: float) -> Trial:
    """A 10 s drive along a 5 m path at ``speed_mps``, scheduled a little faster."""
    t_s = np.linspace(0.0, 10.0, 101)
    s_m = speed_mps * t_s
    e = 0.01 * np.sin(t_s)
    vertex = np.zeros(21)
    drive = LinkDrive(t_s, s_m, e, e, e, vertex, vertex, vertex, reached_end=True)
    return Trial(number, drive, np.full(21, speed_mps + 0.05), 10 * number)


def test_the_figure_shows_each_trials_schedule_and_the_speed_it_drove() -> None:
    trials = [_trial(1, 0.35), _trial(2, 0.5)]
    history = np.array([history_row(t) for t in trials])
    path_s_m = np.linspace(0.0, 5.0, 21)
    fig = figure(history, "test", path_s_m, trials)
    try:
        speeds = fig.axes[2]
        scheduled = [line for line in speeds.lines if line.get_label().endswith("scheduled")]
        assert [line.get_label() for line in scheduled] == [
            "trial 1 scheduled",
            "trial 2 scheduled",
        ]
        np.testing.assert_allclose(scheduled[1].get_ydata(), 0.55)
        driven = [line for line in speeds.lines if line.get_linestyle() == "None"]
        medians = [float(np.median(line.get_ydata())) for line in driven]
        np.testing.assert_allclose(medians, [0.35, 0.5])
        assert "distance along the path" in speeds.get_xlabel()
    finally:
        plt.close(fig)


def test_a_trial_line_gives_the_speed_driven_and_scheduled() -> None:
    line = trial_line(_trial(2, 0.5))
    assert "at 0.50 m/s mean (0.55 m/s scheduled)" in line and line.startswith("trial 2:")
