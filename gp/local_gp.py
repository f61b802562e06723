"""Sliding local GP over experience bins ([Ostafew16], section 4.3): constant-time online learning.

Experiences (query a_k, observed disturbance g_k) are stored in bins keyed by path vertex i and
commanded-speed bin l = floor(speed / speed_bin_mps). A bin keeps its newest ``bin_capacity``
experiences (the oldest is discarded). A query at vertex i and speed bin l uses the experiences
of bins i - vertex_window .. i + vertex_window and l - speed_window .. l + speed_window, so a
prediction costs at most (2 vertex_window + 1)(2 speed_window + 1) bin_capacity points,
independent of path length and deployment time. Hyperparameters are fixed (found offline, e.g.
by ExactGP or SparseGP on earlier trials); with no experience the prediction is the prior
(mean 0).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gp.exact_gp import exact_posterior
from gp.kernels import SquaredExponentialARD
from gp.posterior import Posterior
from gp.validation import check_inputs


@dataclass(frozen=True)
class ExperienceBinsConfig:
    """Bin geometry and capacity ([Ostafew16]'s v_bin, c_bin, c_vertex, c_velocity).

    Attributes:
        speed_bin_mps: width of a commanded-speed bin [m/s].
        bin_capacity: experiences kept per bin (newest first out last).
        vertex_window: neighbouring path vertices used on each side.
        speed_window: neighbouring speed bins used on each side.
    """

    speed_bin_mps: float = 0.25
    bin_capacity: int = 20
    vertex_window: int = 2
    speed_window: int = 1

    def __post_init__(self) -> None:
        if not self.speed_bin_mps > 0:
            raise ValueError(f"speed_bin_mps must be > 0 m/s, got {self.speed_bin_mps}")
        if self.bin_capacity < 1 or self.vertex_window < 0 or self.speed_window < 0:
            raise ValueError(
                "bin_capacity must be >= 1 and the windows >= 0, got "
                f"{self.bin_capacity}, {self.vertex_window}, {self.speed_window}"
            )

    @property
    def max_local_points(self) -> int:
        """Upper bound on the local dataset size."""
        return (2 * self.vertex_window + 1) * (2 * self.speed_window + 1) * self.bin_capacity

    def speed_bin(self, speed_mps: float) -> int:
        return math.floor(speed_mps / self.speed_bin_mps)


class LocalGP:
    """Experience bins plus an exact GP with fixed hyperparameters on the local dataset.

    Args:
        kernels: one SE-ARD kernel per output (all with the same number of features d).
        noise_variances: (n_out,) observation noise variances, output units squared.
        config: bin geometry.
    """

    def __init__(
        self,
        kernels: Sequence[SquaredExponentialARD],
        noise_variances: Sequence[float],
        config: ExperienceBinsConfig = ExperienceBinsConfig(),  # noqa: B008 (frozen)
    ) -> None:
        if len(kernels) != len(noise_variances) or not kernels:
            raise ValueError("pass one kernel and one noise variance per output")
        if len({k.n_features for k in kernels}) != 1:
            raise ValueError("all kernels must have the same number of lengthscales")
        self.kernels = tuple(kernels)
        self.noise_variances = np.asarray(noise_variances, dtype=float)
        self.config = config
        self._bins: dict[tuple[int, int], deque[tuple[np.ndarray, np.ndarray]]] = {}

    @property
    def n_features(self) -> int:
        return self.kernels[0].n_features

    @property
    def n_outputs(self) -> int:
        return len(self.kernels)

    def __len__(self) -> int:
        return sum(len(b) for b in self._bins.values())

    def add(
        self, vertex: int, speed_mps: float, query: np.ndarray, disturbance: np.ndarray
    ) -> None:
        """Store one experience: query a_k (d,) and observed disturbance g_k (n_out,)."""
        a = check_inputs(np.reshape(query, (1, -1)), "query", self.n_features)[0]
        g = check_inputs(np.reshape(disturbance, (1, -1)), "disturbance", self.n_outputs)[0]
        key = (int(vertex), self.config.speed_bin(speed_mps))
        bin_ = self._bins.setdefault(key, deque(maxlen=self.config.bin_capacity))
        bin_.append((a, g))

    def stored(self) -> list[tuple[int, int, np.ndarray, np.ndarray]]:
        """Every experience as (vertex, speed bin, query (d,), disturbance (n_out,)), bins in
        key order and each bin oldest first: adding them in this order to an empty LocalGP of
        the same config (speed (bin + 0.5) * speed_bin_mps) rebuilds the same bins."""
        return [(v, l, a, g) for (v, l), b in sorted(self._bins.items()) for a, g in b]

    def local_data(self, vertex: int, speed_mps: float) -> tuple[np.ndarray, np.ndarray]:
        """Local dataset for a query: X (k, d), Y (k, n_out), k <= config.max_local_points."""
        c = self.config
        l0 = c.speed_bin(speed_mps)
        rows = [
            item
            for i in range(vertex - c.vertex_window, vertex + c.vertex_window + 1)
            for l in range(l0 - c.speed_window, l0 + c.speed_window + 1)
            for item in self._bins.get((i, l), ())
        ]
        if not rows:
            return np.zeros((0, self.n_features)), np.zeros((0, self.n_outputs))
        return np.array([a for a, _ in rows]), np.array([g for _, g in rows])

    def posterior(self, vertex: int, speed_mps: float) -> Posterior | None:
        """Cached-form posterior of the local GP, or None when there is no local experience."""
        X, Y = self.local_data(vertex, speed_mps)
        if X.shape[0] == 0:
            return None
        pairs = zip(self.kernels, self.noise_variances, strict=True)
        fits = [exact_posterior(X, Y[:, j], k, s2) for j, (k, s2) in enumerate(pairs)]
        return Posterior(
            support=np.stack([X] * self.n_outputs),
            lengthscales=np.stack([k.lengthscales for k in self.kernels]),
            variance=np.array([k.variance for k in self.kernels]),
            alpha=np.stack([a for a, _ in fits]),
            var_factor=np.stack([r for _, r in fits]),
            y_offset=np.zeros(self.n_outputs),
        )

    def predict(
        self, vertex: int, speed_mps: float, queries: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Disturbance mean and std (n, n_out) at queries (n, d), from the local experience."""
        A = check_inputs(queries, "queries", self.n_features)
        post = self.posterior(vertex, speed_mps)
        if post is None:
            prior_std = np.sqrt([k.variance for k in self.kernels])
            return np.zeros((A.shape[0], self.n_outputs)), np.tile(prior_std, (A.shape[0], 1))
        return post.predict(A)
