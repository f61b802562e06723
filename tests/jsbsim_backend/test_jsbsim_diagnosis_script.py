"""`scripts/jsbsim_diagnosis.py`: excitation flown on JSBSim, the f450 preset diagnosed."""

import json
from pathlib import Path

import pytest

from experiments.jsbsim_diagnosis import main
from flightlog.schema import read_flight_log
from vehicle_sim.jsbsim_backend import JsbsimF450Plant

SPEED_MISSION = Path(__file__).resolve().parents[2] / "missions" / "excite_speed.toml"


@pytest.mark.slow(expected_s=45)
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
    # issue 18: the fitted drag is JSBSim's own 0.5 rho S CD (its DRAG axis), within 15 %
    fitted = next(c for c in report["causes"] if c["name"] == "isotropic_drag")["params"]
    own = JsbsimF450Plant().air_drag_coefficient_n_per_mps2()
    assert abs(fitted["k_n_per_mps2"] / own - 1.0) < 0.15, (fitted, own)


def test_a_missing_mission_is_one_line_and_exit_2(tmp_path, capsys):
    argv = ["--out", str(tmp_path), "--mission", str(tmp_path / "missing.toml")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("jsbsim-diagnosis: error:") and err.count("\n") == 1
    assert "cannot read excitation mission" in err and not (tmp_path / "logs").exists()


@pytest.mark.parametrize("max_s", ["nan", "-5"])
def test_a_max_s_that_is_no_time_is_one_line_and_exit_2(tmp_path, capsys, max_s):
    """--max-s nan flew the whole missions (no segment compares above nan)."""
    with pytest.raises(SystemExit) as stop:
        main(["--out", str(tmp_path / "out"), "--max-s", max_s])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("jsbsim-diagnosis: error: --max-s must be a finite time > 0 s")
    assert err.count("\n") == 1 and not (tmp_path / "out").exists()


def test_an_out_folder_that_cannot_be_made_is_one_line_before_flying(tmp_path, capsys):
    """A file where the folder goes was a FileExistsError traceback."""
    (tmp_path / "taken").write_text("")
    assert main(["--out", str(tmp_path / "taken")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"jsbsim-diagnosis: error: --out {tmp_path / 'taken'}: a file stands")
    assert err.count("\n") == 1


def test_jsbsim_own_drag_coefficient_is_half_rho_s_cd():
    """The F450's DRAG axis: qbar * S * CD with S = 0.016129 m^2 and CD = 1 (its Aero.xml),
    at the density of Zurich's 488 m: about 0.0094 N/(m/s)^2."""
    k = JsbsimF450Plant().air_drag_coefficient_n_per_mps2()
    assert 0.5 * 1.10 * 0.016129 < k < 0.5 * 1.225 * 0.016129
