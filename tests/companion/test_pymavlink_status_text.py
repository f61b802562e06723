"""The pymavlink Link keeps the vehicle's texts whole, as PX4 sends them: a text longer than a
STATUSTEXT's 50 characters arrives in chunks (MAVLink 2's id and chunk_seq)."""

from __future__ import annotations

from pymavlink.dialects.v20 import common as _MAV

from companion.pymavlink_link import PymavlinkLink


def _as_received(*messages: tuple[str, dict]) -> list:
    """Messages from system 1's autopilot, packed and parsed as they come off the wire
    (MAVLink 2, which PX4 speaks and pymavlink switches to on its first such frame)."""
    sender = _MAV.MAVLink(None, srcSystem=1, srcComponent=1)
    receiver = _MAV.MAVLink(None)
    received = []
    for kind, fields in messages:
        packed = getattr(sender, f"{kind}_encode")(**fields).pack(sender)
        received.extend(receiver.parse_buffer(packed) or [])
    return received


def _heartbeat() -> tuple[str, dict]:
    fields = dict(
        type=_MAV.MAV_TYPE_QUADROTOR,
        autopilot=_MAV.MAV_AUTOPILOT_PX4,
        base_mode=0,
        custom_mode=0,
        system_status=_MAV.MAV_STATE_ACTIVE,
    )
    return "heartbeat", fields


def _text(text: str, text_id: int, seq: int) -> tuple[str, dict]:
    fields = dict(severity=_MAV.MAV_SEVERITY_CRITICAL, text=text.encode(), id=text_id)
    return "statustext", {**fields, "chunk_seq": seq}


def test_a_text_sent_in_chunks_is_kept_whole_and_a_short_one_alone() -> None:
    long = "Critical battery level, executing Return in 5 seconds\t"  # PX4 v1.13's, 54 chars
    link = PymavlinkLink("udpin://127.0.0.1:0")
    for msg in _as_received(
        _heartbeat(),
        _text(long[:50], 7, 0),
        _text(long[50:], 7, 1),
        _text("Failsafe activated\t", 8, 0),
        _text("x" * 50, 0, 0),  # exactly full, id 0: a whole text of 50
        _text("Takeoff detected", 0, 0),
    ):
        link._handle(msg)
    texts = [said.text for said in link.status_texts()]
    assert texts == [long, "Failsafe activated\t", "x" * 50, "Takeoff detected"]
