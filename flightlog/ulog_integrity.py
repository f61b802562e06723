"""Is a ULog file whole, cut short, or damaged? Found by walking its message headers.

ULog ([ULog-format]): a 16-byte file header, then messages of (uint16 size, uint8 type, size
bytes). Two faults leave a file pyulog still reads in part, and they mean different things:

- **truncated**: every message header is valid and the last message runs past the end of the
  file: logging stopped mid-message (a crash, a power loss). What is before is sound.
- **corrupt**: a message header before the end is invalid (an unknown type, a data message of
  a topic never subscribed or of another size than that topic's earlier ones): bytes were
  changed (a failing SD card, a broken copy), the file was not merely cut. What follows may be
  lost or skipped (pyulog resynchronises on the next sync marker, if the log has any).

Data appended later (the flag-bits message's DATA_APPENDED bit and ``appended_offsets``: PX4's
hardfault log, written after a crash at the end of the log that crash cut) starts a new run of
messages at each offset; a message that runs past the next offset is the cut one (truncated),
as pyulog reads it too ([ULog-format] "Flag Bits Message").

A flipped bit inside a message's payload changes no header and cannot be seen: ULog carries no
checksum.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

FILE_HEADER_BYTES = 16
MESSAGE_HEADER_BYTES = 3  # uint16 size, uint8 type
MESSAGE_TYPES = frozenset(b"BFIMPQARDLCSO")  # [ULog-format] "Data Section" message types
SYNC_MAGIC = bytes([0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12])
FIXED_SIZES = {ord("S"): len(SYNC_MAGIC), ord("O"): 2, ord("R"): 2}  # payload bytes
FLAG_BITS_BYTES = 40  # compat_flags[8], incompat_flags[8], appended_offsets: uint64[3]
DATA_APPENDED = 0x01  # incompat_flags[0] bit: appended_offsets hold data


@dataclass(frozen=True)
class ULogDamage:
    """Where a ULog file stops being sound.

    Attributes:
        kind: "truncated" (the file ends mid-message) or "corrupt" (an invalid message header
            before the end).
        at_byte: file offset of the incomplete last message or of the invalid header.
        file_bytes: the file's size.
        detail: what was invalid, for a corrupt file ("" for a truncated one).
    """

    kind: Literal["truncated", "corrupt"]
    at_byte: int
    file_bytes: int
    detail: str = ""


def find_damage(path: str | Path) -> ULogDamage | None:
    """The first fault in the ULog at ``path`` (see the module docstring), or None if every
    message header is valid and the last message of each run (the log, then any appended
    data) ends where the next run starts or at the end of the file."""
    data = Path(path).read_bytes()
    size = len(data)
    if size < FILE_HEADER_BYTES:
        return ULogDamage("truncated", size, size)
    appended = _appended_offsets(data)
    bogus = [o for o in appended if not FILE_HEADER_BYTES < o <= size]
    if bogus or appended != sorted(appended):
        detail = f"appended-data offsets {appended} outside the file or out of order"
        return ULogDamage("corrupt", FILE_HEADER_BYTES, size, detail)
    subscribed: set[int] = set()
    data_sizes: dict[int, int] = {}
    offset = FILE_HEADER_BYTES
    for end in [*appended, size]:
        while offset < end:
            if offset + MESSAGE_HEADER_BYTES > end:
                return ULogDamage("truncated", offset, size)
            length = int.from_bytes(data[offset : offset + 2], "little")
            kind = data[offset + 2]
            stop = min(offset + MESSAGE_HEADER_BYTES + length, end)
            payload = data[offset + MESSAGE_HEADER_BYTES : stop]
            invalid = _invalid_header(kind, length, payload, subscribed, data_sizes)
            if invalid:
                return ULogDamage("corrupt", offset, size, invalid)
            if len(payload) < length:
                return ULogDamage("truncated", offset, size)
            offset += MESSAGE_HEADER_BYTES + length
        offset = end
    return None


def _appended_offsets(data: bytes) -> list[int]:
    """The non-zero ``appended_offsets`` of the flag-bits message (the first message) when its
    DATA_APPENDED bit is set, else []."""
    start = FILE_HEADER_BYTES + MESSAGE_HEADER_BYTES
    length = int.from_bytes(data[FILE_HEADER_BYTES : FILE_HEADER_BYTES + 2], "little")
    if data[FILE_HEADER_BYTES + 2 : start] != b"B" or length < FLAG_BITS_BYTES:
        return []
    if len(data) < start + FLAG_BITS_BYTES or not data[start + 8] & DATA_APPENDED:
        return []
    offsets = (
        int.from_bytes(data[start + 16 + 8 * i : start + 24 + 8 * i], "little") for i in range(3)
    )
    return [o for o in offsets if o]


def _invalid_header(
    kind: int,
    length: int,
    payload: bytes,
    subscribed: set[int],
    data_sizes: dict[int, int],
) -> str:
    """Why a message header of type ``kind`` and ``length`` payload bytes cannot be valid here
    ("" if it can); keeps the subscriptions and each topic's data size seen so far.
    ``payload`` may be short (the file ends): only what it holds is checked."""
    if kind not in MESSAGE_TYPES:
        return f"unknown message type {kind:#04x}"
    if length == 0:
        return f"empty {chr(kind)!r} message"
    if kind in FIXED_SIZES and length != FIXED_SIZES[kind]:
        return f"{chr(kind)!r} message of {length} bytes (it has {FIXED_SIZES[kind]})"
    if kind == ord("A") and len(payload) >= 3:
        subscribed.add(int.from_bytes(payload[1:3], "little"))
    if kind == ord("D") and len(payload) >= 2:
        msg_id = int.from_bytes(payload[0:2], "little")
        if msg_id not in subscribed:
            return f"data message of msg_id {msg_id}, never subscribed"
        expected = data_sizes.setdefault(msg_id, length)
        if length != expected:
            return f"data message of msg_id {msg_id} of {length} bytes (its others: {expected})"
    return ""
