"""A truncated ULog (logging stopped mid-message: a crash, a power loss) is read up to its last
complete message and says so; one whose complete part cannot be used says it is truncated. A
corrupt one (bytes changed in a message header before the end) is called corrupt, not
truncated."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from flightlog.info import describe_log
from flightlog.schema import FlightLogError
from flightlog.ulog import damage_note, read_ulog, summarise_ulog
from flightlog.ulog_integrity import find_damage
from scripts import flightlog_cli, vehicle_sim_cli
from tests.flightlog.ulog_damage import corrupt_copy, hardfault_copy, stale_copy

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


# Hand-built ULogs: a 16-byte file header, then messages of (uint16 size, type, payload).
HEADER = b"ULog\x01\x12\x35\x01" + bytes(8)


def message(kind: bytes, payload: bytes) -> bytes:
    return len(payload).to_bytes(2, "little") + kind + payload


def flag_bits(compat0: int = 0, incompat0: int = 0, offsets: tuple[int, ...] = ()) -> bytes:
    """The flag-bits message: compat[8], incompat[8], appended_offsets uint64[3]."""
    appended = b"".join(o.to_bytes(8, "little") for o in (*offsets, 0, 0, 0)[:3])
    return message(b"B", bytes([compat0]) + bytes(7) + bytes([incompat0]) + bytes(7) + appended)


SUBSCRIBE = message(b"A", bytes([0]) + (7).to_bytes(2, "little") + b"topic")  # msg_id 7
SAMPLE = message(b"D", (7).to_bytes(2, "little") + bytes(8))  # msg_id 7, 8 data bytes


def damage_of(tmp_path: Path, data: bytes):
    path = tmp_path / "hand.ulg"
    path.write_bytes(data)
    return find_damage(path)


def test_a_hand_built_ulog_is_whole(tmp_path) -> None:
    assert damage_of(tmp_path, HEADER + flag_bits() + SUBSCRIBE + SAMPLE + SAMPLE) is None
    assert damage_of(tmp_path, HEADER) is None  # header alone: nothing cut


def test_a_file_shorter_than_the_ulog_header_is_truncated(tmp_path) -> None:
    damage = damage_of(tmp_path, HEADER[:15])
    assert damage is not None and (damage.kind, damage.at_byte) == ("truncated", 15)


def test_a_last_message_one_byte_short_is_truncated_at_its_start(tmp_path) -> None:
    start = len(HEADER + flag_bits() + SUBSCRIBE + SAMPLE)
    damage = damage_of(tmp_path, (HEADER + flag_bits() + SUBSCRIBE + SAMPLE + SAMPLE)[:-1])
    assert damage is not None and (damage.kind, damage.at_byte) == ("truncated", start)


@pytest.mark.parametrize(
    ("bad", "detail"),
    [
        (message(b"I", b""), "empty 'I' message"),
        (message(b"O", b"\x01"), "'O' message of 1 bytes (it has 2)"),
        (message(b"R", b"\x07\x00\x00"), "'R' message of 3 bytes (it has 2)"),
        (
            message(b"D", (7).to_bytes(2, "little") + bytes(7)),
            "data message of msg_id 7 of 9 bytes (its others: 10)",
        ),
    ],
    ids=["empty", "short-dropout", "long-unsubscribe", "short-sample"],
)
def test_an_impossible_message_header_is_corrupt_where_it_stands(tmp_path, bad, detail) -> None:
    start = len(HEADER + flag_bits() + SUBSCRIBE + SAMPLE)
    damage = damage_of(tmp_path, HEADER + flag_bits() + SUBSCRIBE + SAMPLE + bad + SAMPLE)
    assert damage is not None and (damage.kind, damage.at_byte, damage.detail) == (
        "corrupt", start, detail,
    )  # fmt: skip


def test_an_empty_message_ending_the_file_is_corrupt_not_cut(tmp_path) -> None:
    """Its header is whole and says 0 bytes: no cut explains it."""
    start = len(HEADER + flag_bits() + SUBSCRIBE)
    damage = damage_of(tmp_path, HEADER + flag_bits() + SUBSCRIBE + message(b"D", b""))
    assert damage is not None and (damage.kind, damage.at_byte) == ("corrupt", start)


def test_appended_data_may_be_empty_but_its_offsets_must_be_in_order(tmp_path) -> None:
    body = SUBSCRIBE + SAMPLE + SAMPLE
    size = len(HEADER + flag_bits() + body)
    at_end = HEADER + flag_bits(incompat0=1, offsets=(size,)) + body
    assert damage_of(tmp_path, at_end) is None  # the crash report was never written
    first, second = len(HEADER + flag_bits() + SUBSCRIBE), size - len(SAMPLE)
    swapped = HEADER + flag_bits(incompat0=1, offsets=(second, first)) + body
    damage = damage_of(tmp_path, swapped)
    assert damage is not None and damage.kind == "corrupt" and "out of order" in damage.detail


def test_appended_offsets_count_only_with_the_incompat_data_appended_bit(tmp_path) -> None:
    """The same bit in the compat flags, or a flag-bits message too short to hold offsets,
    says nothing about appended data: bytes where offsets would be are not read as such."""
    body = SUBSCRIBE + SAMPLE
    compat_only = HEADER + flag_bits(compat0=1, offsets=(1 << 40,)) + body
    assert damage_of(tmp_path, compat_only) is None
    short_flags = message(b"B", bytes(8) + b"\x01" + bytes(7))  # no appended_offsets field
    assert damage_of(tmp_path, HEADER + short_flags + message(b"I", b"\xff" * 30)) is None


def test_older_data_read_after_the_damage_is_left_out_not_interpolated(tmp_path) -> None:
    """A block of older samples after the damage would give the rows before it other times'
    attitude, thrust and command; the log is its newer half, row for row, and says so."""
    path, _ = stale_copy(tmp_path)
    whole, stale = read_ulog(FIXTURES / "quad_posctl_v1_15.ulg"), read_ulog(path)
    first = int(np.argmin(np.abs(whole.columns["pos_n_m"] - stale.columns["pos_n_m"][0])))
    rows = slice(first, first + stale.n_rows)
    assert 300 < stale.n_rows < whole.n_rows - first + 1
    for name, values in stale.columns.items():
        if name != "t_s" and values.dtype.kind == "f":
            np.testing.assert_array_equal(values, whole.columns[name][rows], err_msg=name)
    assert stale.metadata["samples_out_of_time_order"] > 1000
    assert stale.metadata["duration_s"] < 0.6 * whole.metadata["duration_s"]
    note = damage_note(stale)
    assert note is not None and "\n" not in note
    assert "samples out of time order (older than the data before them" in note
    assert "were left out" in note
    summary = summarise_ulog(path)
    assert min(summary["rates_hz"].values()) > 0 and summary["duration_s"] < 40.0


def test_a_zero_header_timestamp_does_not_stretch_the_log_to_the_boot(tmp_path) -> None:
    """A log whose file header records 0 (a v1.17 flight logged from 408.9 s after boot read as
    504 s long) lasts as long as its data."""
    data = bytearray((FIXTURES / "quad_posctl_v1_15.ulg").read_bytes())
    data[8:16] = bytes(8)  # the header's timestamp [us]
    path = tmp_path / "zero_header.ulg"
    path.write_bytes(bytes(data))
    whole = read_ulog(FIXTURES / "quad_posctl_v1_15.ulg")
    zeroed = read_ulog(path)
    assert abs(zeroed.metadata["duration_s"] - whole.metadata["duration_s"]) < 0.5
    summary = summarise_ulog(path)
    assert summary["duration_s"] < 80.0 and summary["modes"][0][1] < 1.0


def test_convert_and_config_from_log_of_a_damaged_ulog_say_it_is_damaged(tmp_path, capsys):
    """diagnose and fit-gp warned of a damaged log; convert and config-from-log wrote their
    output without a word."""
    path, offset = corrupt_copy(tmp_path, "type")
    csv, toml = tmp_path / "damaged.csv", tmp_path / "damaged.toml"
    assert flightlog_cli.main(["convert", str(path), "--out", str(csv)]) == 0
    err = capsys.readouterr().err
    assert f"flightlog: warning: damaged.ulg is corrupt at byte {offset}" in err
    assert vehicle_sim_cli.main(["config-from-log", str(path), "--out", str(toml)]) == 0
    err = capsys.readouterr().err
    assert f"from the log: damaged.ulg is corrupt at byte {offset}" in err
    assert f"#   damaged.ulg is corrupt at byte {offset}" in toml.read_text()


def test_a_bit_flipped_in_the_last_local_position_time_does_not_stretch_the_log(tmp_path):
    """The real POSCTL flight with bit 40 of its last vehicle_local_position timestamp flipped
    (ULog has no checksum): that sample is left out and said, and the log keeps its length;
    it read as 12.7 days long."""
    from tests.flightlog.ulog_damage import POSCTL, message_headers

    data = bytearray(POSCTL.read_bytes())
    headers = message_headers(bytes(data))
    # 'A' payload: multi_id (1 byte), msg_id (2), name; 'D' payload: msg_id (2), then the
    # topic's fields, its timestamp (uint64, little-endian) first
    (msg_id,) = (
        data[o + 4 : o + 6]
        for o, size, kind in headers
        if kind == "A"
        and data[o + 6 : o + 3 + size] == b"vehicle_local_position"
        and data[o + 3] == 0
    )
    last = [o for o, _, kind in headers if kind == "D" and data[o + 3 : o + 5] == msg_id][-1]
    data[last + 5 + 5] ^= 0x01  # the timestamp's byte 5: bit 40
    path = tmp_path / "flipped.ulg"
    path.write_bytes(bytes(data))
    whole, flipped = read_ulog(POSCTL), read_ulog(path)
    assert flipped.metadata["samples_out_of_time_order"] == 1
    assert flipped.metadata["duration_s"] == pytest.approx(whole.metadata["duration_s"], abs=0.2)
    assert "1 samples out of time order" in (damage_note(flipped) or "")
