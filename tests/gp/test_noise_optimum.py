"""The all-noise optimum (the GP calls every residual noise and predicts about 0) is found and
said in the fit report, on a synthetic case that reaches it and on real PX4 logs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gp.inducing import InducingConfig
from gp.model_io import load_model
from gp.noise_optimum import all_noise_note, all_noise_outputs
from gp.sparse_gp import SparseGP
from scripts import fit_gp as fit_gp_cli

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
FAST = ["--m", "10", "--restarts", "1", "--no-plots", "--force"]


@pytest.mark.parametrize("outlier_share", [0.0, 0.05])
def test_an_input_with_far_outliers_drives_the_fit_to_all_noise_and_it_is_found(outlier_share):
    """y = sin(2 x0): learned on clean inputs; with 5 % of rows at x0 = +-1e4 (the input's
    spread, which sets the lengthscale bounds and the inducing points, some 2000x the bulk's) the
    bound's optimum calls it all noise."""
    rng = np.random.default_rng(0)
    X = rng.uniform(-2.0, 2.0, (1500, 2))
    y = np.sin(2.0 * X[:, 0]) + 0.05 * rng.standard_normal(1500)
    outliers = int(outlier_share * 1500)
    X[:outliers, 0] = rng.choice([-1.0, 1.0], outliers) * 1e4
    y[:outliers] = 0.0
    gp = SparseGP(inducing=InducingConfig("cluster", m=30), random_state=0).fit(X, y)
    signal = np.array([k.variance for k in gp.kernels_])
    found = all_noise_outputs(signal, gp.noise_variances_)
    mean, _ = gp.predict(X[outliers:])
    if outlier_share:
        assert found == [0] and np.std(mean) < 0.1  # predicts about 0
        note = all_noise_note(("y",), signal, gp.noise_variances_)
        assert note is not None and note.startswith("the GP explains nothing but noise on y")
        assert "\n" not in note
        # its "larger --m" never contradicts fit-gp's too-little-flight warning ("lower --m")
        assert "with enough flight" in note and note.index("enough flight") < note.index("--m")
    else:
        assert found == [] and np.std(mean) > 0.5


def test_fit_gp_says_when_a_real_log_leaves_the_gp_all_noise(tmp_path, capsys):
    out = tmp_path / "posctl"
    fit_gp_cli.main([str(FIXTURES / "quad_posctl_v1_15.ulg"), "--out", str(out), *FAST])
    noted = [line for line in capsys.readouterr().err.splitlines() if "nothing but noise" in line]
    assert len(noted) == 1, noted
    assert noted[0].startswith("fit-gp: warning: the GP explains nothing but noise on res_acc_n")
    training = load_model(out.with_suffix(".npz")).training
    assert training["all_noise_outputs"] == ["res_acc_n_mps2", "res_acc_e_mps2", "res_acc_d_mps2"]
    learned = tmp_path / "auto"
    fit_gp_cli.main([str(FIXTURES / "quad_sitl_v1_15_auto.ulg"), "--out", str(learned), *FAST])
    assert "nothing but noise" not in capsys.readouterr().err
    assert "all_noise_outputs" not in load_model(learned.with_suffix(".npz")).training
