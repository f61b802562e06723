"""Command-path causes (command_delay, motor_lag): 1-D bounded search by replay error.

Each cause has one parameter; its value is chosen on the training windows by a coarse grid
followed by a bounded scalar refinement around the best grid point, then judged on the held-out
windows like the force causes: it is named only if it removes at least ``min_gain_fraction`` of
the held-out replay mean squared velocity error that is left.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from diagnosis.cause import Cause
from diagnosis.replay import ReplayResult, Window, replay
from flightlog.schema import FlightLog
from vehicle_sim import SimConfig

COMMAND_CAUSES: tuple[str, ...] = ("command_delay", "motor_lag")

# name -> (parameter, grid of values)
SEARCH_GRIDS: dict[str, tuple[str, np.ndarray]] = {
    "command_delay": ("delay_s", np.linspace(0.0, 0.4, 9)),
    "motor_lag": ("tau_s", np.geomspace(0.008, 0.25, 9)),
}


@dataclass(frozen=True)
class ReplayThresholds:
    """A command-path cause is named if it removes at least ``min_gain_fraction`` of the
    held-out replay mean squared velocity error left and at least ``min_gain_mps`` [m/s] of
    its RMSE."""

    min_gain_fraction: float = 0.5
    min_gain_mps: float = 0.003


@dataclass(frozen=True)
class CommandFit:
    """A fitted command-path cause.

    Attributes:
        name: cause name; param, value: its one parameter and the fitted value.
        train_rmse_mps, test_rmse_mps: replay velocity RMSE with it, training / held-out windows.
    """

    name: str
    param: str
    value: float
    train_rmse_mps: float
    test_rmse_mps: float


def with_cause(config: SimConfig, name: str, value: float) -> SimConfig:
    """``config`` with command-path cause ``name`` set to ``value``."""
    param, _ = SEARCH_GRIDS[name]
    return config.with_effects({name: {param: float(value)}})


def fit_command_cause(
    name: str,
    config: SimConfig,
    logs: Sequence[FlightLog],
    train: Sequence[Window],
    test: Sequence[Window],
    progress: Callable[[str], None] = lambda msg: None,
) -> CommandFit:
    """Search the parameter of ``name`` on ``train`` windows; score it on ``test`` windows."""
    param, grid = SEARCH_GRIDS[name]

    def train_rmse(value: float) -> float:
        return replay(with_cause(config, name, value), logs, train).rmse_mps()

    scores = [train_rmse(v) for v in grid]
    k = int(np.argmin(scores))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    best_value, best_score = float(grid[k]), scores[k]
    if hi > lo:
        options = {"xatol": 1e-3 * hi, "maxiter": 6}
        sol = minimize_scalar(train_rmse, bounds=(lo, hi), method="bounded", options=options)
        if sol.fun < best_score:
            best_value, best_score = float(sol.x), float(sol.fun)
    test_rmse = replay(with_cause(config, name, best_value), logs, test).rmse_mps()
    progress(f"  {name}: {param} = {best_value:.4g}, held-out replay RMSE {test_rmse:.4f} m/s")
    return CommandFit(name, param, best_value, best_score, test_rmse)


def select_command_causes(
    config_now: SimConfig,
    logs: Sequence[FlightLog],
    search: Sequence[Window],
    test: Sequence[Window],
    current: ReplayResult,
    baseline: ReplayResult,
    effects: dict[str, dict[str, object]],
    names: list[str],
    thresholds: ReplayThresholds,
    progress: Callable[[str], None],
) -> tuple[ReplayResult, list[Cause], list[Cause]]:
    """Forward selection of command-path causes by held-out replay error; adds the accepted
    ones to ``effects``. Returns the final held-out replay, accepted and rejected causes."""
    accepted: list[Cause] = []
    rejected: dict[str, Cause] = {}
    left = list(names)
    scale = max(baseline.rmse_mps() ** 2, 1e-12)
    while left and search and current.rmse_mps() >= thresholds.min_gain_mps:
        fits = [fit_command_cause(n, config_now, logs, search, test, progress) for n in left]
        best = min(fits, key=lambda f: f.test_rmse_mps)
        before = current.rmse_mps()
        for f in fits:
            rejected[f.name] = Cause(
                f.name,
                {f.param: f.value},
                float((before**2 - f.test_rmse_mps**2) / scale),
                float(max(0.0, 1.0 - (f.test_rmse_mps / before) ** 2)),
                f"held-out replay velocity RMSE {before:.4f} -> {f.test_rmse_mps:.4f} m/s",
            )
        removed = before**2 - best.test_rmse_mps**2
        if (
            removed < thresholds.min_gain_fraction * before**2
            or before - best.test_rmse_mps < thresholds.min_gain_mps
        ):
            break
        accepted.append(rejected.pop(best.name))
        effects[best.name] = {best.param: best.value}
        config_now = config_now.with_effects({best.name: {best.param: best.value}})
        current = replay(config_now, logs, test)
        left.remove(best.name)
        progress(f"accepted {best.name}")
    return current, accepted, list(rejected.values())
