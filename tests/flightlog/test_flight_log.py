"""Flight-log schema v1: round trip, and one-line errors that name file, row and column."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flightlog.reader import log_rates_hz, rate_shortfalls, read_log
from flightlog.schema import (
    REQUIRED_COLUMNS,
    FlightLogError,
    FlightLogRecorder,
    read_flight_log,
    sidecar_path,
    split_at_gaps,
    write_flight_log,
)


def _row(t_s: float, **extra: float | str) -> dict[str, float | str]:
    row: dict[str, float | str] = dict.fromkeys(REQUIRED_COLUMNS, 0.0)
    row.update(t_s=t_s, q_w=1.0, vel_n_mps=0.5 * t_s, cmd_vel_n_mps=1.0)
    row.update(extra)
    return row


def _write(tmp_path, rows, name="flight.csv"):
    rec = FlightLogRecorder({"source": "test", "mass_kg": 1.5})
    for r in rows:
        rec.append(r)
    return write_flight_log(tmp_path / name, rec.to_log())


def test_round_trip_keeps_values_metadata_and_text_columns(tmp_path):
    rows = [_row(0.02 * i, thrust_n=14.7 + i, mode="OFFBOARD") for i in range(50)]
    path = _write(tmp_path, rows)
    log = read_flight_log(path)
    assert log.n_rows == 50
    np.testing.assert_array_equal(log["t_s"], [0.02 * i for i in range(50)])
    np.testing.assert_array_equal(log["thrust_n"], [14.7 + i for i in range(50)])
    assert log["mode"][3] == "OFFBOARD"
    assert log.metadata["mass_kg"] == 1.5
    assert log.metadata["schema_version"] == 1
    assert log.stack("vel_n_mps", "cmd_vel_n_mps").shape == (50, 2)


def test_missing_required_column_is_named(tmp_path):
    path = _write(tmp_path, [_row(0.0), _row(0.1)])
    text = path.read_text().replace("cmd_yaw_rate_radps", "something_else")
    path.write_text(text)
    match = r"flight\.csv: missing required column\(s\) cmd_yaw_rate_radps"
    with pytest.raises(FlightLogError, match=match):
        read_flight_log(path)


def test_a_header_alone_is_refused_with_what_to_give(tmp_path):
    path = _write(tmp_path, [_row(0.0)])
    path.write_text(path.read_text().splitlines()[0] + "\n")
    with pytest.raises(FlightLogError, match=r"header but no data rows \(the recording stopped"):
        read_flight_log(path)


def test_nan_names_file_row_and_column(tmp_path):
    path = _write(tmp_path, [_row(0.0), _row(0.1), _row(0.2)])
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[3].split(",")
    cells[header.index("vel_e_mps")] = "nan"
    lines[3] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    match = r"flight\.csv: row 3, column vel_e_mps: nan is not finite"
    with pytest.raises(FlightLogError, match=match):
        read_flight_log(path)


def test_time_going_backwards_is_rejected(tmp_path):
    path = _write(tmp_path, [_row(0.0), _row(0.1), _row(0.2)])
    text = path.read_text().splitlines()
    text[3] = text[3].replace("0.2", "0.05", 1)
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(FlightLogError, match=r"row 3, column t_s: time 0.05 does not increase"):
        read_flight_log(path)


def test_truncated_row_and_non_number(tmp_path):
    path = _write(tmp_path, [_row(0.0), _row(0.1)])
    good = path.read_text()
    path.write_text(good.rsplit(",", 3)[0] + "\n")  # cut short: its last line says how to fix
    with pytest.raises(FlightLogError, match="row 2 has .* fields.*cut short.*delete its last"):
        read_flight_log(path)
    lines = good.splitlines()
    path.write_text("\n".join([lines[0], lines[1].rsplit(",", 3)[0], lines[2]]) + "\n")
    with pytest.raises(FlightLogError, match="row 1 has .* fields.*; the file is corrupt$"):
        read_flight_log(path)
    path.write_text(good.replace("0.1,", "abc,", 1))
    with pytest.raises(FlightLogError, match=r"row 2, column t_s: 'abc' is not a number"):
        read_flight_log(path)


def test_a_folder_given_as_log_is_named_a_folder(tmp_path):
    """A folder of logs passed where a log is expected: say it is a folder and what to pass
    (it was called missing), naming the ULog too."""
    (tmp_path / "logs").mkdir()
    with pytest.raises(FlightLogError) as info:
        read_log(tmp_path / "logs")
    assert str(info.value).startswith(f"{tmp_path / 'logs'}: a folder, not a flight log")
    assert ".ulg" in str(info.value)


def test_missing_file_binary_file_and_bad_sidecar(tmp_path):
    with pytest.raises(FlightLogError, match="no such flight log"):
        read_flight_log(tmp_path / "absent.csv")
    binary = tmp_path / "b.csv"
    binary.write_bytes(b"\xff\xfe\x00\x81ULog")
    with pytest.raises(FlightLogError, match="a binary file, not a schema-v1 CSV"):
        read_flight_log(binary)
    path = _write(tmp_path, [_row(0.0), _row(0.1)])
    sidecar_path(path).write_text("{not json")
    with pytest.raises(FlightLogError, match=r"flight\.csv\.json: sidecar is not valid JSON"):
        read_flight_log(path)
    for not_an_object, kind in (("[]", "list"), ('"x"', "str"), ("3", "int")):
        sidecar_path(path).write_text(not_an_object)
        with pytest.raises(FlightLogError, match=f"sidecar holds a JSON {kind}, not an object"):
            read_flight_log(path)
    sidecar_path(path).write_text(json.dumps({"schema_version": 7}))
    with pytest.raises(FlightLogError, match="schema_version 7"):
        read_flight_log(path)


def test_recorder_rejects_inconsistent_and_unknown_columns():
    rec = FlightLogRecorder()
    with pytest.raises(FlightLogError, match="missing required columns"):
        rec.append({"t_s": 0.0})
    with pytest.raises(FlightLogError, match="unknown columns.*'wind_truth_mps'"):
        rec.append(_row(0.0, wind_truth_mps=3.0))
    rec.append(_row(0.0))
    with pytest.raises(FlightLogError, match="row 1 has columns"):
        rec.append(_row(0.1, thrust_n=1.0))
    with pytest.raises(FlightLogError, match="empty"):
        FlightLogRecorder().to_log()


def test_gaps_are_an_error_on_request_and_split_otherwise(tmp_path):
    times = [0.0, 0.1, 0.2, 1.5, 1.6, 3.0]
    path = _write(tmp_path, [_row(t) for t in times])
    with pytest.raises(FlightLogError, match=r"row 4, column t_s: gap of 1.300 s"):
        read_flight_log(path, max_gap_s=0.5)
    parts = split_at_gaps(read_flight_log(path), max_gap_s=0.5)
    assert [p.n_rows for p in parts] == [3, 2, 1]
    assert parts[1]["t_s"][0] == 1.5


def test_a_csv_logs_rate_is_its_row_spacing_across_a_gap():
    """A companion CSV written at 10 Hz (0.1 s rows) for 10 s, then 10 s of nothing (the
    link dropped), then 10 s more: 10 Hz, fast enough for fit-gp and diagnose; 200 rows over
    the 30 s span (6.7 Hz) would be refused for rows the log does have."""
    rec = FlightLogRecorder({"source": "test"})
    for i in [*range(100), *range(200, 300)]:
        rec.append(_row(0.1 * i))
    log = rec.to_log()
    assert log_rates_hz(log) == {"local_position": 10.0, "velocity_command": 10.0}
    assert rate_shortfalls(log, "fit-gp") == rate_shortfalls(log, "diagnose") == []


@pytest.mark.parametrize(
    "content",
    [
        bytes([0xFD, 0x1C, 0x00, 0x00, 0x05, 0x01, 0x01, 0x21]) * 40,  # MAVLink 2 frames
        bytes([0xA3, 0x95, 0x80, 0x80, 0x59]) + bytes(range(128, 256)),  # no NUL, not UTF-8
    ],
)
def test_a_telemetry_log_is_refused_as_binary_not_as_a_ulog_or_a_csv_missing_columns(
    tmp_path, content
):
    """QGC's .tlog given where a ULog belongs said 'missing required column(s) t_s, ...' (or
    'is it a ULog? use the ULog reader', a reader the user cannot choose): say what it is."""
    path = tmp_path / "2026-11-27 09-50-00.tlog"
    path.write_bytes(content)
    with pytest.raises(FlightLogError) as info:
        read_log(path)
    message = str(info.value)
    assert message.startswith(f"{path}: a binary file, not a schema-v1 CSV")
    assert "PX4 ULog (.ulg" in message and ".tlog" in message and "ULog reader" not in message


def test_a_csv_of_other_columns_is_named_once_not_listed_twice(tmp_path):
    path = tmp_path / "export.csv"
    path.write_text("time,lat,lon\n0,47.3,8.5\n")
    with pytest.raises(FlightLogError) as info:
        read_log(path)
    assert str(info.value) == (
        f"{path}: not a schema-v1 flight log: its first line ('time,lat,lon') names none of "
        f"the columns schema v1 needs ({', '.join(REQUIRED_COLUMNS)})"
    )


def test_a_log_saved_by_a_spreadsheet_with_a_byte_order_mark_is_read(tmp_path):
    """A spreadsheet's "CSV UTF-8" starts with a BOM, which made the first column '\\ufefft_s'
    and the log 'missing required column(s) t_s'."""
    path = _write(tmp_path, [_row(0.0), _row(0.1)])
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    log = read_log(path)
    assert log.n_rows == 2 and list(log["t_s"]) == [0.0, 0.1]
