"""STATUSTEXT: long texts chunked with id/chunk_seq (never cut), repeats limited per kind."""

from __future__ import annotations

import pytest

from vehicle_sim.mavlink.statustext import NoticeLimiter, notice_kind, statustext_chunks


def reassemble(msgs) -> str:
    return "".join(m.text if isinstance(m.text, str) else m.text.decode() for m in msgs)


def test_a_short_text_is_one_message_without_chunk_id() -> None:
    (msg,) = statustext_chunks(4, "Offboard denied: no setpoint stream", 7)
    assert msg.id == 0 and msg.chunk_seq == 0


@pytest.mark.parametrize("length", [51, 100, 137])
def test_a_long_text_is_chunked_and_reassembles_whole(length: int) -> None:
    text = "".join(chr(ord("a") + i % 26) for i in range(length))
    msgs = statustext_chunks(2, text, 9)
    assert [m.chunk_seq for m in msgs] == list(range(len(msgs)))
    assert {m.id for m in msgs} == {9}
    assert reassemble(msgs).rstrip("\x00") == text
    assert len(msgs) == length // 50 + 1  # an exact multiple gets an empty closing chunk


def test_the_kind_blanks_names_and_numbers() -> None:
    a = notice_kind("Param MC_ROLLRATE_P: type INT32 refused, it is REAL32; not applied")
    b = notice_kind("Param MPC_XY_P: type UINT8 refused, it is REAL32; not applied")
    assert a == b
    assert notice_kind("Takeoff denied: not armed") != notice_kind("Land denied: not armed")


def test_the_limiter_passes_one_per_kind_per_period() -> None:
    limiter = NoticeLimiter(repeat_s=1.0, memory=4)
    assert limiter.allow("Param A_B_C: value 3 out of range", 0.0)
    assert not limiter.allow("Param X_Y_Z: value 7 out of range", 0.5)
    assert limiter.allow("Land denied: not armed", 0.5)
    assert limiter.allow("Param X_Y_Z: value 7 out of range", 1.2)
