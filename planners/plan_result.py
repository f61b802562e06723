"""What a planner returns: a command, the plan behind it, and whether it can be trusted."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class PlanResult:
    """One planning step's outcome.

    Attributes:
        command: model input to apply now, shape (nu,), in the model's ``input_names`` order;
            for the multirotor models (vel_n, vel_e, vel_d [m/s], yaw_rate [rad/s]) in NED.
            When ``ok`` is False this is the safe command (zero velocity and yaw rate: brake and
            hover).
        predicted_trajectory: planned states, shape (N + 1, nx), row 0 the current state;
            shape (0, nx) when the planner has no prediction (failure, PD regulator).
        ok: True when the command comes from a successful, timely plan.
        reason: empty when ok, otherwise why the safe command was returned.
        solve_time_s: computation time of this step [s].
        predicted_inputs: planned inputs, shape (N, nu), row 0 the command; shape (0, nu)
            without a prediction.
    """

    command: np.ndarray
    predicted_trajectory: np.ndarray
    ok: bool
    reason: str
    solve_time_s: float
    predicted_inputs: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    def __post_init__(self) -> None:
        for name in ("command", "predicted_trajectory", "predicted_inputs"):
            arr = np.array(getattr(self, name), dtype=float)
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)


def safe_result(nu: int, nx: int, reason: str, solve_time_s: float = 0.0) -> PlanResult:
    """The brake/hover answer: zero input of size ``nu``, no prediction, ``ok=False``."""
    return PlanResult(
        np.zeros(nu), np.zeros((0, nx)), False, reason, solve_time_s, np.zeros((0, nu))
    )
