"""A VT&R-like localisation error for the simulated trials ([Ostafew16] sections 4.1, 5.1).

VT&R localises by visual odometry against the taught experience: consecutive estimates are
nearly exact relative to each other ("accurate velocity estimates with respect to the ground",
[Ostafew16] section 4.1), while the absolute error wanders slowly (VO drift, corrected at each
matched vertex). So the error here is a first-order Gauss-Markov process per axis (std
``bias_std``, correlation time ``bias_tau_s``) plus small white noise per frame (``white_std``).
White noise alone at the absolute level would put std sqrt(2) white / dt on every velocity the
learner sees (0.07 m/s for 5 mm at 10 Hz, a fifth of the 0.4 m/s speed), which VT&R does not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LocalisationErrorConfig:
    """Attributes:
    bias_std: std of the slowly varying error (x [m], y [m], heading [rad]).
    bias_tau_s: its correlation time [s].
    white_std: std of the per-frame noise (x [m], y [m], heading [rad]).
    """

    bias_std: tuple[float, float, float] = (0.01, 0.01, 0.005)
    bias_tau_s: float = 3.0
    white_std: tuple[float, float, float] = (0.001, 0.001, 0.001)

    def __post_init__(self) -> None:
        if not self.bias_tau_s > 0:
            raise ValueError(f"bias_tau_s must be > 0 s, got {self.bias_tau_s}")
        if min(self.bias_std) < 0 or min(self.white_std) < 0:
            raise ValueError("localisation error stds must be >= 0")


class LocalisationError:
    """Draws the error (3,) added to the true pose at each control step of ``dt_s``."""

    def __init__(self, config: LocalisationErrorConfig, dt_s: float, rng: np.random.Generator):
        self._a = math.exp(-dt_s / config.bias_tau_s)
        self._bias_std = np.asarray(config.bias_std, dtype=float)
        self._white = np.asarray(config.white_std, dtype=float)
        self._rng = rng
        self._bias = self._bias_std * rng.standard_normal(3)

    def draw(self) -> np.ndarray:
        drive = math.sqrt(1.0 - self._a**2) * self._bias_std * self._rng.standard_normal(3)
        self._bias = self._a * self._bias + drive
        return self._bias + self._white * self._rng.standard_normal(3)
