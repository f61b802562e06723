"""Every command on real ULog fixtures: what each returns, and bad input as one line, exit 2,
nothing written."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from flightlog.reader import read_log
from flightlog.schema import REQUIRED_COLUMNS, FlightLogRecorder, write_flight_log
from scripts import diagnose as diagnose_cli
from scripts import fit_gp as fit_gp_cli
from scripts import flightlog_cli
from tests.flightlog.ulog_damage import corrupt_copy

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
AUTO = FIXTURES / "quad_sitl_v1_15_auto.ulg"

BAD = {
    "truncated.ulg": r"no valid motion.*truncated \(at byte 199955 of 200000\): only its first 2.3",
    "vtol_manual_v1_11.ulg": "no velocity command; flown in MANUAL.*position-controlled mode",
    "quad_manual_v1_6.ulg": "no velocity command; flown in MANUAL.*position-controlled mode",
}


def test_info_names_vehicle_firmware_rates_modes_validity_and_uses(capsys):
    assert flightlog_cli.main(["info", str(AUTO)]) == 0
    out = capsys.readouterr().out
    for line in (
        "vehicle: quadrotor",
        "firmware: PX4 v1.15.0-dev on PX4_SITL",
        "rate local_position: 10 Hz",
        "velocity command from: vehicle_local_position_setpoint",
        "mode TAKEOFF: 0.0 s to",
        "mode RTL:",
        "dropped estimator invalid: 96 of 311 rows",
        "thrust: produced from actuator_motors",
        "fit-gp: rates sufficient",
    ):
        assert line in out


@pytest.mark.parametrize(
    "name, lines",
    [
        ("vtol_manual_v1_11.ulg",
         ["vehicle: VTOL standard", "firmware: PX4 v1.11.2-dev on", "mode MANUAL: 0.0 s to 6.5 s"]),
        ("quad_manual_v1_6.ulg", ["firmware: PX4 v1.6.0-dev on", "mode MANUAL: 0.0 s",
                                  "topic vehicle_land_detected: 1 message\n"]),  # not "0 Hz"
    ],
)  # fmt: skip
def test_info_describes_a_ulog_no_command_can_use_and_says_why(name, lines, capsys):
    assert flightlog_cli.main(["info", str(FIXTURES / name)]) == 0
    out = capsys.readouterr().out
    for line in lines:
        assert line in out
    assert re.search(r"fit-gp, diagnose, convert: cannot use this log: .*no velocity command", out)


@pytest.mark.parametrize(
    ("firmware", "hardware", "line"),
    [
        ("v1.14.0", "PX4_FMU_V6C", "firmware: PX4 v1.14.0 on PX4_FMU_V6C"),
        ("v1.14.0", None, "firmware: PX4 v1.14.0 on a board not logged (no ver_hw)"),
        (None, None, "firmware: PX4, version not logged (no ver_sw_release), on a board not"),
    ],
)
def test_info_names_an_unlogged_board_not_none(firmware, hardware, line):
    """A ULog without ver_hw read 'on None' in its firmware line."""
    from flightlog.info import describe_unusable_ulog

    summary = {"vehicle": "quadrotor", "mav_type": 2, "firmware": firmware, "hardware": hardware}
    summary |= {"duration_s": 3.0, "rates_hz": {}, "messages": {}, "modes": [], "px4_params": {}}
    (firmware_line,) = [s for s in describe_unusable_ulog(summary, "why") if "firmware" in s]
    assert firmware_line.startswith(line) and "None" not in firmware_line


def test_convert_writes_csv_and_sidecar_that_read_back_the_same(tmp_path):
    out = tmp_path / "flight.csv"
    assert flightlog_cli.main(["convert", str(AUTO), "--out", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["flight.csv", "flight.csv.json"]
    a, b = read_log(AUTO), read_log(out)
    assert list(a.columns) == list(b.columns)
    for name in a.columns:
        assert (a[name] == b[name]).all() if name == "mode" else abs(a[name] - b[name]).max() < 1e-9
    meta = json.loads((tmp_path / "flight.csv.json").read_text())
    assert meta["thrust_source"]["topic"] == "actuator_motors"
    assert meta["px4_params"]["MC_ROLLRATE_P"] > 0


def test_ulog_is_recognised_by_content_not_name(tmp_path):
    renamed = tmp_path / "flight.bin"
    shutil.copy(AUTO, renamed)
    assert read_log(renamed).metadata["source"] == "px4_ulog"
    fake = tmp_path / "fake.ulg"
    fake.write_text("t_s,pos_n_m\n0,0\n")
    assert flightlog_cli.main(["info", str(fake)]) == 2


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_real_logs_one_line_exit_2_nothing_written(name, tmp_path, capsys):
    log = str(FIXTURES / name)
    out = tmp_path / "out"
    runs = [
        ("flightlog", lambda: flightlog_cli.main(["convert", log, "--out", str(out / "f.csv")])),
        ("fit-gp", lambda: fit_gp_cli.main([log, "--out", str(out / "model"), "--no-plots"])),
        ("diagnose", lambda: diagnose_cli.main([log, "--sim-config", "iris", "--out", str(out)])),
    ]
    for prog, run in runs:
        assert run() == 2, prog
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(prog), err
        assert re.search(BAD[name], err[0]), err[0]
        assert not out.exists()


@pytest.mark.parametrize("where", ["folder", "under_a_file"])
def test_convert_to_an_unwritable_place_one_line_exit_2_nothing_left(where, tmp_path, capsys):
    """An --out that is a folder, or lies under a file: one line naming it, no traceback, and
    no sidecar or temporary file left beside it."""
    (tmp_path / "taken").mkdir()
    (tmp_path / "plain").write_text("")
    out = tmp_path / ("taken" if where == "folder" else "plain/flight.csv")
    before = sorted(p.name for p in tmp_path.rglob("*"))
    assert flightlog_cli.main(["convert", str(AUTO), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("flightlog: ") and str(out) in err[0], err
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


def test_a_ulog_with_corrupt_definitions_shows_only_our_lines(tmp_path, capsys):
    """Message definitions zeroed in a real log: pyulog's own warnings (one per message id,
    printed to stdout) are not shown; diagnose says one line, info says why no command can
    use the log."""
    data = bytearray((FIXTURES / "quad_posctl_v1_15.ulg").read_bytes())
    data[3000:3200] = bytes(200)
    corrupt = tmp_path / "corrupt.ulg"
    corrupt.write_bytes(bytes(data))
    out = tmp_path / "out"
    assert diagnose_cli.main([str(corrupt), "--sim-config", "iris", "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "", captured.out[:300]
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("diagnose") and "corrupt" in err[0], err
    assert flightlog_cli.main(["info", str(corrupt)]) == 0
    captured = capsys.readouterr()
    assert "Warning" not in captured.out + captured.err, captured.out[:300]
    assert "cannot use this log: ULog is corrupt" in captured.out


def test_convert_onto_its_own_input_is_refused_and_the_ulog_kept(tmp_path, capsys):
    """--out naming the ULog being converted would replace the only copy of the flight."""
    ulog = tmp_path / "flight.ulg"
    shutil.copy(AUTO, ulog)
    assert flightlog_cli.main(["convert", str(ulog), "--out", str(ulog)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is an input being read" in err[0], err
    assert ulog.read_bytes() == AUTO.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["flight.ulg"]


def test_fit_gp_says_a_ulog_was_truncated(tmp_path, capsys):
    whole = (FIXTURES / "quad_posctl_v1_15.ulg").read_bytes()
    (tmp_path / "crashed.ulg").write_bytes(whole[: len(whole) // 2])
    fit_gp_cli.main([str(tmp_path / "crashed.ulg"), "--out", str(tmp_path / "model")])
    err = capsys.readouterr().err
    assert "fit-gp: warning: crashed.ulg is truncated" in err, err


def test_fit_gp_and_info_say_a_ulog_with_a_damaged_header_is_corrupt(tmp_path, capsys):
    damaged, offset = corrupt_copy(tmp_path, "size")
    assert flightlog_cli.main(["info", str(damaged)]) == 0
    out = capsys.readouterr().out
    assert f"corrupt: damaged.ulg is corrupt at byte {offset}" in out and "truncated" not in out
    fit_gp_cli.main([str(damaged), "--out", str(tmp_path / "model")])
    err = capsys.readouterr().err
    assert f"fit-gp: warning: damaged.ulg is corrupt at byte {offset}" in err, err
    assert "truncated" not in err


def test_convert_to_a_ulg_name_is_refused_since_no_command_would_read_the_csv(tmp_path, capsys):
    """`convert flight.ulg --out flight_copy.ulg` wrote a CSV named .ulg, which every command
    then refused as 'named .ulg but does not start with the ULog magic bytes; copy the log
    again from the vehicle'."""
    out = tmp_path / "flight_copy.ULG"
    assert flightlog_cli.main(["convert", str(AUTO), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"flightlog: --out {out}: a .ulg name for a schema-v1 CSV log, which every command "
        "would then refuse as a damaged ULog; name it .csv"
    ]
    assert list(tmp_path.iterdir()) == []


def test_info_on_a_companion_log_says_diagnose_needs_the_onboard_log(tmp_path, capsys):
    """A companion log has no thrust: 'thrust-related causes (mass, payload, thrust) cannot be
    examined' read as if drag and wind could be; none of the force-residual causes can."""
    rec = FlightLogRecorder({"source": "companion"})
    for k in range(200):
        row = dict.fromkeys(REQUIRED_COLUMNS, 0.0)
        rec.append({**row, "t_s": 0.02 * k, "q_w": 1.0, "vel_n_mps": 0.01 * k})
    log = write_flight_log(tmp_path / "nominal.csv", rec.to_log())
    assert flightlog_cli.main(["info", str(log)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert "thrust: none" in out
    assert (
        "diagnose: no thrust: the causes read from the force residual (drags, wind, payload, "
        "battery sag, ground effect) cannot be examined, only those read from the replay "
        "(command delay, motor lag, thrust curve, flight control)"
    ) in out
    assert out[-1].startswith("diagnose: this is the companion's log (MAVLink carries no thrust")
    assert diagnose_cli.main([str(log), "--sim-config", "iris", "--out", str(tmp_path / "d")]) == 0
    assert f"diagnose: warning: {log} is the companion's log" in capsys.readouterr().err
