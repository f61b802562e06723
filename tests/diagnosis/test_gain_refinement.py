"""flight_control's gains refined by replay (Gauss-Newton on the replay's velocity errors): it
finds gains the regression missed, and a replay that diverges neither stops it nor is chosen."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from diagnosis import command_path
from diagnosis.command_path import _refine_gains
from diagnosis.diagnosis import DiagnosisConfig
from diagnosis.fly_schedule import fly_schedule
from diagnosis.replay import replay, windows
from experiments.hidden_effects import schedule
from vehicle_sim import load_sim_config

# the config's: 1.8, 0.4 and 4.0 (PX4's bounds for the horizontal P: 1.2-5)
TRUTH = {"MPC_XY_VEL_P_ACC": 1.35, "MPC_XY_VEL_I_ACC": 1.7, "MPC_Z_VEL_P_ACC": 5.5}


@pytest.fixture(scope="module")
def flight():
    """(log, training windows of the command-path search): the excitation flight flown with
    other velocity-loop gains than the config's."""
    log = fly_schedule(load_sim_config("iris"), schedule(), seed=5, params=TRUTH)
    config = DiagnosisConfig()
    block = config.selection.block_s
    train = [
        w
        for w in windows([log], config.window_s)
        if int(w.t_anchor_s // block) % 2 == 0 and w.t_anchor_s < config.search_log_s
    ]
    return log, train


class DivergingAbove:
    """The replay, with every simulated velocity NaN when the config's horizontal P exceeds
    ``p_gain`` (a replay that blew up); counts those."""

    def __init__(self, p_gain: float) -> None:
        self.p_gain = p_gain
        self.diverged = 0

    def __call__(self, config, logs, wins):
        result = replay(config, logs, wins)
        if dict(config.px4_params)["MPC_XY_VEL_P_ACC"] > self.p_gain:
            self.diverged += 1
            nan = np.full_like(result.sim_vel_ned_mps, np.nan)
            return dataclasses.replace(result, sim_vel_ned_mps=nan)
        return result


def test_refinement_finds_the_gains_from_a_start_a_quarter_off(flight):
    log, train = flight
    start = {k: v * f for (k, v), f in zip(TRUTH.items(), (1.25, 0.75, 0.75), strict=True)}
    refined = _refine_gains(load_sim_config("iris"), [log], train, start)
    for name, value in TRUTH.items():
        assert refined[name] == pytest.approx(value, rel=0.03), refined


def test_a_diverging_replay_is_stepped_away_from(flight, monkeypatch):
    """The true P lies where the replay diverges: the refinement heads there, is refused and
    stays below."""
    log, train = flight
    diverging = DivergingAbove(1.3)
    monkeypatch.setattr(command_path, "replay", diverging)
    start = {"MPC_XY_VEL_P_ACC": 1.22, "MPC_XY_VEL_I_ACC": 1.4}
    refined = _refine_gains(load_sim_config("iris"), [log], train, start)
    assert diverging.diverged > 0  # it did try a P that diverges
    assert all(np.isfinite(v) for v in refined.values()), refined
    assert start["MPC_XY_VEL_P_ACC"] < refined["MPC_XY_VEL_P_ACC"] <= 1.3


def test_a_start_whose_replay_diverges_is_kept(flight, monkeypatch):
    log, train = flight
    monkeypatch.setattr(command_path, "replay", DivergingAbove(1.5))
    start = {"MPC_XY_VEL_P_ACC": 1.7, "MPC_XY_VEL_I_ACC": 1.4}
    assert _refine_gains(load_sim_config("iris"), [log], train, start) == start


def test_a_diverging_jacobian_step_leaves_the_gains_finite(flight, monkeypatch):
    """Every replay with a larger horizontal P than the start's diverges, the forward step of
    the first Jacobian among them: the gains come back finite, with no larger P."""
    log, train = flight
    start = {"MPC_XY_VEL_P_ACC": 1.3, "MPC_XY_VEL_I_ACC": 1.4}
    diverging = DivergingAbove(start["MPC_XY_VEL_P_ACC"] * (1.0 + 1e-5))  # the start's is not
    monkeypatch.setattr(command_path, "replay", diverging)
    refined = _refine_gains(load_sim_config("iris"), [log], train, start)
    assert diverging.diverged > 0
    assert refined["MPC_XY_VEL_P_ACC"] <= diverging.p_gain
    assert all(np.isfinite(v) for v in refined.values()), refined
