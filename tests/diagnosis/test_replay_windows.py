"""The replay's windows over the airborne runs of a log."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.replay import ReplayResult, airborne_runs, windows
from flightlog.schema import FlightLog


def test_a_last_run_shorter_than_the_lead_in_gives_no_window_not_an_index_error():
    """A log that ends 0.3 s after a dropout: the last run has no row past its lead-in, whose
    anchor fell one past the log's last row (IndexError, a traceback out of diagnose)."""
    t = np.r_[np.arange(0.0, 10.0, 0.1), 20.0 + np.arange(0.0, 0.3, 0.1)]
    log = FlightLog({"t_s": t, "pos_d_m": np.full(t.size, -5.0)})
    wins = windows([log], 2.0)
    assert wins and all(w.stop < 100 for w in wins)  # all in the first, 10 s run
    assert windows([FlightLog({"t_s": t[100:], "pos_d_m": np.full(3, -5.0)})], 2.0) == []


@pytest.mark.timeout(30)
@pytest.mark.parametrize("window_s", [0.0, -1.0, float("inf"), float("nan")])
def test_a_window_length_that_is_no_positive_duration_is_refused(window_s):
    """DiagnosisConfig.window_s = 0 made each window end at its own anchor and the next start
    there: windows() never returned; inf and NaN gave no window, silently."""
    t = 0.1 * np.arange(100)
    log = FlightLog({"t_s": t, "pos_d_m": np.full(t.size, -5.0)})
    with pytest.raises(ValueError, match="replay window .* must be a finite number of seconds"):
        windows([log], window_s)


def test_window_times_are_counted_from_the_logs_start():
    """A log whose clock starts at 100 s (a ULog's boot time): windows of 2 s after the 1 s
    lead-in start 1, 3, 5 and 7 s into it; the one at 9 s would run past its end."""
    t = 100.0 + 0.125 * np.arange(80)  # 10 s, exact in binary
    log = FlightLog({"t_s": t, "pos_d_m": np.full(t.size, -5.0)})
    assert [w.t_anchor_s for w in windows([log], 2.0)] == [1.0, 3.0, 5.0, 7.0]


def test_an_offboard_mode_is_recognised_whatever_its_case():
    n = 50
    mode = np.array(["Offboard"] * n + ["POSCTL"] * n)
    log = FlightLog({"t_s": 0.1 * np.arange(2 * n), "pos_d_m": np.full(2 * n, -5.0), "mode": mode})
    assert airborne_runs(log) == [(0, n)]


def test_replay_rmse_is_over_the_3d_velocity_error_of_each_row():
    """Rows with errors (3, 4, 0) and (0, 0, 0) m/s: 3-D errors 5 and 0, RMS sqrt(25 / 2)."""
    result = ReplayResult(
        np.array([0.0, 0.1]), np.array([[3.0, 4.0, 0.0], [0.0, 0.0, 0.0]]), np.zeros((2, 3)),
        np.zeros(2, int),
    )  # fmt: skip
    assert np.isclose(result.rmse_mps(), np.sqrt(12.5))
    empty = ReplayResult(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, int))
    assert np.isnan(empty.rmse_mps())  # no rows compared: no error to state
