"""Damaged copies of a real ULog fixture, for the tests of truncated and corrupt files."""

from __future__ import annotations

from pathlib import Path

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
POSCTL = FIXTURES / "quad_posctl_v1_15.ulg"


def message_headers(data: bytes) -> list[tuple[int, int, str]]:
    """(offset, payload size, type) of each message of a sound ULog, walked naively."""
    headers, offset = [], 16
    while offset < len(data):
        size = int.from_bytes(data[offset : offset + 2], "little")
        headers.append((offset, size, chr(data[offset + 2])))
        offset += 3 + size
    return headers


def corrupt_copy(tmp_path: Path, how: str) -> tuple[Path, int]:
    """quad_posctl_v1_15.ulg with one data message header damaged; the file and its offset.

    "size": near the end, the size set to 0xFFFF, which runs past the end of the file (a walk
    by sizes alone takes it for a cut); "type": mid-file, the type byte's bits flipped."""
    data = bytearray(POSCTL.read_bytes())
    data_messages = [h for h in message_headers(bytes(data)) if h[2] == "D"]
    if how == "size":
        offset = next(h[0] for h in data_messages if h[0] > len(data) - 30_000)
        data[offset : offset + 2] = b"\xff\xff"
    else:
        offset = next(h[0] for h in data_messages if h[0] > len(data) // 2)
        data[offset + 2] ^= 0xFF
    path = tmp_path / "damaged.ulg"
    path.write_bytes(bytes(data))
    return path, offset


def hardfault_copy(tmp_path: Path) -> tuple[Path, int]:
    """quad_posctl_v1_15.ulg as PX4 leaves it after a hardfault: logging stopped mid-message
    (the last data message 20 kB before the end is cut in two), then the hardfault report
    appended as an info-multiple message, the flag bits' DATA_APPENDED bit set and the first
    appended offset at the cut ([ULog-format] "Flag Bits Message"); the file and the offset of
    the cut message."""
    whole = POSCTL.read_bytes()
    assert whole[18:19] == b"B", "the fixture starts with a flag-bits message"
    cut_message = next(h for h in message_headers(whole) if h[0] > len(whole) - 20_000)
    cut = cut_message[0] + 3 + cut_message[1] // 2
    key = b"char[24] hardfault_plain"
    report = bytes([0, len(key)]) + key + b"hardfault: HardFault_Handler".ljust(24)[:24]
    data = bytearray(whole[:cut] + len(report).to_bytes(2, "little") + b"M" + report)
    flags = 16 + 3  # the flag-bits payload: compat[8], incompat[8], appended_offsets uint64[3]
    data[flags + 8] |= 0x01
    data[flags + 16 : flags + 24] = cut.to_bytes(8, "little")
    path = tmp_path / "hardfault.ulg"
    path.write_bytes(bytes(data))
    return path, cut_message[0]


SYNC_MAGIC = bytes([0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12])


def stale_copy(tmp_path: Path) -> tuple[Path, int]:
    """quad_posctl_v1_15.ulg as a failing SD card can leave it (a real v1.17 log went from
    5519.8 s back to 5402.6 s after its damage): the second half of its data, then a message of
    an unknown type, a sync message (pyulog resynchronises on it) and the first half, older
    data read as if it followed; the file and the offset where the second half starts."""
    whole = POSCTL.read_bytes()
    data_messages = [h for h in message_headers(whole) if h[2] == "D"]
    first = data_messages[0][0]
    half = next(h[0] for h in data_messages if h[0] > (first + len(whole)) // 2)
    damaged = (4).to_bytes(2, "little") + b"\x00" + bytes(4)
    sync = len(SYNC_MAGIC).to_bytes(2, "little") + b"S" + SYNC_MAGIC
    path = tmp_path / "stale.ulg"
    path.write_bytes(whole[:first] + whole[half:] + damaged + sync + whole[first:half])
    return path, half
