"""A command-path cause's grid search never takes a diverged replay for the best one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from diagnosis import command_path
from diagnosis.command_path import grid_order, search_grid
from vehicle_sim import load_sim_config


def test_a_replay_that_diverged_scores_inf_and_the_least_finite_one_wins(monkeypatch) -> None:
    """replay_sse stood in for by a bowl over the delay grid whose value nearest the middle
    of the typical range (the first tried) diverges to NaN: that value scores inf, and the
    least finite value is where the bowl is lowest."""
    _, grid = search_grid("command_delay")
    first = int(grid_order("command_delay")[0])
    target = grid[(first + 2) % len(grid)]

    def bowl(config, _logs, _train, _stop_above):  # noqa: ANN001
        delay = dict(zip(config.effect_names, config.effects, strict=True))["command_delay"].delay_s
        return math.nan if delay == grid[first] else 1.0 + (delay - target) ** 2

    monkeypatch.setattr(command_path, "replay_sse", bowl)
    scores = command_path._grid_rmse("command_delay", load_sim_config("iris"), [], [])
    assert scores[first] == np.inf
    assert grid[int(np.argmin(scores))] == pytest.approx(target)
