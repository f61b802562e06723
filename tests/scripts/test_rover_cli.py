"""study --regime / scripts.rover: bad input exits 2; the section 3.4 example writes Fig. 4."""

from pathlib import Path

import pytest

from scripts import rover, study


def test_unknown_regime_exits_2(capsys) -> None:
    assert study.main(["--regime", "rover_exp9"]) == 2
    assert "rover_exp9" in capsys.readouterr().err
    assert rover.main(["--regime", "rover_exp1", "--trials", "0"]) == 2


def test_a_negative_seed_is_one_line_exit_2_not_a_traceback(tmp_path: Path, capsys) -> None:
    out = tmp_path / "out"
    assert study.main(["--regime", "rover_exp1", "--seed", "-1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["rover: error: --seed must be >= 0, got -1"], err
    assert not out.exists()


@pytest.mark.slow
def test_example_regime_writes_the_figure(tmp_path: Path) -> None:
    assert study.main(["--regime", "example", "--out", str(tmp_path)]) == 0
    png = tmp_path / "fig4_illustrative.png"
    assert png.stat().st_size > 10_000
    assert not [p for p in tmp_path.iterdir() if p.name.startswith("tmp")]


def test_an_out_folder_that_cannot_be_made_is_one_line_exit_2(tmp_path: Path, capsys) -> None:
    """A file where the output folder should go: one line naming --out, before any trial."""
    blocker = tmp_path / "blocker"
    blocker.write_text("")
    for regime in ("example", "rover_exp1"):
        assert rover.main(["--regime", regime, "--out", str(blocker / "out")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"rover: --out {blocker}"), err


@pytest.mark.slow
def test_each_trial_shows_progress_on_stderr(tmp_path: Path, capsys) -> None:
    """A rover regime runs for minutes: one stderr line per trial, as every command shows."""
    assert study.main(["--regime", "rover_exp1", "--trials", "2", "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert [line.split(":")[1] for line in err] == [
        " rover_exp1 trial 1/2",
        " rover_exp1 trial 2/2",
    ]
