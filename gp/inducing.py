"""Inducing-point selection: where a sparse GP places its m support points.

Strategies:
    low_speed: [Kulathunga23]. Points are denser where the vehicle flies slowly, because a planner
        in clutter flies mostly there. The target density is the optimal-quantiser density of
        the speed-weighted data distribution, q(z) ~ (p(z) w(|v(z)|))^(d / (d + 2)), with the
        Cauchy weight w(s) = 1 / (1 + (s / speed_scale_mps)^2) that halves at speed_scale_mps.
        In 1-D the points are the (i + 1/2)/m quantiles of q. In d >= 2, k-means with sample
        weights w^((d + 2) / d) places them (weighted k-means centroids have density
        ~ (p w')^(d / (d + 2)), so the speed dependence is w as in 1-D).
    cluster: Torrente et al.'s data-driven MPC. In 1-D, the medians of the data in m
        equal-width histogram bins over the data range (if bins are empty, the most populated
        groups are split at their medians until there are m); in d >= 2, k-means centroids.
    random: m distinct training rows drawn with the seed.
Each strategy may be followed by optimising the positions on the SGPR bound
(``optimize_positions``, done by the sparse GP).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gp.errors import GPInputError

STRATEGIES: tuple[str, ...] = ("low_speed", "cluster", "random")


@dataclass(frozen=True)
class InducingConfig:
    """How to choose inducing points.

    Attributes:
        strategy: one of ``STRATEGIES``.
        m: number of inducing points ([Kulathunga23] uses 30).
        speed_columns: input columns holding velocity components [m/s] whose norm is the speed
            used by ``low_speed``; None uses all columns.
        speed_scale_mps: speed at which the ``low_speed`` weight has halved [m/s].
        optimize_positions: refine the positions by maximising the SGPR bound.
    """

    strategy: str = "low_speed"
    m: int = 30
    speed_columns: tuple[int, ...] | None = None
    speed_scale_mps: float = 1.0
    optimize_positions: bool = False

    def __post_init__(self) -> None:
        if self.strategy not in STRATEGIES:
            valid = ", ".join(STRATEGIES)
            raise ValueError(f"unknown inducing strategy {self.strategy!r}; choose one of {valid}")
        if not (isinstance(self.m, int | np.integer) and self.m >= 1):
            raise ValueError(f"m must be a positive integer count of inducing points, got {self.m}")
        if not self.speed_scale_mps > 0:
            raise ValueError(f"speed_scale_mps must be > 0 m/s, got {self.speed_scale_mps}")


def select_inducing_points(X: np.ndarray, config: InducingConfig, seed: int = 0) -> np.ndarray:
    """Inducing points for inputs X (n, d) -> Z (m, d), deterministic for a given seed."""
    n_distinct = np.unique(X, axis=0).shape[0]
    if n_distinct < config.m:
        raise GPInputError(
            f"{config.m} inducing points requested but the inputs have only {n_distinct} "
            "distinct rows; lower m or add data"
        )
    rng = np.random.default_rng(seed)
    if config.strategy == "random":
        rows = np.unique(X, axis=0)
        return rows[np.sort(rng.choice(rows.shape[0], config.m, replace=False))]
    if config.strategy == "cluster":
        if X.shape[1] == 1:
            return histogram_medians(X[:, 0], config.m)[:, None]
        return _kmeans(X, config.m, None, seed)
    weights = low_speed_weights(X, config.speed_columns, config.speed_scale_mps)
    if X.shape[1] == 1:
        return weighted_quantizer_points(X[:, 0], weights, config.m)[:, None]
    d = X.shape[1]
    return _kmeans(X, config.m, weights ** ((d + 2) / d), seed)


def low_speed_weights(
    X: np.ndarray, speed_columns: tuple[int, ...] | None, speed_scale_mps: float
) -> np.ndarray:
    """w = 1 / (1 + (|v| / speed_scale_mps)^2) per row, (n,), from the speed columns."""
    cols = list(speed_columns) if speed_columns is not None else list(range(X.shape[1]))
    if any(not 0 <= c < X.shape[1] for c in cols):
        raise GPInputError(
            f"speed_columns {tuple(cols)} out of range for {X.shape[1]} input features"
        )
    speed = np.linalg.norm(X[:, cols], axis=1)
    return 1.0 / (1.0 + (speed / speed_scale_mps) ** 2)


def weighted_quantizer_points(x: np.ndarray, weights: np.ndarray, m: int) -> np.ndarray:
    """1-D points at the (i + 1/2)/m quantiles of q ~ (p w)^(1/3), (m,), sorted.

    p is a histogram density of x (10 m bins at least 100); w is interpolated per bin as the
    mean weight of its samples.
    """
    lo, hi = float(x.min()), float(x.max())
    n_bins = max(10 * m, 100)
    edges = np.linspace(lo, hi, n_bins + 1)
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, n_bins - 1)
    mass = np.bincount(idx, weights=weights, minlength=n_bins)
    q = np.cbrt(mass)
    cdf = np.concatenate([[0.0], np.cumsum(q)])
    cdf /= cdf[-1]
    return np.interp((np.arange(m) + 0.5) / m, cdf, edges)


def histogram_medians(x: np.ndarray, m: int) -> np.ndarray:
    """Medians of x in m equal-width bins over its range, sorted, exactly m of them.

    If fewer than m bins hold data, the most populated group is split at its median (into its
    lower and upper halves) until there are m groups.
    """
    lo, hi = float(x.min()), float(x.max())
    edges = np.linspace(lo, hi, m + 1)
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, m - 1)
    groups = [np.sort(x[idx == b]) for b in range(m) if np.any(idx == b)]
    while len(groups) < m:
        big = max(range(len(groups)), key=lambda i: groups[i].size)
        g = groups.pop(big)
        groups[big:big] = [g[: g.size // 2], g[g.size // 2 :]]
    return np.array([np.median(g) for g in groups])


def _kmeans(X: np.ndarray, m: int, weights: np.ndarray | None, seed: int) -> np.ndarray:
    # scikit-learn (2.5 s to load) only here: a command line lists STRATEGIES without it
    from sklearn.cluster import KMeans

    km = KMeans(n_clusters=m, n_init=3, random_state=seed)
    km.fit(X, sample_weight=weights)
    return km.cluster_centers_
