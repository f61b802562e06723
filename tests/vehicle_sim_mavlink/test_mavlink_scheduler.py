"""RateScheduler: nominal rates exactly in the long run, SET_MESSAGE_INTERVAL semantics."""

from __future__ import annotations

import numpy as np
import pytest

from vehicle_sim.mavlink.scheduler import MIN_INTERVAL_S, RateScheduler


def count_sends(scheduler: RateScheduler, duration_s: float, tick_s: float) -> dict[int, int]:
    counts: dict[int, int] = {}
    for now_s in np.arange(0.0, duration_s, tick_s):
        for msg_id in scheduler.due(float(now_s)):
            counts[msg_id] = counts.get(msg_id, 0) + 1
    return counts


@pytest.mark.parametrize("tick_s", [0.004, 0.007, 0.013])
def test_long_run_rates_match_nominal_with_uneven_ticks(tick_s):
    scheduler = RateScheduler({0: 1.0, 32: 50.0, 245: 5.0})
    counts = count_sends(scheduler, 20.0, tick_s)
    assert counts[0] == pytest.approx(20, abs=1)
    assert counts[245] == pytest.approx(100, abs=1)
    # 50 Hz cannot be met with 13 ms ticks: then it degrades to one per tick, never bursts.
    assert counts[32] == pytest.approx(min(1000, 20.0 / tick_s), rel=0.02)


def test_stall_does_not_cause_a_burst():
    scheduler = RateScheduler({32: 50.0})
    assert scheduler.due(0.0) == [32]
    assert scheduler.due(5.0) == [32]  # one send after a 5 s stall, not 250
    assert scheduler.due(5.001) == []
    assert scheduler.due(5.02) == [32]


def test_set_interval_stop_default_and_new_stream():
    scheduler = RateScheduler({32: 50.0})
    scheduler.set_interval_us(32, -1)
    assert scheduler.interval_s(32) is None and scheduler.due(1.0) == []
    scheduler.set_interval_us(32, 0)
    assert scheduler.interval_s(32) == pytest.approx(0.02)
    scheduler.set_interval_us(30, 100_000)
    assert scheduler.interval_s(30) == pytest.approx(0.1)
    scheduler.set_interval_us(30, 1)
    assert scheduler.interval_s(30) == MIN_INTERVAL_S
    scheduler.set_interval_us(31, 0)  # no default: stays off
    assert scheduler.interval_s(31) is None


@pytest.mark.parametrize("bad", [-2.0, float("nan"), float("inf")])
def test_bad_interval_raises(bad):
    with pytest.raises(ValueError, match="interval must be -1, 0 or > 0 us"):
        RateScheduler({}).set_interval_us(30, bad)
