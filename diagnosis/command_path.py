"""Command-path causes (command_delay, motor_lag): 1-D bounded search by replay error.

Each cause has one parameter; its value is chosen on the training windows by a coarse grid
followed by a bounded scalar refinement around the best grid point, then judged on the held-out
windows like the force causes: it is named only if it removes at least ``min_gain_fraction`` of
the held-out replay mean squared velocity error that is left above the noise floor (the white
velocity noise of the log, which no replay can follow), if that removal is significant by a block
bootstrap over the held-out windows (:mod:`.noise_floor`), and if its value is not on the edge of
the search grid (then it is reported "at the bound" and not named).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from diagnosis.cause import Cause
from diagnosis.noise_floor import block_bootstrap
from diagnosis.replay import ReplayResult, Window, replay
from flightlog.schema import FlightLog
from vehicle_sim import SimConfig

COMMAND_CAUSES: tuple[str, ...] = ("command_delay", "motor_lag")

# name -> (parameter, grid of values)
SEARCH_GRIDS: dict[str, tuple[str, np.ndarray]] = {
    "command_delay": ("delay_s", np.linspace(0.0, 1.2, 13)),
    "motor_lag": ("tau_s", np.geomspace(0.008, 0.5, 10)),
}


@dataclass(frozen=True)
class ReplayThresholds:
    """A command-path cause is named if it removes at least ``min_gain_fraction`` of the
    held-out replay mean squared velocity error left and at least ``min_gain_mps`` [m/s] of
    its RMSE."""

    min_gain_fraction: float = 0.5
    min_gain_mps: float = 0.003
    max_p_value: float = 0.01


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
    test: ReplayResult | None = None
    at_bound: bool = False


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
    held_out = replay(with_cause(config, name, best_value), logs, test)
    test_rmse = held_out.rmse_mps()
    at_bound = bool(best_value >= grid[-1] * (1.0 - 1e-3))
    progress(f"  {name}: {param} = {best_value:.4g}, held-out replay RMSE {test_rmse:.4f} m/s")
    return CommandFit(name, param, best_value, best_score, test_rmse, held_out, at_bound)


def _row_sq(result: ReplayResult) -> np.ndarray:
    err = result.sim_vel_ned_mps - result.meas_vel_ned_mps
    return np.sum(err * err, axis=1)


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
    noise_mse_mps2: float = 0.0,
) -> tuple[ReplayResult, list[Cause], list[Cause]]:
    """Forward selection of command-path causes by held-out replay error; adds the accepted
    ones to ``effects``. ``noise_mse_mps2`` is the replay's noise floor (mean squared 3-D
    velocity noise of the log [m^2/s^2]). Returns the final held-out replay, accepted and
    rejected causes."""
    accepted: list[Cause] = []
    rejected: dict[str, Cause] = {}
    left = list(names)
    scale = max(baseline.rmse_mps() ** 2 - noise_mse_mps2, 1e-12)
    while left and search and current.rmse_mps() >= thresholds.min_gain_mps:
        fits = [fit_command_cause(n, config_now, logs, search, test, progress) for n in left]
        best = min(fits, key=lambda f: f.test_rmse_mps)
        before = current.rmse_mps()
        sigs = {}
        for f in fits:
            sig = block_bootstrap(_row_sq(current), _row_sq(f.test), current.window)
            sigs[f.name] = sig
            bound = " at the bound (search wider / the cause may be another)" if f.at_bound else ""
            rejected[f.name] = Cause(
                f.name,
                {f.param: f.value},
                float((before**2 - f.test_rmse_mps**2) / scale),
                float(max(0.0, 1.0 - (f.test_rmse_mps / before) ** 2)),
                f"held-out replay velocity RMSE {before:.4f} -> {f.test_rmse_mps:.4f} m/s"
                f" (p {sig.p_value:.3g}){bound}",
                sig.as_dict(),
                f.at_bound,
            )
        removed = before**2 - best.test_rmse_mps**2
        explainable = max(before**2 - noise_mse_mps2, 0.0)
        if (
            removed < thresholds.min_gain_fraction * explainable
            or before - best.test_rmse_mps < thresholds.min_gain_mps
            or sigs[best.name].p_value > thresholds.max_p_value
            or best.at_bound
        ):
            break
        accepted.append(rejected.pop(best.name))
        effects[best.name] = {best.param: best.value}
        config_now = config_now.with_effects({best.name: {best.param: best.value}})
        current = replay(config_now, logs, test)
        left.remove(best.name)
        progress(f"accepted {best.name}")
    return current, accepted, list(rejected.values())
