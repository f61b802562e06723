"""`scripts/jsbsim_diagnosis.py`: excitation flown on JSBSim, the f450 preset diagnosed."""

import json
from pathlib import Path

import pytest

from experiments.jsbsim_diagnosis import main
from flightlog.schema import read_flight_log

SPEED_MISSION = Path(__file__).resolve().parents[2] / "missions" / "excite_speed.toml"


@pytest.mark.slow
def test_a_short_excitation_on_jsbsim_is_diagnosed_with_a_gain(tmp_path, capsys):
    argv = ["--out", str(tmp_path), "--mission", str(SPEED_MISSION), "--max-s", "30"]
    assert main(argv) == 0
    log = read_flight_log(tmp_path / "logs" / "excite_speed.csv")
    assert log.metadata["backend"] == "jsbsim" and log.metadata["vehicle"] == "f450"
    assert 20.0 < log["t_s"][-1] <= 30.0
    report = json.loads((tmp_path / "diagnosis" / "report.json").read_text())
    assert (tmp_path / "diagnosis" / "report.md").is_file()
    assert report["schema"] == "diagnosis/2" and "isotropic_drag" in report["verdict"]
    baseline_mps = report["baseline"]["replay_vel_rmse_mps"]
    assert baseline_mps > report["extended"]["replay_vel_rmse_mps"]
    out = capsys.readouterr().out
    assert "| isotropic_drag | yes |" in out and "| replay | " in out


def test_a_missing_mission_is_one_line_and_exit_2(tmp_path, capsys):
    argv = ["--out", str(tmp_path), "--mission", str(tmp_path / "missing.toml")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("jsbsim-diagnosis: error:") and err.count("\n") == 1
    assert "cannot read excitation mission" in err and not (tmp_path / "logs").exists()
