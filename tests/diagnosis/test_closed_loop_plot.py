"""The closed-loop plot shows which rows its figures count: a segment a config had to be
re-anchored in (it touched down where the real vehicle flew) is left out of every figure, and
was drawn as if scored (a real v1.16 flight: "config n/a, 0 rows" beside three solid traces)."""

from types import SimpleNamespace

import numpy as np

from diagnosis import report_plots
from diagnosis.closed_loop import ClosedLoopResult


def _drawn(monkeypatch, tmp_path, whole: np.ndarray) -> dict[str, np.ndarray]:
    """label -> north velocity drawn under that label (NaN where the line is broken)."""
    t_s = np.arange(8) * 0.1
    runs = np.repeat([0, 1], 4)
    vel = np.column_stack([np.arange(8.0), np.zeros(8), np.zeros(8)])
    cl = ClosedLoopResult(t_s, vel, vel + 0.5, vel + 0.1, runs, np.zeros(8, bool), whole, 2, 1)
    drawn = {}
    close = report_plots.plt.close

    def read_then_close(fig) -> None:
        lines = fig.axes[0].get_lines()
        drawn.update({line.get_label(): np.asarray(line.get_ydata()) for line in lines})
        close(fig)

    monkeypatch.setattr(report_plots.plt, "close", read_then_close)
    d = SimpleNamespace(closed_loop=cl, added_effects={"wind": {}})
    report_plots.plot_closed_loop(d, tmp_path / "closed_loop.png")
    assert report_plots.plt.get_fignums() == []
    return drawn


def test_a_reanchored_segment_is_drawn_apart_from_the_scored_rows(monkeypatch, tmp_path):
    whole = np.repeat([True, False], 4)  # segment 1 re-anchored
    drawn = _drawn(monkeypatch, tmp_path, whole)
    scored = drawn["closed loop, config"]
    assert np.allclose(scored[np.isfinite(scored)], np.arange(4.0) + 0.5)
    apart = drawn["closed loop, config, re-anchored (not scored)"]
    assert np.allclose(apart[np.isfinite(apart)], np.arange(4.0, 8.0) + 0.5)
    assert "closed loop, extended, re-anchored (not scored)" in drawn


def test_a_plot_of_whole_segments_has_no_not_scored_trace(monkeypatch, tmp_path):
    drawn = _drawn(monkeypatch, tmp_path, np.ones(8, bool))
    assert not [label for label in drawn if "not scored" in label]
    assert np.isfinite(drawn["closed loop, config"]).sum() == 8
