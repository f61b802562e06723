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
