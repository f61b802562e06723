"""Every command's bad option is one line naming it and exit 2, without argparse's usage block."""

from __future__ import annotations

import pytest

from scripts import (
    bench,
    companion_cli,
    diagnose,
    fit_gp,
    flightlog_cli,
    rover,
    study,
    vehicle_sim_cli,
)


def _exit_code(main, argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:  # some commands leave argparse's exit to the caller
        return int(exc.code)


@pytest.mark.parametrize(
    ("prog", "main", "argv", "message"),
    [
        ("diagnose", diagnose.main, ["f.csv", "--sim-config", "iris", "--out", "o",
                                     "--workers", "0"], "--workers must be >= 1"),
        ("diagnose", diagnose.main, [], "the following arguments are required"),
        ("companion", companion_cli.main, ["m.toml", "--rate-hz", "0"], "rate_hz must be within"),
        ("study", study.main, ["--m", "0"], "m must be >= 1"),
        ("bench", bench.main, ["--only", "nope"], "unknown part 'nope'"),
        ("rover", rover.main, ["--regime", "example", "--frobnicate"], "unrecognized arguments"),
        ("fit-gp", fit_gp.main, ["f.csv", "--out", "m", "--m", "0"], "--m must be >= 1"),
        ("fit-gp", fit_gp.main, ["f.csv", "--out", "m", "--nominal", "unicycle"],
         "invalid choice: 'unicycle'"),
        ("study", study.main, ["--quick", "--repeats", "2"], "drop --quick or --repeats"),
        ("flightlog convert", flightlog_cli.main, ["convert", "f.ulg"], "required: --out"),
    ],
)  # fmt: skip
def test_bad_option_is_one_line_and_exit_2(prog, main, argv, message, capsys):
    assert _exit_code(main, argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"{prog}: error: ") and message in err[0], err


@pytest.mark.parametrize(
    ("prog", "main", "argv"),
    [
        ("diagnose", diagnose.main, ["f.csv", "--sim-config", "iris", "--out", ""]),
        ("fit-gp", fit_gp.main, ["f.csv", "--out", ""]),
        ("companion", companion_cli.main, ["m.toml", "--log", " "]),
        ("study", study.main, ["--out", ""]),
        ("flightlog convert", flightlog_cli.main, ["convert", "f.ulg", "--out", ""]),
        ("rover", rover.main, ["--regime", "example", "--out", ""]),
        ("vehicle-sim", vehicle_sim_cli.main, ["--log", ""]),
    ],
)
def test_an_empty_output_path_is_refused_not_taken_as_the_current_folder(
    prog, main, argv, tmp_path, monkeypatch, capsys
):
    """``--out "$OUT"`` with OUT unset: refused in one line; nothing lands in the current folder
    (a report set there would replace the user's own report.md)."""
    monkeypatch.chdir(tmp_path)
    assert _exit_code(main, argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"{prog}: error: ") and "empty path" in err[0], err
    assert list(tmp_path.iterdir()) == []
