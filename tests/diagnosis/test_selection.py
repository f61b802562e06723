"""Forward selection on held-out blocks, on arrays with known causes."""

from __future__ import annotations

import numpy as np

from diagnosis.candidates import FORCE_CAUSES
from diagnosis.selection import select_causes, train_test_masks
from tests.diagnosis.test_force_math import BATTERY, synthetic, with_residual


def test_blocks_alternate_between_training_and_held_out():
    data = synthetic(n=400)
    train, test = train_test_masks(data, block_s=2.0)
    assert not np.any(train & test) and np.all(train | test)
    assert abs(train.sum() - test.sum()) <= 40
    flips = np.flatnonzero(np.diff(test.astype(int)))
    assert len(flips) == 9


def test_two_causes_are_selected_in_order_of_strength():
    truth = {"payload": {"mass_ratio": 1.4}, "body_drag": {"c_n_per_mps2": (0.03, 0.03, 0.05)}}
    data = with_residual(synthetic(n=1200), truth, noise_n=0.05)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ("payload", "body_drag")
    assert abs(result.effects["payload"]["mass_ratio"] - 1.4) < 0.01


def test_noise_alone_names_nothing():
    data = with_residual(synthetic(n=1200), {}, noise_n=0.3)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ()
    assert result.remaining_rms_n() > 0.25


def test_slowly_wandering_disturbance_does_not_generalise():
    data = synthetic(n=2400)
    rng = np.random.default_rng(5)
    walk = np.cumsum(rng.normal(0.0, 0.05, (data.n_rows, 3)), axis=0)
    walk -= walk.mean(axis=0)
    data = type(data)(**{**data.__dict__, "resid_ned_n": walk})
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ()
