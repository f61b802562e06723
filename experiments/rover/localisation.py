"""A VT&R-like localisation error for the simulated trials ([Ostafew16] sections 4.1, 5.1).

VT&R localises by visual odometry against the taught experience: consecutive estimates are
nearly exact relative to each other ("accurate velocity estimates with respect to the ground",
[Ostafew16] section 4.1), while the absolute error wanders slowly (VO drift, corrected at each
matched vertex). So the error here is a slow wander per axis (std ``bias_std``, correlation
time ``bias_tau_s``) plus small white noise per frame (``white_std``).

The wander is a second-order Gauss-Markov process (white noise through two first-order lags of
time constant T = ``bias_tau_s`` / 2, so its autocorrelation sigma^2 (1 + |t| / T) e^(-|t| / T)
integrates to the same ``bias_tau_s`` a first-order process of that correlation time has): its
change over a short time t grows as t (a velocity error of std sigma / T), where a first-order
process's grows as sqrt(t). The VO that VT&R is built on errs "less than 4 cm/m" against GPS
([Stenning13], quoted by [Ostafew16] section 5.1): between two fixes d metres apart the relative
error stays under 0.04 d. At experiment 1's 0.4 m/s and 10 Hz (d = 4 cm per frame, 1.6 mm)
a first-order wander of 1 cm and 3 s moves 2.6 mm per axis per frame, 2.3 times the bound, and
exceeds it up to d of about 0.2 m; the second-order wander of the same size and correlation
time moves 0.67 mm per frame, about 0.6 of the bound at one frame and less beyond (tested:
under the bound at every d from 4 cm to 4 m). The wander's size and correlation time are not
pinned by any source at hand and are kept.
White noise alone at the absolute level would put std sqrt(2) white / dt on every velocity the
learner sees (0.07 m/s for 5 mm at 10 Hz, a fifth of the 0.4 m/s speed), which VT&R does not.

[Stenning13]: B. Stenning, C. McManus, T. Barfoot, "Planning using a network of reusable paths:
a physical embodiment of a rapidly exploring random tree", Journal of Field Robotics 30(6),
2013.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LocalisationErrorConfig:
    """Attributes:
    bias_std: std of the slowly varying error (x [m], y [m], heading [rad]).
    bias_tau_s: its correlation time (the integral of its autocorrelation over sigma^2) [s].
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
    """Draws the error (3,) added to the true pose at each control step of ``dt_s``.

    Per axis: u_{k+1} = a u_k + sqrt(1 - a^2) s_u n_k, b_{k+1} = a b_k + (1 - a) u_k with
    a = exp(-dt / T), T = bias_tau_s / 2; s_u = sigma (1 + a) / sqrt(1 + a^2) makes the
    stationary std of b sigma. The state starts stationary (cov(b, u) = a s_u^2 / (1 + a)).
    """

    def __init__(self, config: LocalisationErrorConfig, dt_s: float, rng: np.random.Generator):
        a = math.exp(-dt_s / (0.5 * config.bias_tau_s))
        self._a = a
        sigma = np.asarray(config.bias_std, dtype=float)
        self._s_u = sigma * (1.0 + a) / math.sqrt(1.0 + a * a)
        self._white = np.asarray(config.white_std, dtype=float)
        self._rng = rng
        n_u, n_b = rng.standard_normal(3), rng.standard_normal(3)
        # corr(b, u) = cov / (sigma s_u) = a s_u / ((1 + a) sigma) = a / sqrt(1 + a^2)
        rho = a / math.sqrt(1.0 + a * a)
        self._u = self._s_u * n_u
        self._bias = sigma * (rho * n_u + math.sqrt(1.0 - rho * rho) * n_b)

    def draw(self) -> np.ndarray:
        a = self._a
        self._bias = a * self._bias + (1.0 - a) * self._u
        drive = math.sqrt(1.0 - a * a) * self._s_u * self._rng.standard_normal(3)
        self._u = a * self._u + drive
        return self._bias + self._white * self._rng.standard_normal(3)
