"""The thrust-mismatch regression lines its features up with the follower's rows."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.replay import windows
from diagnosis.thrust_response import track_thrust
from experiments.hidden_effects import fly_hidden
from experiments.thrust_mismatch import main, row_features
from vehicle_sim import load_sim_config


@pytest.mark.slow
def test_features_follow_the_tracked_rows_and_the_cli_reports(tmp_path, capsys):
    logs = fly_hidden({"motor_lag": {"tau_s": 0.06}}, tmp_path, 5)
    wins = windows(logs)[::4]
    tracked = track_thrust(load_sim_config("iris"), logs, wins)
    feats = row_features(logs, wins)
    np.testing.assert_array_equal(feats[:, 0], tracked.meas_thrust_n)
    assert np.std(feats[:, 1]) > 0.1  # the excitation flight moves along body z
    assert main(["--config", "iris", str(tmp_path / "flight_0.csv")]) == 0
    assert "RMS left" in capsys.readouterr().out
