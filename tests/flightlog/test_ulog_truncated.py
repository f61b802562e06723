"""A truncated ULog (logging stopped mid-message: a crash, a power loss) is read up to its last
complete message and says so; one whose complete part cannot be used says it is truncated."""

from __future__ import annotations

from pathlib import Path

import pytest

from flightlog.info import describe_log
from flightlog.schema import FlightLogError
from flightlog.ulog import read_ulog, truncation_note

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"


def test_the_complete_part_of_a_truncated_ulog_is_read_and_named(tmp_path) -> None:
    whole = (FIXTURES / "quad_posctl_v1_15.ulg").read_bytes()
    half = tmp_path / "crashed.ulg"
    half.write_bytes(whole[: len(whole) // 2])
    log = read_ulog(half)
    assert log.metadata["duration_s"] > 30.0 and log.n_rows > 200
    assert log.metadata["truncated_at_byte"][1] == len(whole) // 2
    note = truncation_note(log)
    assert note is not None and note.startswith("crashed.ulg is truncated") and "\n" not in note
    assert f"truncated: {note}" in describe_log(log)
    assert truncation_note(read_ulog(FIXTURES / "quad_posctl_v1_15.ulg")) is None


def test_a_truncated_ulog_too_short_to_use_says_it_is_truncated() -> None:
    with pytest.raises(FlightLogError, match=r"no valid motion.*truncated.*first 2\.3 s"):
        read_ulog(FIXTURES / "truncated.ulg")
