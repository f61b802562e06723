"""The log's own noise floor, and whether a held-out improvement stands out from it.

Noise floor. A measured signal is a smooth part (the vehicle's motion, bandwidth a few Hz)
plus white sensor noise. The second difference x[i+1] - 2 x[i] + x[i-1] nearly cancels the smooth
part and has variance 6 sigma^2 for white noise of std sigma; the median absolute value
(times 1.4826 for a Gaussian) keeps the estimate robust to the few rows where the motion itself
jumps (setpoint steps, touch-downs). What no model of the vehicle can explain is that white part.

Significance. Held-out rows are not independent: filters, a drifting IMU bias and gusts correlate
neighbouring rows, so a likelihood-ratio test on rows would count one wiggle many times and
overstate significance. The held-out blocks (4 s apart from each other by a training block) are
close to independent, so we resample them: a block bootstrap [Efron93] of the summed reduction
in squared error gives a one-sided p-value (the share of resamples where the cause does not
help) and a 95 % interval of the reduction, with no assumption on the error distribution. Only
the blocks where the cause changes the prediction are resampled: a ground effect acts in the few
blocks with ground holds, and resamples that happen to draw none of them say nothing about it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAD_TO_STD = 1.4826  # std / median absolute deviation for a Gaussian
# Relative standard error of the variance estimate sigma^2 of :func:`white_noise_std`, times
# sqrt(rows): 2.8 / sqrt(n) (measured by Monte Carlo on white Gaussian noise, n = 500-8000; the
# MAD is a third as efficient as the sample variance and neighbouring second differences are
# correlated). On a 100 s log at 20 Hz the floor is known to about 6 % per axis: a residual that
# stands only that much above it is not evidence of anything left to explain.
NOISE_VAR_REL_SE_SQRT_N = 2.8
BOOTSTRAP_SAMPLES = 2000
MIN_BOOTSTRAP_BLOCKS = 6  # fewer touched blocks: resample finer ones (:func:`block_bootstrap`)


def white_noise_std(x: np.ndarray, segment: np.ndarray | None = None) -> np.ndarray:
    """(k,) std of the white part of each column of ``x`` (n, k), per contiguous ``segment``.

    Differences never straddle two segments. Zeros with fewer than 3 rows.
    """
    x = np.asarray(x, float).reshape(len(x), -1)
    seg = np.zeros(len(x), int) if segment is None else np.asarray(segment)
    parts = []
    for s in np.unique(seg):
        rows = x[seg == s]
        if len(rows) >= 3:
            parts.append(rows[2:] - 2.0 * rows[1:-1] + rows[:-2])
    if not parts:
        return np.zeros(x.shape[1])
    d2 = np.vstack(parts)
    return MAD_TO_STD * np.median(np.abs(d2), axis=0) / np.sqrt(6.0)


def noise_sse_std_error(noise_std: np.ndarray, n_estimated: int, n_rows: int) -> float:
    """Standard error of the squared-error floor ``n_rows * sum(noise_std**2)`` [units^2] when
    ``noise_std`` (k,) was estimated by :func:`white_noise_std` from ``n_estimated`` rows
    (the axes' estimates taken as independent)."""
    var = np.asarray(noise_std, float) ** 2
    rel = NOISE_VAR_REL_SE_SQRT_N / np.sqrt(max(n_estimated, 1))
    return float(n_rows * rel * np.sqrt(np.sum(var * var)))


@dataclass(frozen=True)
class Significance:
    """A held-out improvement judged by block bootstrap.

    Attributes:
        reduction: summed reduction of the squared error over the held-out blocks.
        low, high: 95 % bootstrap interval of that reduction.
        p_value: one-sided: the share of resamples in which the reduction is <= 0.
        n_blocks: held-out blocks resampled (those where the cause changes the prediction).
    """

    reduction: float
    low: float
    high: float
    p_value: float
    n_blocks: int

    def as_dict(self) -> dict[str, float | int | str]:
        return {
            "test": "block bootstrap of the held-out squared-error reduction",
            "reduction": self.reduction,
            "interval_95": [self.low, self.high],
            "p_value": self.p_value,
            "n_blocks": self.n_blocks,
        }


def block_bootstrap(
    before_sq: np.ndarray,
    after_sq: np.ndarray,
    block: np.ndarray,
    seed: int = 0,
    fine_block: np.ndarray | None = None,
    min_blocks: int = MIN_BOOTSTRAP_BLOCKS,
) -> Significance:
    """Significance of the reduction ``sum(before_sq - after_sq)`` over rows grouped by ``block``.

    A bootstrap over two or three blocks cannot tell anything: when the cause acts in fewer than
    ``min_blocks`` of them (a ground effect in a few seconds of low holds), the rows are grouped
    by ``fine_block`` instead (shorter blocks, still long against the white noise's correlation
    of one row; a drifting IMU bias is near constant over a few such blocks and shifts them
    alike, which the cause's least force, counted over the rows it acts on, guards against).

    Args:
        before_sq, after_sq: (n,) squared error per held-out row without and with the cause.
        block: (n,) block id of each row.
        seed: resampling seed (deterministic result).
        fine_block: (n,) shorter block ids, used when the cause touches too few ``block``s.
        min_blocks: least number of touched blocks before ``fine_block`` is used.
    """
    sig = _bootstrap(before_sq, after_sq, block, seed)
    if fine_block is not None and sig.n_blocks < min_blocks:
        return _bootstrap(before_sq, after_sq, fine_block, seed)
    return sig


def _bootstrap(
    before_sq: np.ndarray, after_sq: np.ndarray, block: np.ndarray, seed: int
) -> Significance:
    _, inverse = np.unique(np.asarray(block), return_inverse=True)
    diff = np.asarray(before_sq) - np.asarray(after_sq)
    per_block = np.bincount(inverse, weights=diff)
    touched = np.bincount(inverse, weights=np.abs(diff))
    per_block = per_block[touched > 1e-12 * max(float(touched.max(initial=0.0)), 1e-300)]
    total = float(per_block.sum())
    if len(per_block) < 2:  # one block (or none) the cause acts on: no evidence of a pattern
        return Significance(total, total, total, 1.0, len(per_block))
    ids = per_block
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, len(ids), size=(BOOTSTRAP_SAMPLES, len(ids)))
    sums = per_block[picks].sum(axis=1)
    low, high = np.quantile(sums, [0.025, 0.975])
    p = float((np.count_nonzero(sums <= 0.0) + 1) / (BOOTSTRAP_SAMPLES + 1))
    return Significance(total, float(low), float(high), p, len(ids))
