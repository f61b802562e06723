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
