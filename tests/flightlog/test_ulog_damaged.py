"""A truncated ULog (logging stopped mid-message: a crash, a power loss) is read up to its last
complete message and says so; one whose complete part cannot be used says it is truncated. A
corrupt one (bytes changed in a message header before the end) is called corrupt, not
truncated."""

from __future__ import annotations

from pathlib import Path

import pytest
from pyulog import ULog

from flightlog.info import describe_log
from flightlog.schema import FlightLogError
from flightlog.ulog import damage_note, read_ulog
from flightlog.ulog_integrity import find_damage
from tests.flightlog.ulog_damage import corrupt_copy, hardfault_copy

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"


def test_the_complete_part_of_a_truncated_ulog_is_read_and_named(tmp_path) -> None:
    whole = (FIXTURES / "quad_posctl_v1_15.ulg").read_bytes()
    half = tmp_path / "crashed.ulg"
    half.write_bytes(whole[: len(whole) // 2])
    log = read_ulog(half)
    assert log.metadata["duration_s"] > 30.0 and log.n_rows > 200
    assert log.metadata["truncated_at_byte"][1] == len(whole) // 2
    note = damage_note(log)
    assert note is not None and note.startswith("crashed.ulg is truncated") and "\n" not in note
    assert f"truncated: {note}" in describe_log(log)
    assert damage_note(read_ulog(FIXTURES / "quad_posctl_v1_15.ulg")) is None


def test_a_truncated_ulog_too_short_to_use_says_it_is_truncated() -> None:
    with pytest.raises(FlightLogError, match=r"no valid motion.*truncated.*first 2\.3 s"):
        read_ulog(FIXTURES / "truncated.ulg")


def test_the_real_fixtures_are_whole_and_the_cut_one_is_truncated() -> None:
    for path in sorted(FIXTURES.glob("*.ulg")):
        damage = find_damage(path)
        if path.name == "truncated.ulg":
            assert damage is not None and (damage.kind, damage.at_byte) == ("truncated", 199955)
        else:
            assert damage is None, (path.name, damage)


@pytest.mark.parametrize("how", ["size", "type"])
def test_a_ulog_with_a_damaged_header_is_called_corrupt_not_truncated(tmp_path, how) -> None:
    path, offset = corrupt_copy(tmp_path, how)
    log = read_ulog(path)
    assert "truncated_at_byte" not in log.metadata
    assert log.metadata["corrupt_at_byte"] == [offset, path.stat().st_size]
    note = damage_note(log)
    assert note is not None and "\n" not in note
    assert note.startswith(f"damaged.ulg is corrupt at byte {offset} of {path.stat().st_size}")
    assert "truncated" not in note and "copy the .ulg again" in note
    assert f"corrupt: {note}" in describe_log(log)


def test_a_crashed_ulog_with_the_hardfault_report_appended_is_truncated_not_corrupt(tmp_path):
    """PX4 appends its hardfault report after the message the crash cut (pyulog reads it, and
    the log before it, without a fault): the walk resumes at the appended offset."""
    path, cut_at = hardfault_copy(tmp_path)
    parsed = ULog(str(path))
    assert not parsed.file_corruption and "hardfault_plain" in parsed.msg_info_multiple_dict
    damage = find_damage(path)
    assert damage is not None and (damage.kind, damage.at_byte) == ("truncated", cut_at)
    log = read_ulog(path)
    assert "corrupt_at_byte" not in log.metadata
    assert damage_note(log).startswith(
        f"hardfault.ulg is truncated (last message incomplete at byte {cut_at}"
    )


def test_an_appended_offset_past_the_end_is_corrupt(tmp_path):
    path, _ = hardfault_copy(tmp_path)
    data = bytearray(path.read_bytes())
    data[16 + 3 + 16 : 16 + 3 + 24] = (len(data) + 1).to_bytes(8, "little")
    path.write_bytes(bytes(data))
    damage = find_damage(path)
    assert damage is not None and damage.kind == "corrupt" and "appended-data" in damage.detail
