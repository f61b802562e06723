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


def test_a_ground_effect_confined_to_short_low_holds_is_named():
    """Issue 18: a thrust gain acting only in a tenth of the rows (short holds at 5-12 cm) has a
    small RMS over the whole flight; counted over the rows it acts on it is clearly there."""
    rng = np.random.default_rng(11)
    n = 2400
    alt = np.full(n, 2.0)
    for start in np.linspace(100, n - 200, 10).astype(int):
        alt[start : start + 24] = rng.uniform(0.05, 0.12, 24)
    truth = {"ground_effect": {"max_gain": 0.1, "rotor_radius_m": 0.13, "rotor_height_m": 0.1}}
    data = with_residual(synthetic(n=n, alt_m=alt), truth, noise_n=0.2)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ("ground_effect",)
    clean = with_residual(synthetic(n=n, alt_m=alt), {}, noise_n=0.2)
    assert select_causes(clean, {}, BATTERY, FORCE_CAUSES).accepted == ()


def test_explained_fractions_stay_shares_when_the_noise_floor_swamps_the_residual():
    """Noise alone at 1 N: the estimated floor lies above the held-out residual, so nothing is
    explainable; a candidate's explained fraction is then its share of the whole held-out
    residual (a few tenths of a percent), not of a vanishing explainable part (128 % and
    -113 % here; 996185 % on a real EKF-failure log)."""
    data = with_residual(synthetic(n=1200), {}, noise_n=1.0)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.baseline_sse_n2 < result.noise_sse_n2
    assert result.accepted == ()
    assert all(abs(s.explained_fraction) < 0.02 for s in result.scores), result.scores


def test_an_explained_fraction_is_of_the_part_above_the_floor_else_of_the_whole():
    """The rule both the force and the replay path use: a share of the explainable part, at
    most all of it; of the whole error when nothing stands above the floor (a replay whose
    error is within its noise floor had divided by 1e-12 m^2/s^2)."""
    from diagnosis.cause import explained_fraction

    assert explained_fraction(2.0, total=10.0, noise=6.0, least=0.1) == 0.5
    assert explained_fraction(6.0, total=10.0, noise=6.0, least=0.1) == 1.0
    assert explained_fraction(-9.0, total=10.0, noise=6.0, least=0.1) == -1.0
    assert explained_fraction(0.5, total=10.0, noise=10.5, least=0.1) == 0.05
    assert explained_fraction(0.5, total=10.0, noise=9.95, least=0.1) == 0.05
    assert explained_fraction(0.5, total=0.0, noise=0.0, least=0.0) == 0.0
