"""study --regime / scripts.rover: bad input exits 2; the section 3.4 example writes Fig. 4."""

import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from scripts import rover, study

REPO = Path(__file__).resolve().parents[2]


def test_unknown_regime_exits_2(capsys) -> None:
    assert study.main(["--regime", "rover_exp9"]) == 2
    assert "rover_exp9" in capsys.readouterr().err
    assert rover.main(["--regime", "rover_exp1", "--trials", "0"]) == 2
    capsys.readouterr()
    # the example is one fixed run: options it would ignore are refused, not dropped silently
    for extra in (["--trials", "5"], ["--quick"], ["--seed", "3"]):
        assert rover.main(["--regime", "example", *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and extra[0] in err[0], err


@pytest.mark.slow
def test_example_regime_writes_the_figure(tmp_path: Path, capsys) -> None:
    assert study.main(["--regime", "example", "--out", str(tmp_path)]) == 0
    png = tmp_path / "fig4_illustrative.png"
    out, err = capsys.readouterr()
    assert f"wrote {png}" in err  # where to look; the figures printed say what they are:
    assert set(json.loads(out)["rms_tracking_error_z"]) == {"feedback", "mpc", "lbnmpc"}
    assert png.stat().st_size > 10_000
    assert not [p for p in tmp_path.iterdir() if p.name.startswith("tmp")]


def test_an_out_folder_that_cannot_be_made_is_one_line_exit_2(tmp_path: Path, capsys) -> None:
    """A file where the output folder should go: one line naming --out, before any trial."""
    blocker = tmp_path / "blocker"
    blocker.write_text("")
    for regime in ("example", "rover_exp1"):
        assert rover.main(["--regime", regime, "--out", str(blocker / "out")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"rover: error: --out {blocker}"), err
    # through study, its lines name the command the user ran (they said "rover: error:")
    assert study.main(["--regime", "rover_exp1", "--out", str(blocker / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"study: error: --out {blocker}"), err


def test_without_out_the_files_go_under_out_as_every_command_s_do(
    tmp_path: Path, monkeypatch, capsys
) -> None:
    """Not into a rover_out/ beside the sources, which nothing ignores; --help says where."""
    monkeypatch.chdir(tmp_path)
    assert rover.main(["--regime", "example"]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert (tmp_path / "out" / "rover" / "fig4_illustrative.png").is_file()
    capsys.readouterr()
    assert rover.main(["--help"]) == 0
    assert "output folder (default out/rover)" in capsys.readouterr().out


def test_a_negative_seed_is_one_line_exit_2(tmp_path: Path, capsys) -> None:
    """The trial draws need a seed >= 0: said in one line, not a NumPy traceback."""
    assert rover.main(["--regime", "rover_exp1", "--seed", "-3", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--seed" in err[0] and ">= 0" in err[0], err
    assert rover.main(["--regime", "rover_exp1", "--seed", "x", "--out", str(tmp_path)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "argument --seed: must be an integer >= 0, got 'x'" in line  # not "invalid _seed"


def test_help_lists_the_regimes_what_is_written_and_quick(capsys) -> None:
    """--help says what each regime is and which files it writes; study's --help points at
    the rover regimes it hands over."""
    assert rover.main(["--help"]) == 0
    text = capsys.readouterr().out
    for word in ("rover_exp2", "Ackermann", "fig4_illustrative.png", "REGIME.json", "--quick"):
        assert word in text, word
    # each panel of the regime's figure (experiments.rover.report.figure) is named
    assert "e_L along the path in the first and the last trial" in " ".join(text.split())
    assert study.main(["--help"]) == 0
    assert "rover_exp1" in capsys.readouterr().out


@pytest.mark.slow
def test_quick_rover_regime_through_study_reports_each_trial(tmp_path: Path, capsys) -> None:
    """`study --regime rover_exp1 --quick` (study's own smoke option) runs a few trials, says
    each on stderr as it ends, and writes the figure and the summary."""
    assert study.main(["--regime", "rover_exp1", "--quick", "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    assert "trial 1/2" in err and "trial 2/2" in err
    assert f"wrote {tmp_path / 'rover_exp1.png'} and {tmp_path / 'rover_exp1.json'}" in err
    assert (tmp_path / "rover_exp1.json").stat().st_size > 0
    assert (tmp_path / "rover_exp1.png").stat().st_size > 10_000


@pytest.mark.slow
@pytest.mark.parametrize(
    ("regime", "once_running"),
    [("rover_exp1", "trial 1/20"), ("example", "example: feedback, MPC and LB-NMPC")],
)
def test_ctrl_c_is_one_line_exit_130_and_writes_nothing(
    tmp_path: Path, regime: str, once_running: str
) -> None:
    """Ctrl-C after the first trial (or while the example runs its three controllers): no
    traceback, exit 130, no half-written figure, and no empty --out folder left behind."""
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "scripts.rover", "--regime", regime, "--out", str(out)],
        cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    try:
        for line in proc.stderr:
            if once_running in line:
                break
        proc.send_signal(signal.SIGINT)
        err = proc.stderr.read()
        assert proc.wait(60) == 130, err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)
    assert "Traceback" not in err and err.strip().splitlines()[-1].startswith("rover: interrupted")
    assert list(tmp_path.iterdir()) == []  # not even the folder
