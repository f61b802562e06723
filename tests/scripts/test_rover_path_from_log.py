"""`rover-path teach --from-log`: a path from a recorded drive in a real PX4 ULog, its refusals
(one line, exit 2, nothing written) and a repeat of what it taught."""

import json
from pathlib import Path

import pytest

from scripts.rover_path import main
from tests.flightlog.ulog_damage import FIXTURES, POSCTL, corrupt_copy

EXISTING = "x_m,y_m\n0,0\n1,0\n2,0\n"  # a path file already there, which a refusal keeps


def test_teach_from_a_real_log_prints_what_a_live_teach_prints_and_the_span(
    tmp_path: Path, capsys
) -> None:
    out = tmp_path / "p.csv"
    assert main(["teach", "--from-log", str(POSCTL), "--out", str(out)]) == 0
    rows = out.read_text().splitlines()
    assert rows[0] == "x_m,y_m" and len(rows) == 1 + 53
    assert capsys.readouterr().err.strip().splitlines() == [
        f"rover-path: wrote {out}: 53 vertices 0.25 m apart, 12.9 m (open: its end is 7.7 m "
        "from its start); from quad_posctl_v1_15.ulg 0.0-75.1 s (armed, quadrotor)"
    ]


@pytest.mark.parametrize(
    ("log", "extra", "message"),
    [
        ("{readme}", [], "not a ULog file (it does not start with the ULog magic bytes)"),
        ("{tmp}/head.ulg", [], "ULog is truncated at byte 2853 and holds no local position"),
        ("fixedwing_v1_17rc_status.ulg", [], "holds no vehicle_local_position; log the drive"),
        ("quad_stab_nogps_v1_16_1.ulg", [], "local position is invalid throughout the log"),
        ("quad_manual_v1_6.ulg", [], "the vehicle was never armed; pass --start-s and --end-s"),
        ("quad_offboard_v1_16.ulg", [], "turns back on itself at t=19.2 s"),
        ("quad_offboard_v1_16.ulg", ["--end-s", "15"], "moved 0.00 m"),
        ("quad_posctl_v1_15.ulg", ["--start-s", "80"], "--start-s 80 is outside"),
        ("quad_posctl_v1_15.ulg", ["--end-s", "80"], "--end-s 80 is past the end"),
    ],
)
def test_a_log_that_gives_no_path_is_one_line_exit_2_and_nothing_written(
    tmp_path: Path, capsys, log: str, extra: list[str], message: str
) -> None:
    (tmp_path / "head.ulg").write_bytes(POSCTL.read_bytes()[:3000])
    readme = FIXTURES / "README.md"
    source = log.format(tmp=tmp_path, readme=readme)
    source = source if "/" in source else str(FIXTURES / source)
    out = tmp_path / "p.csv"
    out.write_text(EXISTING)
    assert main(["teach", "--from-log", source, "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rover-path: error: ") and message in err[0], err
    assert out.read_text() == EXISTING
    assert sorted(p.name for p in tmp_path.iterdir()) == ["head.ulg", "p.csv"]  # no temporary


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--start-s", "3"], "--start-s cuts a span of --from-log DRIVE.ulg; pass --from-log"),
        (["--from-log", "x.ulg", "--drive", "3:0"], "--drive is for a live teach"),
        (["--from-log", "x.ulg", "--timeout", "9"], "--timeout is for a live teach"),
        (["--from-log", "x.ulg", "--link", "mavsdk"], "--link is for a live teach"),
        (["--from-log", "x.ulg", "--url", "udpin:0.0.0.0:15540"], "--url is for a live teach"),
        (["--from-log", "x.ulg", "--seed", "3"], "--seed is for a live teach"),
        (["--from-log", "x.ulg", "--end-s=-1"], "--end-s: must be a finite number >= 0"),
        (["--from-log", str(POSCTL), "--out", str(POSCTL)], "is an input being read"),
    ],
)
def test_options_that_do_not_fit_are_one_line_exit_2(
    tmp_path: Path, capsys, argv: list[str], message: str
) -> None:
    out = ["--out", str(tmp_path / "p.csv")] if "--out" not in argv else []
    assert main(["teach", *out, *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err


def test_a_damaged_log_says_so_and_teaches_what_was_read(tmp_path: Path, capsys) -> None:
    damaged, offset = corrupt_copy(tmp_path, "type")
    assert main(["teach", "--from-log", str(damaged), "--out", str(tmp_path / "p.csv")]) == 0
    warning, wrote = capsys.readouterr().err.strip().splitlines()
    assert warning.startswith(f"rover-path: warning: damaged.ulg is corrupt at byte {offset}")
    assert "53 vertices" in wrote and "from damaged.ulg" in wrote


@pytest.mark.slow
def test_a_path_taught_from_a_real_log_is_repeated(tmp_path: Path, capsys) -> None:
    path = tmp_path / "p.csv"
    span = ["--start-s", "20", "--end-s", "40"]  # 2.6 m of the flight, turning gently
    assert main(["teach", "--from-log", str(POSCTL), "--out", str(path), *span]) == 0
    assert "11 vertices" in capsys.readouterr().err
    argv = ["repeat", "--path", str(path), "--link", "inprocess", "--vehicle", "husky_50kg",
            "--trials", "2", "--drive-back", "--out", str(tmp_path / "out")]  # fmt: skip
    assert main(argv) == 0
    assert "completed: 2 trials driven" in capsys.readouterr().err
    report = json.loads((tmp_path / "out" / "repeat.json").read_text())
    assert report["status"] == "completed" and report["trial"] == [1, 2]
    assert all(report["reached_end"]) and max(report["max_e_lat_m"]) < 0.1
