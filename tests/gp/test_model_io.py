"""Model files: round trip, versioning and feature-definition checks."""

import json

import numpy as np
import pytest

from gp.errors import ModelFileError
from gp.features import feature_definition
from gp.model_io import ResidualModel, load_model, read_model_header, save_model


def _model(small_model):
    features = feature_definition("velocity", "kinematic_4dof", residual_dt_s=0.05)
    return ResidualModel.from_estimator(
        small_model, features, inducing={"strategy": "low_speed", "m": 12}, training={"n_rows": 600}
    )


def test_round_trip_keeps_predictions_and_description(small_model, tmp_path):
    model = _model(small_model)
    path = save_model(tmp_path / "residual", model)
    assert path == tmp_path / "residual.npz" and sorted(p.name for p in tmp_path.iterdir()) == [
        "residual.npz"
    ]
    loaded = load_model(path, expected=model.features)
    X = np.random.default_rng(0).normal(size=(20, 3))
    np.testing.assert_array_equal(loaded.predict(X)[0], small_model.predict(X)[0])
    np.testing.assert_array_equal(loaded.predict(X)[1], small_model.predict(X)[1])
    assert loaded.features == model.features and loaded.model_type == "sgpr"
    doc = read_model_header(path)
    assert doc["format_version"] == 1
    assert doc["feature_definition"]["nominal_model"] == {
        "name": "kinematic_4dof",
        "params": {"residual_dt_s": 0.05},
    }
    assert len(doc["hyperparameters"]) == 3 and doc["training_data"] == {"n_rows": 600}
    f = loaded.casadi_function()
    np.testing.assert_allclose(
        np.array(f(X[0])[0]).ravel(), small_model.predict(X[:1])[0][0], atol=1e-9
    )


@pytest.mark.parametrize(
    ("expected", "message"),
    [
        (feature_definition("history"), r"trained on features 'velocity' .* expects 'history'"),
        (
            feature_definition("velocity", "kinematic_4dof", residual_dt_s=0.02),
            r"residual_dt_s=0\.05\).* expects .*residual_dt_s=0\.02",
        ),
    ],
)
def test_loading_against_another_feature_definition_is_an_error(
    small_model, tmp_path, expected, message
):
    path = save_model(tmp_path / "m", _model(small_model))
    with pytest.raises(ModelFileError, match=message) as info:
        load_model(path, expected=expected)
    assert "\n" not in str(info.value) and "refit" in str(info.value)


def _rewrite(path, small_model, header=None, drop=None, extra=None):
    """Write a model file by hand: a changed header, a dropped array or an extra entry."""
    model = _model(small_model)
    arrays = {k: getattr(model.posterior, k) for k in ("support", "lengthscales", "variance")}
    arrays |= {k: getattr(model.posterior, k) for k in ("alpha", "var_factor", "y_offset")}
    arrays["noise_variance"] = model.noise_variance
    arrays["header"] = np.array(json.dumps(header if header is not None else model.to_dict()))
    arrays.pop(drop, None)
    np.savez(path, **arrays, **(extra or {}))


def test_missing_wrong_version_and_corrupt_files_are_one_line_errors(small_model, tmp_path):
    with pytest.raises(ModelFileError, match="no such model file; train one with fit-gp"):
        load_model(tmp_path / "absent.npz")
    path = tmp_path / "m.npz"
    _rewrite(path, small_model, header={**_model(small_model).to_dict(), "format_version": 99})
    with pytest.raises(ModelFileError, match="version 99, this reader understands"):
        load_model(path)
    _rewrite(path, small_model, drop="alpha")
    with pytest.raises(ModelFileError, match="incomplete or corrupt model"):
        load_model(path)
    path.write_bytes(b"PK\x03\x04 truncated")
    with pytest.raises(ModelFileError, match="not a readable model file") as info:
        load_model(path)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "content",
    [
        b"garbage\n",
        b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (0,), }",
    ],
    ids=["text", "npy"],
)
def test_a_file_that_is_no_npz_archive_is_named_so_in_one_line(tmp_path, content):
    """Not "holds Python objects" (numpy tries any unknown bytes as a pickle), and no
    traceback for a single array (.npy) saved under the model's name."""
    path = tmp_path / "m.npz"
    path.write_bytes(content)
    with pytest.raises(ModelFileError, match="not a .npz archive as fit-gp writes") as info:
        load_model(path)
    assert "Python objects" not in str(info.value) and "\n" not in str(info.value)


def test_a_model_file_holding_python_objects_is_refused_without_suggesting_pickle(
    small_model, tmp_path
):
    path = tmp_path / "m.npz"
    _rewrite(path, small_model, extra={"payload": np.array([{"x": 1}], dtype=object)})
    with pytest.raises(ModelFileError, match="holds Python objects") as info:
        load_model(path)
    assert "allow_pickle" not in str(info.value)


def test_an_older_two_file_model_gets_the_fix(tmp_path):
    (tmp_path / "old.json").write_text("{}")
    with pytest.raises(ModelFileError, match="older two-file model: refit it with fit-gp"):
        load_model(tmp_path / "old")


def test_a_flight_log_given_as_model_is_named_as_not_a_model(tmp_path):
    """``--gp-model flight.csv`` (a log, with its sidecar flight.csv.json beside it): the
    message names the file given and what a model is, not an "older two-file model"."""
    (tmp_path / "flight.csv").write_text("t_s\n0\n")
    (tmp_path / "flight.csv.json").write_text("{}")
    with pytest.raises(ModelFileError) as info:
        load_model(tmp_path / "flight.csv")
    message = str(info.value)
    assert message.startswith(f"{tmp_path / 'flight.csv'}: not a model file")
    assert "two-file" not in message and "fit-gp" in message and "\n" not in message
