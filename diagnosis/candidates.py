"""One small candidate model per airframe effect of the vocabulary, fitted to the force residual.

A candidate maps a parameter vector ``theta`` onto effect parameters (``{name: {param: value}}``)
that are merged over the effects the config already has; its fit minimises the squared force
residual left over by the merged effects (:mod:`.force_model`) with bounded least squares
(scipy ``least_squares``; the drag, payload and battery candidates are linear in ``theta`` and
converge in a few iterations). ``wind`` is a steady horizontal wind; it needs drag to act
through: if the config has none, the wind candidate fits rotor drag jointly. Causes already
accepted are re-fitted jointly with each new candidate, so an early estimate that absorbed part
of a later cause is corrected.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from diagnosis.force_model import BatteryModel, EffectParams, predicted_residual
from diagnosis.forces import ForceData

FORCE_CAUSES: tuple[str, ...] = (
    "rotor_drag", "body_drag", "isotropic_drag", "wind", "payload", "battery_sag",
    "ground_effect",
)  # fmt: skip


@dataclass(frozen=True)
class Candidate:
    """A cause's parameterisation.

    Attributes:
        name: effect name from the vocabulary.
        x0, lower, upper: (p,) start and bounds of ``theta``.
        to_effects: theta -> effect parameters this cause adds or replaces.
    """

    name: str
    x0: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    to_effects: Callable[[np.ndarray], dict[str, dict[str, object]]]


@dataclass(frozen=True)
class CandidateFit:
    """A fitted candidate: its effects (merged over the base) and its training cost."""

    name: str
    effects: dict[str, dict[str, object]]
    train_sse_n2: float
    n_params: int
    at_bound: bool = False


def merge(base: EffectParams, extra: EffectParams) -> dict[str, dict[str, object]]:
    """``base`` with the effects of ``extra`` added or replaced, as plain dicts."""
    out = {k: dict(v) for k, v in base.items()}
    out.update({k: dict(v) for k, v in extra.items()})
    return out


def make_candidate(name: str, base: EffectParams) -> Candidate:
    """The candidate for cause ``name`` given the effects already in the config."""
    if name == "rotor_drag":
        k0 = base.get("rotor_drag", {}).get("k_n_per_mps", (0.3, 0.3, 0.1))
        return Candidate(
            name,
            np.array(k0, float),
            np.zeros(3),
            np.full(3, 10.0),
            lambda th: {"rotor_drag": {"k_n_per_mps": _tup(th)}},
        )
    if name == "body_drag":
        c0 = base.get("body_drag", {}).get("c_n_per_mps2", (0.02, 0.02, 0.04))
        return Candidate(
            name,
            np.array(c0, float),
            np.zeros(3),
            np.full(3, 5.0),
            lambda th: {"body_drag": {"c_n_per_mps2": _tup(th)}},
        )
    if name == "isotropic_drag":
        k0 = base.get("isotropic_drag", {}).get("k_n_per_mps2", 0.03)
        return Candidate(
            name,
            np.array([k0], float),
            np.zeros(1),
            np.full(1, 10.0),
            lambda th: {"isotropic_drag": {"k_n_per_mps2": float(th[0])}},
        )
    if name == "wind":
        if {"rotor_drag", "body_drag", "isotropic_drag"} & set(base):
            return Candidate(
                name,
                np.zeros(2),
                np.full(2, -30.0),
                np.full(2, 30.0),
                lambda th: {"wind": {"vel_ned_mps": (*_tup(th), 0.0)}},
            )
        return Candidate(
            name,
            np.array([0.0, 0.0, 0.3, 0.3, 0.1]),
            np.array([-30.0, -30.0, 0.0, 0.0, 0.0]),
            np.array([30.0] * 2 + [10.0] * 3),
            lambda th: {
                "wind": {"vel_ned_mps": (*_tup(th[:2]), 0.0)},
                "rotor_drag": {"k_n_per_mps": _tup(th[2:])},
            },
        )
    if name == "payload":
        return Candidate(
            name,
            np.array([1.0]),
            np.array([0.5]),
            np.array([1.8]),
            lambda th: {"payload": {"mass_ratio": float(th[0])}},
        )
    if name == "battery_sag":
        return Candidate(
            name,
            np.array([0.1]),
            np.array([0.0]),
            np.array([0.6]),
            lambda th: {"battery_sag": {"max_thrust_loss": float(th[0])}},
        )
    if name == "ground_effect":
        return Candidate(
            name,
            np.array([0.2, 0.15]),
            np.array([0.0, 0.03]),
            np.array([1.0, 0.5]),
            lambda th: {
                "ground_effect": {"max_gain": float(th[0]), "rotor_radius_m": float(th[1])}
            },
        )
    raise ValueError(f"no force candidate {name!r}; force causes are {FORCE_CAUSES}")


def fit_jointly(
    candidates: Sequence[Candidate], base: EffectParams, data: ForceData, battery: BatteryModel
) -> CandidateFit:
    """Fit ``candidates`` together on top of ``base`` to the force residual of ``data``; the
    fit is named after the last candidate (the one being tried)."""
    sizes = np.cumsum([0, *(len(c.x0) for c in candidates)])

    def effects_of(theta: np.ndarray) -> dict[str, dict[str, object]]:
        out = dict(base)
        for c, a, b in zip(candidates, sizes[:-1], sizes[1:], strict=True):
            out = merge(out, c.to_effects(theta[a:b]))
        return out

    def cost(theta: np.ndarray) -> np.ndarray:
        return (predicted_residual(effects_of(theta), data, battery) - data.resid_ned_n).ravel()

    lower = np.concatenate([c.lower for c in candidates])
    upper = np.concatenate([c.upper for c in candidates])
    x0 = np.clip(np.concatenate([c.x0 for c in candidates]), lower, upper)
    sol = least_squares(cost, x0, bounds=(lower, upper), x_scale="jac")
    own = slice(sizes[-2], sizes[-1])
    at_bound = on_bound(sol.x[own], lower[own], upper[own])
    return CandidateFit(
        candidates[-1].name, effects_of(sol.x), float(2.0 * sol.cost), len(x0), at_bound
    )


def on_bound(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray, rel: float = 1e-3) -> bool:
    """True if a parameter sits on its search bound: the upper one, or a lower one that is not
    the effect's natural zero (a drag of 0 is "no drag", a payload ratio of 0.5 is a limit)."""
    span = (upper - lower) * rel
    high = theta >= upper - span
    low = (theta <= lower + span) & (lower != 0.0)
    return bool(np.any(high | low))


def residual_sse(effects: EffectParams, data: ForceData, battery: BatteryModel) -> float:
    """Sum of squared force residual [N^2] left over by ``effects`` on ``data``."""
    err = predicted_residual(effects, data, battery) - data.resid_ned_n
    return float(np.sum(err * err))


def _tup(theta: np.ndarray) -> tuple[float, ...]:
    return tuple(float(v) for v in theta)
