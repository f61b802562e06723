"""The one reader every command uses: a file named .ulg is refused when it is not one (in any
case of the name), a missing one is named missing; one flight given twice is refused; signals
too slow for a command, and --mode filters no log can meet, are named."""

from __future__ import annotations

import numpy as np
import pytest

from flightlog.reader import rate_shortfalls, read_log, require_distinct, require_modes
from flightlog.schema import FlightLog, FlightLogError


def rated(velocity_command_hz: float | None, local_position_hz: float = 50.0) -> FlightLog:
    rates = {"local_position": local_position_hz}
    if velocity_command_hz is not None:
        rates["velocity_command"] = velocity_command_hz
    return FlightLog({"t_s": np.arange(3.0)}, {"rates_hz": rates})


def moded(*modes: str) -> FlightLog:
    return FlightLog({"t_s": np.arange(float(len(modes))), "mode": np.array(modes)})


def test_a_file_named_ulg_in_capitals_without_the_magic_bytes_is_refused(tmp_path):
    path = tmp_path / "FLIGHT.ULG"
    path.write_text("time,pos_n_m\n0,0\n")
    with pytest.raises(FlightLogError, match="named .ulg but does not start with the ULog magic"):
        read_log(path)


def test_an_empty_ulg_and_a_csv_named_ulg_are_said_to_be_what_they_are(tmp_path):
    """Both read 'does not start with the ULog magic bytes; ... (or pass a schema-v1 CSV)':
    for the CSV, a fix it already was."""
    empty = tmp_path / "empty.ulg"
    empty.write_bytes(b"")
    with pytest.raises(FlightLogError, match=r"empty.ulg: empty file \(0 bytes\); copy the log"):
        read_log(empty)
    csv = tmp_path / "flight.ulg"
    for text in ("t_s,pos_n_m\n0,0\n", "\ufeffpos_n_m, t_s\n0,0\n"):  # a spreadsheet's too
        csv.write_text(text, encoding="utf-8")
        with pytest.raises(FlightLogError, match=r"a schema-v1 CSV \(its header has t_s\); rename"):
            read_log(csv)


def test_a_missing_ulg_is_named_missing_not_foreign(tmp_path):
    with pytest.raises(FlightLogError, match="no such flight log"):
        read_log(tmp_path / "gone.ulg")


def test_a_copy_of_a_flight_is_refused_and_a_missing_path_left_to_the_reader(tmp_path):
    first, copy = tmp_path / "a.csv", tmp_path / "b.csv"
    first.write_text("t_s\n0\n")
    copy.write_text("t_s\n0\n")
    with pytest.raises(FlightLogError, match=f"{copy}: the same flight as {first}"):
        require_distinct([first, copy])
    require_distinct([first, tmp_path / "gone.csv"])  # the reader will say it is missing


def test_a_rate_at_most_five_percent_under_a_need_meets_it():
    """PX4's logger writes a 10 Hz topic a little slower: 9.5 Hz meets a 10 Hz need, and
    4.75 Hz a 5 Hz one; 9.4 Hz does not."""
    assert rate_shortfalls(rated(4.75, 9.5), "diagnose") == []
    assert rate_shortfalls(rated(4.75, 9.4), "diagnose") == [
        "local_position at 9.4 Hz (needs >= 10 Hz)"
    ]


def test_a_signal_the_log_does_not_hold_is_too_slow():
    assert rate_shortfalls(rated(None), "fit-gp") == ["velocity_command at 0 Hz (needs >= 5 Hz)"]


def test_a_mode_filter_needs_one_named_mode_in_any_log():
    require_modes([moded("MANUAL"), moded("POSCTL", "POSCTL")], ["POSCTL", "OFFBOARD"])
    with pytest.raises(FlightLogError, match="no rows in mode OFFBOARD; the logs hold MANUAL"):
        require_modes([moded("MANUAL")], ["OFFBOARD"])


def test_no_mode_filter_asks_nothing_of_the_logs():
    require_modes([FlightLog({"t_s": np.arange(3.0)})], [])
