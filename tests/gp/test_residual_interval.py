"""The residual's interval in log steps: a whole number of the logs' median step, or refused."""

from pathlib import Path

import numpy as np
import pytest
from gp_synthetic_logs import record_log

from flightlog.schema import FlightLog
from gp.errors import GPInputError
from gp.residual_interval import log_step_s, mixed_steps, residual_steps


@pytest.mark.parametrize(("dt_s", "steps"), [(0.02, 5), (0.05, 2), (0.1, 1)])
def test_the_nmpcs_interval_in_steps_of_50_20_and_10_hz_logs(dt_s, steps):
    logs = [record_log(60, dt_s=dt_s, seed=i) for i in range(2)]
    assert residual_steps(logs, 0.1) == steps


def test_a_wall_clock_logs_jitter_and_dropped_rows_do_not_move_the_step():
    rng = np.random.default_rng(0)
    t = np.cumsum(0.02 + 0.002 * rng.standard_normal(500))
    t = np.delete(t, [50, 51, 200])  # rows the link dropped
    log = FlightLog({"t_s": t})
    assert log_step_s([log]) == pytest.approx(0.02, abs=5e-4)
    assert residual_steps([log], 0.1) == 5


@pytest.mark.parametrize("interval_s", [0.05, 0.01])
def test_an_interval_that_is_no_whole_number_of_steps_is_refused_in_one_line(interval_s):
    """2.5 steps of a 50 Hz log, and half of one."""
    with pytest.raises(GPInputError) as info:
        residual_steps([record_log(60, dt_s=0.02)], interval_s)
    message = str(info.value)
    assert "\n" not in message
    assert f"residual interval {interval_s:g} s is not a whole number" in message
    assert "the logs' 0.02 s steps; give a multiple of it" in message


def test_logs_of_different_rates_are_said_in_one_line_and_one_rate_is_not():
    """A 50 Hz companion log beside a 10 Hz PX4 ULog was pooled without a word."""
    fast = record_log(60, dt_s=0.02)
    slow = FlightLog({"t_s": np.arange(30) * 0.1}, path=Path("px4.ulg"))
    assert mixed_steps([fast, record_log(60, dt_s=0.02, seed=1)]) is None
    message = mixed_steps([fast, slow])
    assert message is not None and "\n" not in message
    assert message.startswith("the logs are of different rates (steps 0.02 s in ")
    assert "0.1 s in px4.ulg" in message and "fit logs of one rate together" in message
