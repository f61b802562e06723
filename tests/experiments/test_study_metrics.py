"""Tracking figures of one log: the settled figure leaves out the start, nothing else."""

from __future__ import annotations

import numpy as np

from experiments.study.metrics import SETTLE_S, settled_tracking_rmse_m, tracking_rmse_m
from flightlog.schema import FlightLog

_AXES = ("n", "e", "d")


def _log(t: np.ndarray, mode: np.ndarray, error_n: np.ndarray) -> FlightLog:
    zeros = np.zeros_like(t)
    columns = {"t_s": t, "mode": mode}
    for a in _AXES:
        columns[f"ref_pos_{a}_m"] = zeros
        columns[f"pos_{a}_m"] = error_n if a == "n" else zeros
    return FlightLog(columns, {})


def test_settled_tracking_leaves_out_the_first_seconds_of_following_only():
    rng = np.random.default_rng(7)
    dt = 0.02
    t = np.arange(0.0, 12.0, dt)
    start = rng.uniform(1.0, 3.0)  # when OFFBOARD begins [s]
    mode = np.where(t >= start, "OFFBOARD", "HOLD")
    t0 = t[mode == "OFFBOARD"][0]
    offset = rng.uniform(0.3, 0.8)  # the offset the takeoff left [m]
    late_error = rng.normal(0.0, rng.uniform(0.02, 0.05), t.size)
    error = np.where(t - t0 < SETTLE_S, offset, late_error)
    log = _log(t, mode, error)
    follow = t - t0 >= SETTLE_S
    expected = np.sqrt(np.mean(late_error[follow] ** 2))
    np.testing.assert_allclose(settled_tracking_rmse_m(log), expected, rtol=1e-12)
    assert tracking_rmse_m(log) > settled_tracking_rmse_m(log) + 0.1
    assert np.isnan(settled_tracking_rmse_m(log, settle_s=t[-1] - t0 + 1.0))
