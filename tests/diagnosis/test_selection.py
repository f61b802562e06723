"""Forward selection on held-out blocks, on arrays with known causes."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

from diagnosis.candidates import FORCE_CAUSES
from diagnosis.force_model import predicted_residual
from diagnosis.forces import ForceData
from diagnosis.selection import ForceSelection, select_causes, train_test_masks
from tests.diagnosis.test_force_math import BATTERY, synthetic, with_residual


def test_blocks_alternate_between_training_and_held_out():
    data = synthetic(n=400)
    train, test = train_test_masks(data, block_s=2.0)
    assert not np.any(train & test) and np.all(train | test)
    assert abs(train.sum() - test.sum()) <= 40
    flips = np.flatnonzero(np.diff(test.astype(int)))
    assert len(flips) == 9


def test_two_causes_are_selected_in_order_of_strength():
    truth = {"payload": {"mass_ratio": 1.4}, "body_drag": {"c_n_per_mps2": (0.03, 0.03, 0.05)}}
    data = with_residual(synthetic(n=1200), truth, noise_n=0.05)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ("payload", "body_drag")
    assert abs(result.effects["payload"]["mass_ratio"] - 1.4) < 0.01
    assert result.explained_of_explainable() > 0.99  # both true causes: all but the noise


def test_a_true_cause_explains_all_of_the_residual_above_the_noise():
    """A 1.2 payload under 0.6 N of noise per axis: the noise is a tenth of the held-out
    residual, and the payload all of the rest; the share reported is of the part above the
    noise floor (about 1), not of the whole (about 0.9)."""
    data = with_residual(synthetic(n=1200), {"payload": {"mass_ratio": 1.2}}, noise_n=0.6)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ("payload",)
    assert 0.05 < result.noise_sse_n2 / result.baseline_sse_n2 < 0.2
    assert result.explained_of_explainable() > 0.97


def test_a_cause_whose_fit_sits_on_its_search_bound_is_not_named():
    """Twice the residual of the heaviest payload the search allows (mass ratio 1.8): the
    payload fit stops on that bound and explains most of the residual, but a value the search
    cut short is not a finding, so nothing is named."""
    data = synthetic(n=1200)
    heaviest = predicted_residual({"payload": {"mass_ratio": 1.8}}, data, BATTERY)
    noise = 0.05 * np.random.default_rng(1).standard_normal((data.n_rows, 3))
    data = ForceData(**{**data.__dict__, "resid_ned_n": 2.0 * heaviest + noise})
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ()
    best = result.scores[0]
    assert best.name == "payload" and best.at_bound and best.explained_fraction > 0.5
    assert best.effects["payload"]["mass_ratio"] == pytest.approx(1.8, rel=1e-3)


def test_a_cause_a_later_one_makes_redundant_is_dropped():
    """Body drag (0.03 per axis) with a trace of isotropic drag (0.002), under 0.01 N of noise:
    isotropic_drag is taken first (it explains most of a nearly isotropic drag), then
    body_drag; given body_drag, what isotropic_drag adds is below the floor (0.3 % of the
    weight), though measurable at this noise, so it is dropped: only body_drag is named."""
    truth = {
        "body_drag": {"c_n_per_mps2": (0.03, 0.03, 0.03)},
        "isotropic_drag": {"k_n_per_mps2": 0.002},
    }
    data = with_residual(synthetic(n=1200), truth, noise_n=0.01)
    said: list[str] = []
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES, progress=said.append)
    assert "accepted isotropic_drag" in said and "accepted body_drag" in said
    assert result.accepted == ("body_drag",)


def test_noise_alone_names_nothing():
    data = with_residual(synthetic(n=1200), {}, noise_n=0.3)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ()
    assert result.remaining_rms_n() > 0.25


def test_slowly_wandering_disturbance_does_not_generalise():
    data = synthetic(n=2400)
    rng = np.random.default_rng(5)
    walk = np.cumsum(rng.normal(0.0, 0.05, (data.n_rows, 3)), axis=0)
    walk -= walk.mean(axis=0)
    data = type(data)(**{**data.__dict__, "resid_ned_n": walk})
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ()


def test_a_ground_effect_confined_to_short_low_holds_is_named():
    """Issue 18: a thrust gain acting only in a tenth of the rows (short holds at 5-12 cm) has a
    small RMS over the whole flight; counted over the rows it acts on it is clearly there."""
    rng = np.random.default_rng(11)
    n = 2400
    alt = np.full(n, 2.0)
    for start in np.linspace(100, n - 200, 10).astype(int):
        alt[start : start + 24] = rng.uniform(0.05, 0.12, 24)
    truth = {"ground_effect": {"max_gain": 0.1, "rotor_radius_m": 0.13, "rotor_height_m": 0.1}}
    data = with_residual(synthetic(n=n, alt_m=alt), truth, noise_n=0.2)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ("ground_effect",)
    clean = with_residual(synthetic(n=n, alt_m=alt), {}, noise_n=0.2)
    assert select_causes(clean, {}, BATTERY, FORCE_CAUSES).accepted == ()


def test_explained_fractions_stay_shares_when_the_noise_floor_swamps_the_residual():
    """Noise alone at 1 N: the estimated floor lies above the held-out residual, so nothing is
    explainable; a candidate's explained fraction is then its share of the whole held-out
    residual (a few tenths of a percent), not of a vanishing explainable part (128 % and
    -113 % here; 996185 % on a real EKF-failure log)."""
    data = with_residual(synthetic(n=1200), {}, noise_n=1.0)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.baseline_sse_n2 < result.noise_sse_n2
    assert result.accepted == ()
    assert all(abs(s.explained_fraction) < 0.02 for s in result.scores), result.scores
    assert result.explained_of_explainable() == 1.0  # nothing above the floor is left over


def test_an_explained_fraction_is_of_the_part_above_the_floor_else_of_the_whole():
    """The rule both the force and the replay path use: a share of the explainable part, at
    most all of it; of the whole error when nothing stands above the floor (a replay whose
    error is within its noise floor had divided by 1e-12 m^2/s^2)."""
    from diagnosis.cause import explained_fraction

    assert explained_fraction(2.0, total=10.0, noise=6.0, least=0.1) == 0.5
    assert explained_fraction(6.0, total=10.0, noise=6.0, least=0.1) == 1.0
    assert explained_fraction(-9.0, total=10.0, noise=6.0, least=0.1) == -1.0
    assert explained_fraction(0.5, total=10.0, noise=10.5, least=0.1) == 0.05
    assert explained_fraction(0.5, total=10.0, noise=9.95, least=0.1) == 0.05
    assert explained_fraction(0.5, total=0.0, noise=0.0, least=0.0) == 0.0


def test_a_cause_too_weak_to_matter_is_not_named_however_clear():
    """A payload of 0.2 % of the weight under 1 mN of noise stands far out of the noise, but
    its RMS force (0.2 % / sqrt(3) per component) is under the 0.3 % of the weight a cause must
    explain to be named."""
    data = with_residual(synthetic(n=1200), {"payload": {"mass_ratio": 1.002}}, noise_n=0.001)
    result = select_causes(data, {}, BATTERY, FORCE_CAUSES)
    assert result.accepted == ()
    assert result.scores[0].name == "payload" and result.scores[0].explained_fraction > 0.9


def test_a_step_gain_is_the_share_of_the_then_remaining_residual():
    """Each score's step gain is 1 - (after / before)^2 of its RMS residuals (same rows)."""
    truth = {"payload": {"mass_ratio": 1.4}, "body_drag": {"c_n_per_mps2": (0.03, 0.03, 0.05)}}
    data = with_residual(synthetic(n=1200), truth, noise_n=0.05)
    for s in select_causes(data, {}, BATTERY, FORCE_CAUSES).scores:
        assert s.step_gain_fraction == pytest.approx(1.0 - (s.after_rms_n / s.before_rms_n) ** 2)


def test_a_second_logs_first_block_is_held_out():
    """Blocks alternate within each log, and the parity flips from one log to the next, so
    two logs that start alike are not both trained on their first seconds."""
    data = synthetic(n=160)  # 8 s at 20 Hz: blocks of 2 s
    two_logs = ForceData(
        **{**data.__dict__, "t_s": np.tile(data.t_s[:80], 2), "segment": np.repeat([0, 1], 80)}
    )
    train, test = train_test_masks(two_logs, block_s=2.0)
    assert train[:40].all() and test[40:80].all()  # first log: train, test
    assert test[80:120].all() and train[120:].all()  # second log: test, train


def test_explained_of_explainable_is_a_share_of_the_residual_above_the_noise_floor():
    """Held-out residual 10 N^2 over 2 rows with noise std (1, 0, 0) N: floor 2 N^2, 8 above
    it. Down to 6 N^2 explains half of that; below the floor all of it (not more); a residual
    at the floor leaves nothing to explain (all of it explained)."""
    left_at = partial(ForceSelection, (), {}, 10.0, n_test=2, noise_std_n=(1.0, 0.0, 0.0))
    assert left_at(final_sse_n2=6.0).explained_of_explainable() == 0.5
    assert left_at(final_sse_n2=0.0).explained_of_explainable() == 1.0
    at_floor = ForceSelection((), {}, 2.0, 2.0, 2, (1.0, 0.0, 0.0))
    assert at_floor.explained_of_explainable() == 1.0


def test_remaining_rms_is_per_component():
    """12 N^2 left over 2 rows of 3 components: sqrt(12 / 6) N."""
    assert ForceSelection((), {}, 20.0, 12.0, 2).remaining_rms_n() == pytest.approx(np.sqrt(2.0))
