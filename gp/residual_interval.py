"""The residual's interval as a whole number of log steps.

The residual is measured over H log steps (gp.datasets); a planner that applies it over its
own interval (the NMPC's 0.1 s) needs H steps to make that interval, so H is the interval
divided by the logs' step, and only a whole number of steps will do. The logs' step is their
median time step, so a wall-clock log's jitter and an occasional dropped row do not move it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flightlog.schema import FlightLog
from gp.errors import GPInputError

# An interval this far from a whole number of steps, in steps, is not one (a fifth of a step:
# a 50 Hz log's 0.1 s is 5 steps within 4 ms, 0.05 s is 2.5 and refused).
WHOLE_TOLERANCE_STEPS = 0.2


# Logs whose median steps differ by more than this ratio are of different rates.
MIXED_RATE_RATIO = 1.2


def mixed_steps(logs: Sequence[FlightLog]) -> str | None:
    """One line when the logs are of different rates (their median steps differ by more than
    MIXED_RATE_RATIO), naming each log's step, else None: each residual is measured over its
    own log's steps (gp.datasets), a different quantity at another rate, while the model keeps
    one time base, the logs' median step (log_step_s)."""
    steps = [(log.where, float(np.median(np.diff(log["t_s"])))) for log in logs if log.n_rows > 1]
    values = [step for _, step in steps]
    if len(values) < 2 or max(values) <= MIXED_RATE_RATIO * min(values):
        return None
    listed = ", ".join(f"{step:.3g} s in {where}" for where, step in steps)
    return (
        f"the logs are of different rates (steps {listed}): each residual is measured over its "
        "own log's steps, a different quantity at each rate, while the model keeps one time "
        f"base (their median step, {log_step_s(logs):.3g} s); fit logs of one rate together"
    )


def log_step_s(logs: Sequence[FlightLog]) -> float:
    """The logs' median time step [s], over the consecutive rows of every log."""
    return float(np.median(np.concatenate([np.diff(log["t_s"]) for log in logs])))


def residual_steps(logs: Sequence[FlightLog], interval_s: float) -> int:
    """The whole number (>= 1) of the logs' steps (log_step_s) that makes ``interval_s`` [s].

    Raises:
        GPInputError: the interval is not within WHOLE_TOLERANCE_STEPS of a whole number
            (>= 1) of steps (one line naming both and the fix).
    """
    step_s = log_step_s(logs)
    steps = round(interval_s / step_s)
    if steps < 1 or abs(steps * step_s - interval_s) > WHOLE_TOLERANCE_STEPS * step_s:
        raise GPInputError(
            f"residual interval {interval_s:g} s is not a whole number of the logs' "
            f"{step_s:.4g} s steps; give a multiple of it (the NMPC's interval is 0.1 s)"
        )
    return steps
