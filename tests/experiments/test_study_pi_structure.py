"""`study --learned-model px4_velocity_pi`: the GP is fitted on PX4's velocity PI loop with the
gains the autopilot reported with the nominal flights, the PI structure alone flies as the
ablation (offset-free, better than nominal) and the identified lag alone beside it, and the
report and headline say so."""

from __future__ import annotations

import pytest

from companion.autopilot_gains import velocity_loop_gains
from companion.inprocess_link import InProcessLink
from gp.model_io import load_model
from scripts.study import main as study_main


@pytest.mark.slow(expected_s=75)
def test_wind_study_learns_on_the_pi_structure_beside_the_lag(tmp_path, capsys):
    out = tmp_path / "study"
    argv = ["--quick", "--regime", "wind_field", "--learned-model", "px4_velocity_pi"]
    assert study_main([*argv, "--out", str(out)]) == 0
    captured = capsys.readouterr()
    reported = dict(velocity_loop_gains(InProcessLink.from_vehicle("iris_wind_field", 0)))
    for sel in ("low_speed", "cluster"):
        features = load_model(out / f"gp_{sel}.npz").features
        assert features.nominal_model == "px4_velocity_pi"
        gains = {k: v for k, v in features.nominal_params if k in reported}
        assert gains == pytest.approx(reported)
    report = (out / "report.md").read_text()
    # the structure-alone arm (figures keyed identified_lag) is named by what it flies
    for arm in ("structure alone (px4_velocity_pi)", "lag_structure"):
        assert f"| {arm} | 2 (2) |" in report
    assert "| identified_lag |" not in report
    assert "flies the learned model's structure (`px4_velocity_pi`)" in report
    assert "trajectory 0 structure alone (px4_velocity_pi) seed " in captured.err
    assert "lag_structure: identified velocity lag tau_s=" in captured.err
    headline = dict(line.split(" = ") for line in captured.out.splitlines() if " = " in line)
    assert headline["structure_model"] == "px4_velocity_pi"
    lag, augmented = (
        float(headline[k]) for k in ("tracking_rmse_lag_structure_m", "tracking_rmse_augmented_m")
    )
    assert float(headline["gp_over_lag_structure"]) == pytest.approx(lag / augmented, rel=1e-3)
    # offset-free, the PI structure alone flies well clear of nominal through the wind (read
    # as an acceleration, the integrator holding the wind made it fly worse than nominal)
    nominal, pi_alone = (
        float(headline[k]) for k in ("tracking_rmse_nominal_m", "tracking_rmse_identified_lag_m")
    )
    assert pi_alone < 0.5 * nominal
