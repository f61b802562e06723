"""Choose causes by held-out error: forward selection over the force candidates.

Rows are cut into blocks of ``block_s`` seconds; even blocks train, odd blocks test. Starting
from the config's own effects, each round fits every remaining candidate on the training rows
and keeps the one that lowers the held-out squared residual most, if

- it removes at least ``min_gain_fraction`` of what is left *above the noise floor* (the white
  part of the residual, estimated from the data by :func:`.noise_floor.white_noise_std`: no
  model removes sensor noise, so it must not count in the denominator). The floor is itself an
  estimate, known to a few per cent (:func:`.noise_floor.noise_sse_std_error`); what stands less
  than ``floor_margin_se`` standard errors above it is not counted as explainable either, so on a
  noisy log a small, localised but significant effect (ground effect in a few seconds of low
  holds) is not vetoed by the floor's own uncertainty (issue 18),
- the removal is significant: block-bootstrap p-value below ``max_p_value``
  (:func:`.noise_floor.block_bootstrap`; why a bootstrap over blocks is explained there),
- and it explains at least ``min_force_fraction`` of the weight in RMS force over the rows it
  acts on (all rows for drag or a payload; the low holds for ground effect).

Otherwise selection stops: what does not generalise is not named.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import partial

import numpy as np

from diagnosis.candidates import Candidate, fit_jointly, make_candidate, residual_sse
from diagnosis.cause import explained_fraction
from diagnosis.force_model import BatteryModel, EffectParams, predicted_residual
from diagnosis.forces import GRAVITY_MPS2, ForceData
from diagnosis.noise_floor import (
    Significance,
    block_bootstrap,
    noise_sse_std_error,
    white_noise_std,
)


@dataclass(frozen=True)
class SelectionConfig:
    """Held-out split and acceptance thresholds.

    Attributes:
        block_s: length of the alternating train/test blocks [s].
        min_gain_fraction: least fraction of the remaining held-out squared residual a cause
            must remove to be named.
        min_force_fraction: least RMS force [fraction of the nominal weight] a cause must explain.
        max_fit_rows: training rows used by the fits at most (evenly spaced), to bound the time.
        max_p_value: largest block-bootstrap p-value of the held-out reduction to name a cause.
        floor_margin_se: standard errors of the noise-floor estimate added to the floor before
            the ``min_gain_fraction`` rule.
        fine_block_s: block length [s] the bootstrap resamples for a cause acting in only a few
            held-out blocks (:func:`.noise_floor.block_bootstrap`).
    """

    block_s: float = 4.0
    min_gain_fraction: float = 0.5
    min_force_fraction: float = 0.003
    max_fit_rows: int = 2000
    max_p_value: float = 0.01
    floor_margin_se: float = 2.0
    fine_block_s: float = 1.0


@dataclass(frozen=True)
class CauseScore:
    """How one candidate did when it was last tried.

    Attributes:
        name: cause name.
        effects: the fitted effects (base merged with this cause).
        explained_fraction: fraction of the baseline held-out squared residual it removes
            (on top of the causes accepted before it).
        step_gain_fraction: fraction of the then-remaining held-out squared residual it removes.
        before_rms_n, after_rms_n: held-out force residual RMS per component without and with
            it (on top of the causes accepted before it) [N].
        accepted: whether it was named.
        significance: block bootstrap of its held-out reduction (None if not computed).
        at_bound: a parameter of it sits on its search bound (then it is not named).
    """

    name: str
    effects: dict[str, dict[str, object]]
    explained_fraction: float
    step_gain_fraction: float
    before_rms_n: float
    after_rms_n: float
    accepted: bool
    significance: Significance | None = None
    at_bound: bool = False


@dataclass(frozen=True)
class ForceSelection:
    """Outcome of forward selection.

    Attributes:
        scores: accepted causes in order, then the rejected ones, best first.
        effects: the config's effects plus the accepted causes.
        baseline_sse_n2, final_sse_n2: held-out squared residual before and after.
        n_test: held-out rows.
        noise_std_n: (3,) std of the white part of the force residual per NED axis [N].
    """

    scores: tuple[CauseScore, ...]
    effects: dict[str, dict[str, object]]
    baseline_sse_n2: float
    final_sse_n2: float
    n_test: int
    noise_std_n: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def noise_sse_n2(self) -> float:
        """Held-out squared residual the noise floor accounts for [N^2]."""
        return float(self.n_test * sum(s * s for s in self.noise_std_n))

    def explained_of_explainable(self) -> float:
        """Fraction of the explainable held-out squared residual (above the noise floor) that
        the accepted causes remove, in [0, 1]; 1 when nothing stood above the floor."""
        explainable = self.baseline_sse_n2 - self.noise_sse_n2
        if explainable <= 0.0:
            return 1.0
        return float(np.clip((self.baseline_sse_n2 - self.final_sse_n2) / explainable, 0.0, 1.0))

    @property
    def accepted(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.scores if s.accepted)

    def remaining_rms_n(self) -> float:
        """RMS per component of the held-out force residual left over [N]."""
        return float(np.sqrt(self.final_sse_n2 / max(3 * self.n_test, 1)))


def train_test_masks(data: ForceData, block_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Boolean (n,) masks of training and held-out rows (alternating time blocks)."""
    block = np.floor(data.t_s / block_s).astype(int) + data.segment
    test = block % 2 == 1
    return ~test, test


def select_causes(
    data: ForceData,
    base: EffectParams,
    battery: BatteryModel,
    names: Sequence[str],
    config: SelectionConfig = SelectionConfig(),
    progress: Callable[[str], None] = lambda msg: None,
) -> ForceSelection:
    """Forward selection of force causes ``names`` on top of the config's effects ``base``."""
    train_mask, test_mask = train_test_masks(data, config.block_s)
    train_rows = np.flatnonzero(train_mask)
    stride = max(1, -(-len(train_rows) // config.max_fit_rows))
    train, test = data.take(train_rows[::stride]), data.take(test_mask)
    noise = white_noise_std(data.resid_ned_n, data.segment)
    noise_sse = test.n_rows * float(np.sum(noise * noise))
    noise_margin = config.floor_margin_se * noise_sse_std_error(noise, data.n_rows, test.n_rows)
    test_block = np.floor(test.t_s / config.block_s).astype(int) + 100_000 * test.segment
    fine_block = np.floor(test.t_s / config.fine_block_s).astype(int) + 1_000_000 * test.segment
    base = {k: dict(v) for k, v in base.items()}
    current = base
    current_sq = _row_sq(current, test, battery)
    baseline = float(current_sq.sum())
    remaining_sse = baseline
    least_sse = test.n_rows * 3 * (config.min_force_fraction * data.mass_kg * GRAVITY_MPS2) ** 2
    share = partial(explained_fraction, total=baseline, noise=noise_sse, least=least_sse)
    chosen: list[Candidate] = []
    accepted: list[CauseScore] = []
    last_try: dict[str, CauseScore] = {}
    left = list(names)
    while left:
        tried = []
        for name in left:
            fit = fit_jointly([*chosen, make_candidate(name, base)], base, train, battery)
            sse = residual_sse(fit.effects, test, battery)
            tried.append((sse, fit))
            after_sq = _row_sq(fit.effects, test, battery)
            sig = block_bootstrap(current_sq, after_sq, test_block, fine_block=fine_block)
            last_try[name] = _score(name, fit, share, remaining_sse, sse, test, False, sig)
            progress(
                f"  {name}: held-out force residual {_rms(sse, test):.3f} N (p {sig.p_value:.3g})"
            )
        best_sse, best = _simplest_of_best(tried, remaining_sse)
        removed = remaining_sse - best_sse
        explainable = max(remaining_sse - noise_sse - noise_margin, 0.0)
        sig = last_try[best.name].significance
        acting = _acting_rows(current, best.effects, test, battery)
        floor_sse = acting * 3 * (config.min_force_fraction * data.mass_kg * GRAVITY_MPS2) ** 2
        if (
            removed < config.min_gain_fraction * explainable
            or removed < floor_sse
            or sig is None
            or sig.p_value > config.max_p_value
            or best.at_bound
        ):
            break
        accepted.append(_score(best.name, best, share, remaining_sse, best_sse, test, True, sig))
        chosen.append(make_candidate(best.name, base))
        current = best.effects
        current_sq = _row_sq(current, test, battery)
        remaining_sse = best_sse
        left.remove(best.name)
        progress(f"accepted {best.name}")
    # Backward pass: a cause accepted early (the simplest of near-equals) may be made redundant
    # by a later one (isotropic_drag taken first for a body drag that body_drag then fits in
    # full). Drop an accepted cause whose removal, the others refitted, costs less than the
    # floor or is not significant (what the forward pass would not have accepted).
    for score in list(accepted):
        if len(chosen) < 2:
            break
        others = [c for c in chosen if c.name != score.name]
        fit = fit_jointly(others, base, train, battery)
        without_sq = _row_sq(fit.effects, test, battery)
        cost = float(without_sq.sum()) - remaining_sse
        acting = _acting_rows(fit.effects, current, test, battery)
        floor_sse = acting * 3 * (config.min_force_fraction * data.mass_kg * GRAVITY_MPS2) ** 2
        sig = block_bootstrap(without_sq, current_sq, test_block, fine_block=fine_block)
        if cost < floor_sse or sig.p_value > config.max_p_value:
            progress(f"dropped {score.name}: redundant given the others")
            accepted.remove(score)
            chosen = others
            current = fit.effects
            current_sq = without_sq
            remaining_sse = float(without_sq.sum())
            last_try[score.name] = replace(score, accepted=False)
            left.append(score.name)
    rejected = sorted(
        (s for n, s in last_try.items() if n in left), key=lambda s: -s.explained_fraction
    )
    return ForceSelection(
        tuple(accepted) + tuple(rejected),
        current,
        baseline,
        remaining_sse,
        test.n_rows,
        (float(noise[0]), float(noise[1]), float(noise[2])),
    )


def _row_sq(effects: EffectParams, data: ForceData, battery: BatteryModel) -> np.ndarray:
    """(n,) squared force residual per row [N^2] left over by ``effects``."""
    err = predicted_residual(effects, data, battery) - data.resid_ned_n
    return np.sum(err * err, axis=1)


def _acting_rows(
    before: EffectParams, after: EffectParams, data: ForceData, battery: BatteryModel
) -> int:
    """Rows of ``data`` on which ``after`` predicts another force residual than ``before``: a
    ground effect acts only in the low holds, and its RMS force counts over those rows."""
    change = predicted_residual(after, data, battery) - predicted_residual(before, data, battery)
    size = np.linalg.norm(change, axis=1)
    return int(np.count_nonzero(size > 1e-9 * max(float(size.max(initial=0.0)), 1e-300)))


def _simplest_of_best(tried: list, before: float, tolerance: float = 0.05):
    """The candidate with fewest parameters among those within ``tolerance`` of the best
    removal; (held-out sse, fit)."""
    best_sse = min(sse for sse, _ in tried)
    if best_sse >= before:
        return min(tried, key=lambda t: t[0])
    near = [t for t in tried if before - t[0] >= (1.0 - tolerance) * (before - best_sse)]
    return min(near, key=lambda t: (t[1].n_params, t[0]))


def _score(name, fit, share, before, after, test, accepted, sig=None) -> CauseScore:
    explained = share(before - after)
    step = (before - after) / before if before > 0 else 0.0
    return CauseScore(
        name,
        fit.effects,
        float(explained),
        float(step),
        _rms(before, test),
        _rms(after, test),
        accepted,
        sig,
        fit.at_bound,
    )


def _rms(sse: float, data: ForceData) -> float:
    return float(np.sqrt(sse / max(3 * data.n_rows, 1)))
