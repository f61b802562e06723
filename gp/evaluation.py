"""Held-out evaluation as in [Kulathunga23] (Table 2, Fig. 5).

Per axis, with residuals y [m/s^2], their time base dt [s] and the model's mean g [m/s^2]:
    nominal error   = RMSE(y * dt)         [m/s]  (the nominal model alone)
    augmented error = RMSE((y - g) * dt)   [m/s]  (nominal model + learned residual)
Held-out data are whole contiguous blocks of segments, so no test row has a training neighbour
one step away.
"""

from __future__ import annotations

import numpy as np

from gp.datasets import ResidualDataset
from gp.errors import DatasetError


def holdout_split(
    dataset: ResidualDataset, fraction: float, seed: int = 0, n_blocks: int = 10
) -> tuple[ResidualDataset, ResidualDataset]:
    """Split into (train, test) by contiguous blocks.

    Each segment is cut into blocks of about n_rows / n_blocks rows; blocks are drawn with the
    seed until the held-out share is closest to ``fraction``. At least one block stays on each
    side.
    """
    if not 0.0 < fraction < 1.0:
        raise DatasetError(f"holdout fraction must be in (0, 1), got {fraction}")
    block_len = max(1, dataset.n_rows // n_blocks)
    block_id = np.empty(dataset.n_rows, dtype=int)
    next_id = 0
    for seg in np.unique(dataset.segment):
        rows = np.flatnonzero(dataset.segment == seg)
        block_id[rows] = next_id + np.arange(rows.size) // block_len
        next_id = int(block_id[rows].max()) + 1
    if next_id < 2:
        raise DatasetError(
            f"only {dataset.n_rows} rows: too few to hold out a block; record more data"
        )
    order = np.random.default_rng(seed).permutation(next_id)
    counts = np.bincount(block_id, minlength=next_id)
    taken = np.cumsum(counts[order])
    n_test = int(np.clip(np.argmin(np.abs(taken - fraction * dataset.n_rows)) + 1, 1, next_id - 1))
    test = np.isin(block_id, order[:n_test])
    return dataset.subset(~test), dataset.subset(test)


def residual_rmse(dataset: ResidualDataset, mean: np.ndarray) -> dict[str, list[float]]:
    """Per-axis nominal and augmented velocity errors [m/s] for predicted means (n, 3)."""
    dt = dataset.dt_s[:, None]
    nominal = np.sqrt(np.mean((dataset.Y * dt) ** 2, axis=0))
    augmented = np.sqrt(np.mean(((dataset.Y - mean) * dt) ** 2, axis=0))
    return {"nominal_rmse_mps": nominal.tolist(), "augmented_rmse_mps": augmented.tolist()}
