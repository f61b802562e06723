"""The replay's windows over the airborne runs of a log."""

from __future__ import annotations

import numpy as np

from diagnosis.replay import windows
from flightlog.schema import FlightLog


def test_a_last_run_shorter_than_the_lead_in_gives_no_window_not_an_index_error():
    """A log that ends 0.3 s after a dropout: the last run has no row past its lead-in, whose
    anchor fell one past the log's last row (IndexError, a traceback out of diagnose)."""
    t = np.r_[np.arange(0.0, 10.0, 0.1), 20.0 + np.arange(0.0, 0.3, 0.1)]
    log = FlightLog({"t_s": t, "pos_d_m": np.full(t.size, -5.0)})
    wins = windows([log], 2.0)
    assert wins and all(w.stop < 100 for w in wins)  # all in the first, 10 s run
    assert windows([FlightLog({"t_s": t[100:], "pos_d_m": np.full(3, -5.0)})], 2.0) == []
