"""A ranked cause as report.json lists it, and effect parameters flattened for it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Cause:
    """One ranked cause, as in report.json (params flattened to floats).

    ``statistic`` is the significance test of its held-out improvement (diagnosis/2);
    ``at_bound`` marks a fit on its search bound, which is never named. ``unpinned``: parameters
    the log does not pin (name -> 95 % interval [low, high]): their value is the best estimate,
    kept in the extended config, but not a claim (e.g. ``flight_control``'s vertical I on a log
    with noisy thrust telemetry).
    """

    name: str
    params: dict[str, float]
    explained_fraction: float
    confidence: float
    evidence: str
    statistic: dict[str, object] | None = None
    at_bound: bool = False
    unpinned: dict[str, tuple[float, float]] = field(default_factory=dict)


def flatten_params(params: dict[str, object]) -> dict[str, float]:
    """Effect parameters as name -> float; vectors get an axis suffix (n/e/d for a parameter
    whose name says it is NED, ``vel_ned_mps``; x/y/z body axes otherwise)."""
    out: dict[str, float] = {}
    for key, value in params.items():
        if isinstance(value, (tuple, list, np.ndarray)):
            axes = "ned" if "_ned_" in f"{key}_" else "xyz"
            for axis, v in zip(axes, value, strict=True):
                out[f"{key}_{axis}"] = float(v)
        else:
            out[key] = float(value)
    return out


def explained_fraction(removed: float, total: float, noise: float, least: float) -> float:
    """What share a cause explains: ``removed`` of the explainable part ``total - noise`` (the
    held-out squared error above the noise floor, in the units of ``total``), clipped to
    [-1, 1]; when that part is not above ``least``, nothing stands above the floor and the
    share is of the whole ``total`` (a share of a vanishing part read 10^6 % on a real log)."""
    explainable = total - noise
    scale = explainable if explainable > least else total
    return float(np.clip(removed / scale, -1.0, 1.0)) if scale > 0.0 else 0.0
