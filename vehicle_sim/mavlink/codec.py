"""MAVLink 2 framing for one link: datagram -> messages, message -> bytes (with signing).

Uses pymavlink's generated ``common`` dialect directly (MAVLink 2 framing, v1 frames are decoded
too). Each UDP datagram is parsed on its own, so a truncated datagram never corrupts the next
one; whatever cannot be decoded is counted, never raised.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.signing import UNSIGNED_ALLOWED_MSG_IDS, signing_timestamp

SYSTEM_ID = 1
COMPONENT_ID = 1


@dataclass(frozen=True)
class DecodedDatagram:
    """What one datagram held.

    Attributes:
        messages: the well-formed messages, in order (known ids only).
        bad_frames: frames or byte runs that failed (bad prefix, length, CRC, unknown id).
        truncated: True when the datagram ended inside a frame.
        signing_rejected: frames refused by the signing policy (unsigned or bad signature).
    """

    messages: tuple[mavlink2.MAVLink_message, ...]
    bad_frames: int
    truncated: bool
    signing_rejected: int


class LinkCodec:
    """Encoder/decoder of one link: its sequence numbers and, optionally, its signing key."""

    def __init__(self, signing_key: bytes | None = None, link_id: int = 0) -> None:
        self._encoder = mavlink2.MAVLink(None, srcSystem=SYSTEM_ID, srcComponent=COMPONENT_ID)
        self._signing = self._encoder.signing
        self._signing_rejected = 0
        if signing_key is not None:
            if len(signing_key) != 32:
                raise ValueError(f"signing key must be 32 bytes, got {len(signing_key)}")
            self._signing.secret_key = signing_key
            self._signing.link_id = link_id
            self._signing.sign_outgoing = True
            self._signing.timestamp = signing_timestamp(time.time())
            self._signing.allow_unsigned_callback = self._allow_unsigned

    @property
    def signed(self) -> bool:
        return self._signing.secret_key is not None

    def _allow_unsigned(self, _mav: mavlink2.MAVLink, msg_id: int) -> bool:
        allowed = msg_id in UNSIGNED_ALLOWED_MSG_IDS
        if not allowed:
            self._signing_rejected += 1
        return allowed

    def encode(self, msg: mavlink2.MAVLink_message) -> bytes:
        """Frame a message as MAVLink 2 from system 1 component 1 (signed on a signed link)."""
        if self.signed:
            self._signing.timestamp = max(self._signing.timestamp, signing_timestamp(time.time()))
        data = bytes(msg.pack(self._encoder))
        self._encoder.seq = (self._encoder.seq + 1) % 256
        return data

    def decode(self, datagram: bytes) -> DecodedDatagram:
        """Parse one datagram; never raises."""
        parser = mavlink2.MAVLink(None, srcSystem=SYSTEM_ID, srcComponent=COMPONENT_ID)
        parser.robust_parsing = True
        parser.signing = self._signing
        rejected_before = self._signing_rejected
        messages: list[mavlink2.MAVLink_message] = []
        bad = 0
        try:
            found = parser.parse_buffer(datagram) or []
        except Exception:  # pymavlink raises more than MAVError on hostile input
            return DecodedDatagram((), 1, False, self._signing_rejected - rejected_before)
        for msg in found:
            if isinstance(msg, (mavlink2.MAVLink_bad_data, mavlink2.MAVLink_unknown)):
                bad += 1
            else:
                messages.append(msg)
        rejected = self._signing_rejected - rejected_before
        return DecodedDatagram(
            tuple(messages), max(0, bad - rejected), parser.buf_len() > 0, rejected
        )
