"""Residual datasets from synthetic flight logs: targets, features, splitting and rejection."""

import dataclasses

import numpy as np
import pytest
from gp_synthetic_logs import drag_residual, record_log

from flightlog.schema import FlightLog
from gp.datasets import DatasetConfig, residual_dataset
from gp.errors import DatasetError
from gp.evaluation import holdout_split, residual_rmse
from gp.features import FeatureDefinition, feature_definition
from gp.log_signals import model_input, model_state
from planners.nominal_models import make_model


def _config(name="velocity", **kwargs):
    return DatasetConfig(feature_definition(name, "kinematic_4dof", residual_dt_s=0.05), **kwargs)


def test_residual_against_kinematic_model_is_the_known_residual():
    data = residual_dataset([record_log(300)], _config())
    assert data.n_rows == 299 and data.X.shape == (299, 3) and data.Y.shape == (299, 3)
    np.testing.assert_allclose(data.X, data.vel_ned_mps)
    np.testing.assert_allclose(data.Y, drag_residual(data.vel_ned_mps), atol=1e-9)
    np.testing.assert_allclose(data.dt_s, 0.05)


def test_history_features_hold_the_previous_step():
    log = record_log(100)
    data = residual_dataset([log], _config("history"))
    assert data.X.shape == (98, 12)
    k = 10
    np.testing.assert_allclose(data.X[k, 3:6], log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")[k])
    np.testing.assert_allclose(
        data.X[k, 0:3], log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")[k + 1]
    )
    np.testing.assert_allclose(data.X[k, 9], log["cmd_vel_n_mps"][k])
    assert data.features.input_names[3] == "vel_n_mps[k-1]"


def test_gap_splits_the_log_and_no_residual_spans_it():
    data = residual_dataset([record_log(200, gap_at=120)], _config())
    assert len(data.segment_names) == 2 and data.n_rows == 119 + 79
    assert data.dt_s.max() == pytest.approx(0.05)


def test_mode_changes_split_and_unlisted_modes_are_dropped():
    modes = ["position"] * 50 + ["offboard"] * 100 + ["position"] * 50
    log = record_log(200, modes=modes)
    assert len(residual_dataset([log], _config()).segment_names) == 3
    only = residual_dataset([log], _config(modes=("offboard",)))
    assert len(only.segment_names) == 1 and only.n_rows == 99


def test_nan_in_a_log_is_rejected_with_row_and_column():
    log = record_log(50)
    cols = dict(log.columns)
    cols["vel_e_mps"] = cols["vel_e_mps"].copy()
    cols["vel_e_mps"][7] = np.nan
    with pytest.raises(
        DatasetError, match=r"row 8, column vel_e_mps is nan; drop or repair"
    ) as info:
        residual_dataset([FlightLog(cols)], _config())
    assert "\n" not in str(info.value)


def test_too_short_logs_give_a_clear_error():
    with pytest.raises(DatasetError, match="no usable rows in 1 log"):
        residual_dataset([record_log(3)], _config())


def test_unmappable_nominal_model_signal_is_a_clear_error():
    log = record_log(20)
    odd = dataclasses.replace(make_model("kinematic_4dof"), state_names=("pos_n_m", "alt_m"))
    with pytest.raises(DatasetError, match=r"state signals \['alt_m'\] that cannot be taken"):
        model_state(odd, log)
    assert model_input(make_model("unicycle"), log).shape == (20, 2)


def test_bad_feature_set_lists_the_valid_ones():
    with pytest.raises(ValueError, match="unknown feature set 'speed'; choose one of velocity"):
        feature_definition("speed")


def test_holdout_split_uses_whole_blocks_and_evaluates_like_paper_000():
    """Segments of 399 and 299 rows in blocks of 69 (a tenth of the rows; each segment's
    remainder a shorter block): in each segment the rows held out lie in runs no shorter than
    the shortest block (23 rows: 299 - 4 x 69), and they make up a quarter of the rows within
    half a block."""
    data = residual_dataset([record_log(400, seed=1), record_log(300, seed=2)], _config())
    train, test = holdout_split(data, 0.25, seed=3)
    assert train.n_rows + test.n_rows == data.n_rows
    assert abs(test.n_rows - 0.25 * data.n_rows) <= 69 / 2
    assert np.bincount(data.segment).tolist() == [399, 299]
    rows = zip(data.segment, data.X, data.Y, strict=True)
    row_of = {(s, *x, *y): i for i, (s, x, y) in enumerate(rows)}
    held = np.zeros(data.n_rows, bool)
    held[[row_of[(s, *x, *y)] for s, x, y in zip(test.segment, test.X, test.Y, strict=True)]] = 1
    for seg in np.unique(data.segment):
        runs = np.diff(np.flatnonzero(np.diff(np.r_[0, held[data.segment == seg], 0])))[::2]
        assert np.all(runs >= 23), (seg, runs)
    perfect = residual_rmse(test, test.Y)
    assert perfect["augmented_rmse_mps"] == [0.0, 0.0, 0.0]
    nominal = residual_rmse(test, np.zeros_like(test.Y))["nominal_rmse_mps"]
    np.testing.assert_allclose(nominal, np.sqrt(np.mean((test.Y * 0.05) ** 2, axis=0)))


def test_feature_definition_round_trips_through_dict():
    fd = feature_definition("state_input", "first_order_lag", tau_s=0.4)
    assert FeatureDefinition.from_dict(fd.to_dict()) == fd
    assert fd.speed_columns == (0, 1, 2) and fd.n_features == 7


def test_a_log_disarmed_throughout_is_refused_for_that_not_for_short_segments():
    """A real log recorded on the ground after the flight (v1.8, RTL finished, disarmed): the
    error says the vehicle never flew, not that its segments were short."""
    log = record_log(50)
    cols = dict(log.columns)
    cols["armed"] = np.zeros(50)
    with pytest.raises(DatasetError, match=r"all 50 rows are disarmed \(the vehicle never flew\)"):
        residual_dataset([FlightLog(cols)], _config())
    cols["armed"] = np.where(np.arange(50) < 47, 0.0, 1.0)
    with pytest.raises(DatasetError, match=r"of 50 rows, 47 disarmed, 3 in segments shorter"):
        residual_dataset([FlightLog(cols)], _config())
