"""STATUSTEXT as PX4 sends it: long texts chunked, repeats limited per kind of message.

MAVLink 2's STATUSTEXT carries 50 characters; a longer text goes out in chunks that share a
non-zero ``id`` and count ``chunk_seq`` from 0, the last one NUL-terminated (an exact multiple
of 50 gets an empty closing chunk) ([MAVLink] STATUSTEXT). Rate limiting is per *kind* of
message, not per text: "Param MC_ROLLRATE_P: type INT32 refused" and the same refusal for
another parameter are one kind, so a client hammering every parameter cannot flood the link.
"""

from __future__ import annotations

import math
import re

from pymavlink.dialects.v20 import common as mavlink2

TEXT_LEN = 50  # characters in one STATUSTEXT
CHUNK_ID_MAX = 65535

_FACTORY = mavlink2.MAVLink(None)
# Upper-case identifiers (parameter and mode names) and numbers vary within one kind.
_VARYING = re.compile(r"\b[A-Z][A-Z0-9_]{2,}\b|[-+]?\d+(\.\d+)?([eE][-+]?\d+)?")


def notice_kind(text: str) -> str:
    """The text with its names and numbers blanked: the key repeats are limited by."""
    return _VARYING.sub("#", text)


def statustext_chunks(severity: int, text: str, chunk_id: int) -> list[mavlink2.MAVLink_message]:
    """The STATUSTEXT messages carrying ``text``: one if it fits, else chunks with ``chunk_id``
    (1..65535) and ``chunk_seq`` 0, 1, ..."""
    raw = text.encode("ascii", "replace")
    if len(raw) <= TEXT_LEN:
        return [_FACTORY.statustext_encode(severity=severity, text=raw, id=0, chunk_seq=0)]
    if not 1 <= chunk_id <= CHUNK_ID_MAX:
        raise ValueError(f"chunk_id must be within 1..{CHUNK_ID_MAX}, got {chunk_id}")
    pieces = [raw[i : i + TEXT_LEN] for i in range(0, len(raw), TEXT_LEN)]
    if len(pieces[-1]) == TEXT_LEN:
        pieces.append(b"")  # the closing NUL of an exact multiple of 50
    return [
        _FACTORY.statustext_encode(severity=severity, text=piece, id=chunk_id, chunk_seq=seq)
        for seq, piece in enumerate(pieces)
    ]


class NoticeLimiter:
    """At most one notice of a kind per ``repeat_s`` seconds; remembers up to ``memory`` kinds."""

    def __init__(self, repeat_s: float, memory: int) -> None:
        self._repeat_s = repeat_s
        self._memory = memory
        self._sent_s: dict[str, float] = {}

    def allow(self, text: str, now_s: float) -> bool:
        kind = notice_kind(text)
        if now_s - self._sent_s.get(kind, -math.inf) < self._repeat_s:
            return False
        if len(self._sent_s) >= self._memory:  # hostile input can still make many kinds
            self._sent_s = {k: s for k, s in self._sent_s.items() if now_s - s < self._repeat_s}
        self._sent_s[kind] = now_s
        return True
