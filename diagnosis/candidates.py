"""One small candidate model per airframe effect of the vocabulary, fitted to the force residual.

A candidate maps a parameter vector ``theta`` onto effect parameters (``{name: {param: value}}``)
that are merged over the effects the config already has; its fit minimises the squared force
residual left over by the merged effects (:mod:`.force_model`) with bounded least squares
(scipy ``least_squares``; the drag, payload and battery candidates are linear in ``theta`` and
converge in a few iterations). Which parameters are searched, within which bounds and from
which start, each effect class says in its parameter specs (``ParamSpec.search``). ``wind`` is a
steady horizontal wind; it acts through drag (``ACTS_THROUGH``): if the config has none, the
wind candidate fits its ``FIT_WITH`` effect, rotor drag, jointly. Causes already
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
from vehicle_sim.effects import EFFECT_CLASSES, ParamSpec, effects_with_role
from vehicle_sim.effects.base import Search

FORCE_CAUSES: tuple[str, ...] = effects_with_role("force")


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
    """The candidate for cause ``name`` given the effects already in the config: the searched
    parameters of the effect's specs (``ParamSpec.search``), and those of its ``FIT_WITH``
    effect when none of the effects it acts through is in the config."""
    cls = EFFECT_CLASSES.get(name)
    if cls is None or cls.ROLE != "force":
        raise ValueError(f"no force candidate {name!r}; force causes are {FORCE_CAUSES}")
    flat = _searched(cls, base)
    if cls.FIT_WITH is not None and not set(cls.ACTS_THROUGH) & set(base):
        flat += _searched(EFFECT_CLASSES[cls.FIT_WITH], {})
    x0 = np.concatenate([p.x0 for p in flat])
    lower = np.concatenate([p.lower for p in flat])
    upper = np.concatenate([p.upper for p in flat])
    sizes = np.cumsum([0, *(len(p.x0) for p in flat)])

    def to_effects(theta: np.ndarray) -> dict[str, dict[str, object]]:
        out: dict[str, dict[str, object]] = {}
        for p, a, b in zip(flat, sizes[:-1], sizes[1:], strict=True):
            out.setdefault(p.effect, {})[p.spec.name] = p.value(theta[a:b])
        return out

    return Candidate(name, x0, lower, upper, to_effects)


@dataclass(frozen=True)
class _SearchedParam:
    """One searched parameter of an effect: its spec and search, and the start of its free
    components (shape (free,))."""

    effect: str
    spec: ParamSpec
    search: Search
    x0: np.ndarray

    @property
    def lower(self) -> np.ndarray:
        return np.full(len(self.x0), self.search.lo)

    @property
    def upper(self) -> np.ndarray:
        return np.full(len(self.x0), self.search.hi)

    def value(self, theta: np.ndarray) -> float | tuple[float, ...]:
        """The parameter value for its slice of theta (unsearched components 0)."""
        if self.spec.size == 1:
            return float(theta[0])
        return (*_tup(theta), *(0.0,) * (self.spec.size - len(theta)))


def _searched(cls: type, base: EffectParams) -> list[_SearchedParam]:
    out = []
    for spec in cls.PARAMS:
        s = spec.search
        if s is None:
            continue
        free = spec.size if s.free is None else s.free
        start = base.get(cls.name, {}).get(spec.name, s.start) if s.warm else s.start
        x0 = np.broadcast_to(np.asarray(start, float), (spec.size,))[:free].copy()
        out.append(_SearchedParam(cls.name, spec, s, x0))
    return out


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
