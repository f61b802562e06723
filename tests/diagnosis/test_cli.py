"""The `diagnose` command: files in, report.json / report.md / plots / extended config out."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from experiments.hidden_effects import draw, fly_hidden
from scripts.diagnose import main
from vehicle_sim import load_sim_config

SCHEMA_KEYS = {"schema", "baseline", "causes", "verdict", "extended"}
CAUSE_KEYS = {"name", "params", "explained_fraction", "confidence", "evidence"}
V2_KEYS = {
    "closed_loop", "noise_floor", "explained_of_explainable", "not_examined", "at_bound",
    "warnings", "thrust_sources",
}  # fmt: skip
V2_CAUSE_KEYS = {"statistic", "at_bound", "unpinned"}
CLOSED_LOOP_KEYS = {
    "baseline_vel_rmse_mps", "extended_vel_rmse_mps", "gain", "ground_hold_gain", "segments",
    "segments_reanchored", "segments_reanchored_baseline", "segments_reanchored_extended",
    "scored_rows",
}  # fmt: skip


HEAVY = ("diagnosis", "vehicle_sim", "scipy", "matplotlib", "numba", "casadi")


@pytest.mark.parametrize("argv", [["--help"], ["f.csv", "--out", "o"]])
def test_help_and_a_bad_command_line_answer_before_the_diagnosis_loads(argv):
    """The diagnosis' libraries (about 3 s of CPU) load only once the command line is read."""
    code = (
        "import sys\n"
        "from scripts.diagnose import main\n"
        f"try:\n    main({argv!r})\nexcept SystemExit:\n    pass\n"
        f"print(sorted({{n.split('.')[0] for n in sys.modules}} & set({HEAVY!r})))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout


@pytest.mark.slow
def test_cli_writes_schema_report_plots_and_a_loadable_extended_config(tmp_path, capsys):
    truth, _ = draw("payload", np.random.default_rng(21))
    log_path = tmp_path / "flight_0.csv"
    fly_hidden(truth, tmp_path, seed=21)
    out = tmp_path / "out"
    assert main([str(log_path), "--sim-config", "iris", "--out", str(out)]) == 0
    assert "verdict: payload" in capsys.readouterr().err
    doc = json.loads((out / "report.json").read_text())
    assert set(doc) == SCHEMA_KEYS | V2_KEYS and doc["schema"] == "diagnosis/2"
    assert set(doc["baseline"]) == {"replay_vel_rmse_mps"}
    assert set(doc["extended"]) == {"replay_vel_rmse_mps", "gain"}
    assert all(set(c) == CAUSE_KEYS | V2_CAUSE_KEYS for c in doc["causes"])
    assert doc["causes"][0]["statistic"]["p_value"] < 0.01
    assert doc["verdict"] == ["payload"] and doc["causes"][0]["name"] == "payload"
    assert doc["extended"]["gain"] >= 3.0
    assert set(doc["closed_loop"]) == CLOSED_LOOP_KEYS
    assert doc["closed_loop"]["gain"] >= 3.0
    md = (out / "report.md").read_text()
    assert "## Closed-loop tracking" in md
    for png in ("replay_velocity.png", "residual_payload.png", "closed_loop_velocity.png"):
        assert f"]({png})" in md and (out / png).stat().st_size > 1000
    extended = load_sim_config(out / "extended_config.toml")
    assert extended.effect("payload").mass_ratio == pytest.approx(
        truth["payload"]["mass_ratio"], rel=0.02
    )
    assert extended.vehicle == load_sim_config("iris").vehicle


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["missing.csv", "--sim-config", "iris"], "no such flight log"),
        (["LOG", "--sim-config", "no_such_preset"], "no such config file or preset"),
    ],
)
def test_cli_bad_input_gives_one_line_and_exit_2(args, message, tmp_path, capsys):
    log = tmp_path / "flight_0.csv"
    log.write_text("t_s,pos_n_m\n0,0\n")
    argv = [
        str(log) if a == "LOG" else str(tmp_path / a) if a.endswith(".csv") else a for a in args
    ]
    assert main([*argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_cli_rejects_a_log_without_required_columns(tmp_path, capsys):
    log = tmp_path / "flight_0.csv"
    log.write_text("t_s,pos_n_m\n0,0\n")
    assert main([str(log), "--sim-config", "iris", "--out", str(tmp_path / "out")]) == 2
    assert "missing required column" in capsys.readouterr().err


def test_an_unusable_out_folder_is_refused_in_one_line_before_any_work(tmp_path, capsys):
    from scripts.diagnose import main as diagnose_main

    blocker = tmp_path / "report"
    blocker.write_text("a file where the report folder should go\n")
    code = diagnose_main(
        [str(tmp_path / "absent.csv"), "--sim-config", "iris", "--out", str(blocker)]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--out" in err[0] and "folder" in err[0]
    assert blocker.read_text().startswith("a file where")  # nothing lost
