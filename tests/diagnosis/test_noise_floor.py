"""The noise floor is read off the data, and the block bootstrap tells signal from noise."""

from __future__ import annotations

import numpy as np

from diagnosis.noise_floor import block_bootstrap, noise_sse_std_error, white_noise_std


def test_white_noise_std_recovers_the_noise_under_a_smooth_signal():
    rng = np.random.default_rng(3)
    sigma = rng.uniform(0.1, 0.6, 3)
    t = np.arange(0.0, 60.0, 0.02)
    smooth = np.column_stack([np.sin(0.7 * t), 3.0 * np.cos(0.3 * t), np.sign(np.sin(0.2 * t))])
    est = white_noise_std(smooth + rng.normal(size=(len(t), 3)) * sigma, np.zeros(len(t)))
    assert np.allclose(est, sigma, rtol=0.08), (est, sigma)


def test_block_bootstrap_is_significant_for_a_real_reduction_only():
    rng = np.random.default_rng(4)
    block = np.repeat(np.arange(30), 100)
    before = rng.chisquare(3, block.size)
    noise_only = rng.chisquare(3, block.size)
    real = before * 0.5
    assert block_bootstrap(before, real, block).p_value < 0.01
    sig = block_bootstrap(before, noise_only, block, seed=1)
    assert sig.p_value > 0.05 and sig.low < 0.0 < sig.high


def test_noise_floor_standard_error_matches_its_spread():
    """The floor's own uncertainty (used so that it cannot veto a small significant cause) is
    what repeated draws of white noise show."""
    rng = np.random.default_rng(8)
    sigma = rng.uniform(0.2, 0.7, 3)
    n = 1500
    floors = [n * np.sum(white_noise_std(rng.normal(size=(n, 3)) * sigma) ** 2) for _ in range(400)]
    predicted = noise_sse_std_error(sigma, n, n)
    assert 0.8 < np.std(floors) / predicted < 1.25, (np.std(floors), predicted)


def test_a_cause_acting_in_few_blocks_is_resampled_on_finer_ones():
    """Three 4 s blocks cannot make a bootstrap; the 1 s blocks inside them can."""
    rng = np.random.default_rng(9)
    t = np.arange(0.0, 120.0, 0.05)
    block, fine = np.floor(t / 4.0).astype(int), np.floor(t).astype(int)
    before = rng.chisquare(3, t.size) * 0.3
    acting = np.isin(block, (5, 13, 21))
    gain = np.where(acting, rng.normal(0.15, 0.3, t.size), 0.0)
    after = before - gain
    coarse = block_bootstrap(before, after, block)
    finer = block_bootstrap(before, after, block, fine_block=fine)
    assert coarse.n_blocks == 3 and finer.n_blocks == 12
    assert finer.p_value < 0.01
    noise_only = np.where(acting, rng.normal(0.0, 0.3, t.size), 0.0)
    assert block_bootstrap(before, before - noise_only, block, fine_block=fine).p_value > 0.01


def test_white_noise_std_needs_three_rows_per_segment():
    """Fewer than 3 rows hold no second difference (zeros); 3 rows hold exactly one:
    x = (0, 1, 0) gives |0 - 2 + 0| = 2, so 1.4826 * 2 / sqrt(6)."""
    assert np.array_equal(white_noise_std(np.array([[0.0], [1.0]])), [0.0])
    np.testing.assert_allclose(
        white_noise_std(np.array([[0.0], [1.0], [0.0]])), [1.4826 * 2.0 / np.sqrt(6.0)]
    )


def test_white_noise_std_does_not_difference_across_segments():
    """Two flights at different constant levels have no noise; differenced across the jump
    between them, half the second differences would be the jump."""
    x = np.array([0.0, 0.0, 0.0, 5.0, 5.0, 5.0])
    assert np.array_equal(white_noise_std(x, np.array([0, 0, 0, 1, 1, 1])), [0.0])
    assert white_noise_std(x)[0] > 0.0  # one segment: the jump shows


def test_noise_floor_standard_error_counts_the_rows_it_was_estimated_from():
    """sigma = 2 estimated from 196 rows: sigma^2 = 4 known to 2.8 / sqrt(196) = 20 %, so a
    floor of 50 rows (50 * 4 = 200) is known to 40."""
    assert np.isclose(noise_sse_std_error(np.array([2.0]), 196, 50), 40.0)


def test_a_cause_acting_in_one_block_only_is_not_significant():
    before = np.ones(40)
    after = np.where(np.arange(40) < 10, 0.0, 1.0)  # helps in block 0 only
    sig = block_bootstrap(before, after, np.repeat(np.arange(4), 10))
    assert sig.n_blocks == 1 and sig.p_value == 1.0
    assert sig.reduction == sig.low == sig.high == 10.0


def test_a_cause_that_reduces_nothing_in_total_is_not_significant():
    """It changes every block's prediction, better on one row and as much worse on the next:
    every resample's reduction is zero, which is no help."""
    before = np.tile([1.0, 1.0], 8)
    after = np.tile([0.0, 2.0], 8)
    sig = block_bootstrap(before, after, np.repeat(np.arange(8), 2))
    assert sig.n_blocks == 8 and sig.p_value == 1.0


def test_a_cause_touching_exactly_min_blocks_keeps_the_coarse_blocks():
    before = np.ones(60)
    after = np.where(np.arange(60) < 36, 0.5, 1.0)  # acts in 6 of 10 blocks
    block, fine = np.repeat(np.arange(10), 6), np.arange(60)
    sig = block_bootstrap(before, after, block, fine_block=fine, min_blocks=6)
    assert sig.n_blocks == 6


def test_bootstrap_interval_is_the_95_percent_one():
    """With 200 independent blocks the resampled sum is near Gaussian: mean the total,
    std sqrt(n) times the blocks' (population) std, so the 95 % interval is +-1.96 of it."""
    rng = np.random.default_rng(11)
    per_block = rng.normal(0.5, 1.0, 200)
    sig = block_bootstrap(per_block, np.zeros(200), np.arange(200))
    half = 1.96 * np.sqrt(200) * np.std(per_block)
    assert np.isclose(sig.high - sig.low, 2.0 * half, rtol=0.08), (sig.low, sig.high, half)
