"""fit-gp end to end on synthetic logs written to tmp_path."""

import subprocess
import sys

import numpy as np
import pytest
from gp_synthetic_logs import lag_plant_log, record_log

from flightlog.schema import write_flight_log
from gp.features import feature_definition
from gp.model_io import load_model, read_model_header
from gp.prediction_check import structure_only
from scripts import fit_gp as fit_gp_cli
from scripts import fit_gp_run
from scripts.fit_gp import main


def test_fit_gp_writes_model_plots_and_reports_rmse(tmp_path, capsys):
    logs = [
        write_flight_log(tmp_path / f"flight{i}.csv", record_log(400, seed=i, noise_mps=0.002))
        for i in range(2)
    ]
    out = tmp_path / "models" / "residual"
    code = main([*map(str, logs), "--out", str(out), "--m", "10", "--restarts", "1"])
    assert code == 0
    captured = capsys.readouterr()
    assert "fitting 3 sparse GPs (low_speed, m=10)" in captured.err
    for suffix in (".npz", "_residual_n.png", "_residual_e.png", "_residual_d.png"):
        assert (tmp_path / "models" / f"residual{suffix}").stat().st_size > 0
    assert not (tmp_path / "models" / "residual.json").exists()  # one self-describing file
    doc = read_model_header(tmp_path / "models" / "residual.npz")
    nominal = doc["training_data"]["nominal_rmse_mps"]
    augmented = doc["training_data"]["augmented_rmse_mps"]
    assert all(a < 0.5 * n for a, n in zip(augmented[:2], nominal[:2], strict=True))
    assert "augmented_rmse_mps" in captured.out
    expected = feature_definition("velocity", "kinematic_4dof", residual_dt_s=0.05)
    model = load_model(out, expected=expected)
    assert np.isfinite(model.predict(np.zeros((1, 3)))[0]).all()


HEAVY = ("sklearn", "scipy", "matplotlib", "casadi", "pyulog", "scripts.fit_gp_run")


@pytest.mark.parametrize(
    "argv", [["--help"], ["f.csv"], ["f.csv", "--out", "m", "--inducing", "kmeans"]]
)
def test_help_and_a_bad_command_line_answer_before_the_fitting_loads(argv):
    """The fitting's libraries (about 3 s of CPU) load only once the command line is read."""
    code = (
        "import sys\n"
        "from scripts.fit_gp import main\n"
        f"print(main({argv!r}))\n"
        "loaded = {*sys.modules, *(name.split('.')[0] for name in sys.modules)}\n"
        f"print(sorted(loaded & set({HEAVY!r})))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    *_, exit_code, heavy = out.stdout.strip().splitlines()
    assert (exit_code, heavy) == ("0" if argv == ["--help"] else "2", "[]"), out.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["missing.csv"], "no such flight log"),
        (["LOG", "--m", "5000"], "inducing points requested but"),
        (["LOG", "--inducing", "kmeans"], "invalid choice: 'kmeans'"),
        (["LOG", "--holdout-fraction", "1.5"], "--holdout-fraction must be in (0, 1)"),
        (["LOG", "--nominal-param", "tau_s"], "expected NAME=NUMBER"),
        # the parameter of another model: was a TypeError's text beside the implied residual_dt_s
        (
            ["LOG", "--nominal-param", "tau_s=0.5"],
            "nominal model kinematic_4dof has no parameter tau_s; it takes residual_dt_s",
        ),
        (
            ["LOG", "--nominal", "first_order_lag", "--nominal-param", "tau=0.5"],
            "nominal model first_order_lag has no parameter tau; it takes tau_s, tau_d_s",
        ),
        (
            ["LOG", "--nominal", "px4_velocity_pi"],
            "neither its sidecar's velocity_loop_gains nor its PX4 parameters",
        ),
        (["LOG", "--seed", "-1"], "--seed must be >= 0, got -1"),
        (["LOG", "--restarts", "-1"], "--restarts must be >= 1 starting point(s), got -1"),
        (["LOG", "--residual-interval-s", "inf"], "--residual-interval-s must be finite and > 0"),
        (["LOG", "--check-horizon-s", "inf"], "--check-horizon-s must be finite and > 0"),
    ],
)
def test_bad_input_exits_non_zero_with_one_line(tmp_path, capsys, args, message):
    log = write_flight_log(tmp_path / "f.csv", record_log(60))
    argv = [
        str(log) if a == "LOG" else str(tmp_path / a) if a.endswith(".csv") else a for a in args
    ]
    assert main([*argv, "--out", str(tmp_path / "m"), "--no-plots"]) == 2
    err_lines = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert len(err_lines) == 1 and message in err_lines[0]


def test_fit_gp_identifies_the_lag_when_flying_first_order_lag(tmp_path, capsys):
    from test_lag_identification import lag_log

    log = write_flight_log(tmp_path / "lag.csv", lag_log(0.55, 0.25))
    out = tmp_path / "lag_model"
    args = [
        str(log),
        "--out",
        str(out),
        "--nominal",
        "first_order_lag",
        "--features",
        "state_input",
        "--m",
        "8",
        "--restarts",
        "1",
        "--no-plots",
    ]
    assert main(args) == 0
    assert "identified velocity lag tau_s=0.55" in capsys.readouterr().err
    params = dict(load_model(out).features.nominal_params)
    assert params["tau_s"] == pytest.approx(0.55, rel=0.03)


def test_an_unwritable_out_is_refused_before_the_fit(tmp_path, capsys):
    """A file where the model's folder should be: one line, exit 2, before any GP is fitted
    (with --check-horizon-s or many logs the fit takes minutes)."""
    log = write_flight_log(tmp_path / "f.csv", record_log(60))
    (tmp_path / "plain").write_text("")
    out = tmp_path / "plain" / "model.npz"
    assert main([str(log), "--out", str(out), "--no-plots", "--force"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert not [line for line in err if "fitting" in line], err
    assert err[-1].startswith(f"fit-gp: error: --out {out}"), err


def test_the_same_flight_given_twice_is_refused(tmp_path, capsys):
    """A log and a copy of it: its held-out rows would be training rows too, so the held-out
    check would test the model on what it learned. One line naming both, exit 2; also for
    diagnose."""
    from scripts import diagnose

    log = write_flight_log(tmp_path / "f.csv", record_log(60))
    copy = tmp_path / "copy.csv"
    copy.write_bytes(log.read_bytes())
    assert main([str(log), str(copy), "--out", str(tmp_path / "m"), "--no-plots"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{copy}: the same flight as {log}" in err[0], err
    argv = [str(log), str(log), "--sim-config", "iris", "--out", str(tmp_path / "d")]
    assert diagnose.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the same flight as" in err[0], err
    assert not (tmp_path / "m.npz").exists() and not (tmp_path / "d").exists()


def test_a_history_model_from_fit_gp_flies_with_the_nmpcs_interval(tmp_path, capsys):
    """--residual-interval-s 0.1 on 50 Hz logs: the residual over 5 steps, so a
    velocity_history model lags one planner interval and the companion's NMPC takes it (over
    one step it lags 0.02 s and is refused in one line)."""
    from companion.nmpc_planner import CompanionNmpc, NmpcSettings
    from gp.errors import ModelFileError

    log = write_flight_log(tmp_path / "f.csv", record_log(300, dt_s=0.02, noise_mps=0.002))
    settings = NmpcSettings(speed_limit_mps=4.0, period_s=0.02, time_budget_s=30.0)
    base = [str(log), "--features", "velocity_history", "--nominal", "first_order_lag"]
    base += ["--nominal-param", "tau_s=0.5", "--nominal-param", "tau_d_s=0.4"]
    base += ["--m", "8", "--restarts", "1", "--no-plots", "--force"]  # judged elsewhere
    assert main([*base, "--out", str(tmp_path / "one_step")]) == 0
    with pytest.raises(ModelFileError, match="interval"):
        CompanionNmpc(settings, load_model(tmp_path / "one_step"))
    # said when it is written, not first found at take-off
    assert (
        "fit-gp: warning: the companion's NMPC will refuse this model (flown at the logs' rate): "
        "residual model's velocity history lags 0.02 s but the NMPC's interval is 0.1 s"
    ) in capsys.readouterr().err
    assert main([*base, "--out", str(tmp_path / "interval"), "--residual-interval-s", "0.1"]) == 0
    err = capsys.readouterr().err
    assert "residual over 5 log steps (0.1 s)" in err and "will refuse" not in err
    model = load_model(tmp_path / "interval")
    assert model.features.residual_steps == 5
    CompanionNmpc(settings, model)
    assert main([*base, "--out", str(tmp_path / "odd"), "--residual-interval-s", "0.05"]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert len(err) == 1 and "not a whole number of the logs' 0.02 s steps" in err[0]


def test_a_gp_that_does_not_beat_the_lag_is_written_and_said_to_be_left_out(tmp_path, capsys):
    """A pure velocity lag with sensor noise leaves the GP nothing to learn: the check against
    the lag alone fails, fit-gp writes the file (the companion flies the lag from it) and says
    so in one line; the GP's own held-out doubts no longer block what will not fly."""
    logs = [
        str(write_flight_log(tmp_path / f"f{i}.csv", lag_plant_log(i, 0.4, 0.0, n_rows=1500)))
        for i in range(2)
    ]
    args = ["--nominal", "first_order_lag", "--features", "velocity", "--check-horizon-s", "2"]
    code = fit_gp_cli.main([*logs, *args, "--out", str(tmp_path / "m")])
    err = capsys.readouterr().err
    assert "does NOT beat first_order_lag alone" in err
    assert code == 0 and (tmp_path / "m.npz").exists()
    said = [line for line in err.splitlines() if line.startswith("fit-gp: the GP does not beat")]
    assert said == [
        "fit-gp: the GP does not beat first_order_lag alone (see the check above): the companion "
        "flies first_order_lag without it (the file keeps the GP to inspect)"
    ]
    assert structure_only(load_model(tmp_path / "m.npz"))


def test_held_out_doubts_about_a_gp_left_out_are_not_asked_but_the_lags_bound_is():
    metrics = {"nominal_rmse_mps": [0.001, 0.001, 0.001], "augmented_rmse_mps": [0.002] * 3}
    on_bound = {"tau_s": fit_gp_run.TAU_BOUNDS_S[1], "tau_d_s": 0.5}
    assert len(fit_gp_run.model_doubts(metrics, on_bound)) == 4
    (doubt,) = fit_gp_run.model_doubts(metrics, on_bound, gp_flies=False)
    assert doubt.startswith("identified tau_s=")


def test_an_out_folder_is_refused_with_the_file_name_to_give(tmp_path, capsys):
    """diagnose --out takes a folder; fit-gp's names the model file (a folder wrote g.npz and
    its plots beside the folder)."""
    log = write_flight_log(tmp_path / "f.csv", record_log(60))
    folder = tmp_path / "g"
    folder.mkdir()
    assert main([str(log), "--out", str(folder), "--no-plots"]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert (
        f"--out {folder} is a folder; give the model file's name, e.g. --out {folder}/model" in line
    )
    assert not list(tmp_path.glob("g*.*")) and not any(folder.iterdir())  # nothing written
