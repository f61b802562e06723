"""LinkCodec: framing round trips, hostile datagrams counted (never raised), signing policy."""

from __future__ import annotations

import hashlib
import random
import time

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.codec import LinkCodec
from vehicle_sim.mavlink.signing import (
    SigningKeyError,
    key_from_text,
    load_signing_key,
    signing_timestamp,
)

KEY = hashlib.sha256(b"test passphrase").digest()


def client(key: bytes | None = None, sign: bool = True) -> mavlink2.MAVLink:
    mav = mavlink2.MAVLink(None, srcSystem=245, srcComponent=190)
    if key is not None:
        mav.signing.secret_key = key
        mav.signing.sign_outgoing = sign
        mav.signing.timestamp = signing_timestamp(time.time())
    return mav


def command(mav: mavlink2.MAVLink) -> bytes:
    msg = mav.command_long_encode(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0)
    data = bytes(msg.pack(mav))
    mav.seq += 1
    return data


def test_encode_decode_round_trip_keeps_fields_and_source():
    codec = LinkCodec()
    msg = mavlink2.MAVLink_local_position_ned_message(1234, 1.0, -2.0, 3.5, 0.1, 0.2, -0.3)
    decoded = client().parse_buffer(codec.encode(msg))
    assert decoded is not None and len(decoded) == 1
    got = decoded[0]
    assert got.get_type() == "LOCAL_POSITION_NED"
    assert (got.get_srcSystem(), got.get_srcComponent()) == (1, 1)
    assert (got.time_boot_ms, got.x, got.y, got.z) == (1234, 1.0, -2.0, 3.5)


def test_sequence_numbers_advance_per_message():
    codec = LinkCodec()
    hb = mavlink2.MAVLink_heartbeat_message(2, 12, 1, 0, 3, 3)
    seqs = [client().parse_buffer(codec.encode(hb))[0].get_seq() for _ in range(3)]
    assert seqs == [0, 1, 2]


def test_two_frames_in_one_datagram_both_decode():
    codec = LinkCodec()
    mav = client()
    decoded = codec.decode(command(mav) + command(mav))
    assert len(decoded.messages) == 2 and decoded.bad_frames == 0 and not decoded.truncated


@pytest.mark.parametrize(
    ("mangle", "truncated"),
    [
        (lambda d: d[:-5], True),  # cut inside the frame
        (lambda d: d[:-2] + bytes([d[-2] ^ 0xFF, d[-1]]), False),  # bad CRC
        (lambda d: b"\x00\x01garbage" + d[:3], True),  # junk then a partial header
        (lambda d: bytes(200), False),  # no frame at all
    ],
)
def test_damaged_datagrams_decode_to_nothing_and_are_counted(mangle, truncated):
    decoded = LinkCodec().decode(mangle(command(client())))
    assert decoded.messages == ()
    assert decoded.bad_frames >= 1 or decoded.truncated
    assert decoded.truncated == truncated


def test_random_bytes_never_raise():
    rng = random.Random(7)
    codec = LinkCodec()
    for _ in range(2000):
        data = bytes(rng.getrandbits(8) for _ in range(rng.randint(0, 300)))
        if rng.random() < 0.5:
            data = b"\xfd" + data
        codec.decode(data)  # must not raise


def test_signed_link_rejects_unsigned_and_wrongly_signed_commands():
    codec = LinkCodec(KEY)
    unsigned = codec.decode(command(client()))
    assert unsigned.messages == () and unsigned.signing_rejected == 1
    wrong = codec.decode(command(client(hashlib.sha256(b"other").digest())))
    assert wrong.messages == () and wrong.signing_rejected == 1
    good = codec.decode(command(client(KEY)))
    assert len(good.messages) == 1 and good.signing_rejected == 0


def test_signed_link_accepts_unsigned_heartbeat_and_signs_its_output():
    codec = LinkCodec(KEY)
    mav = client()
    hb = mav.heartbeat_encode(6, 8, 0, 0, 0)
    assert len(codec.decode(bytes(hb.pack(mav))).messages) == 1
    receiver = client(KEY)
    out = receiver.parse_buffer(codec.encode(hb))
    assert out is not None and out[0]._signed


def test_key_file_formats(tmp_path):
    hex_file = tmp_path / "hex.key"
    hex_file.write_text(KEY.hex() + "\n")
    assert load_signing_key(hex_file) == KEY
    assert key_from_text("test passphrase") == KEY
    empty = tmp_path / "empty.key"
    empty.write_text("  \n")
    with pytest.raises(SigningKeyError, match="empty signing key in .*empty.key"):
        load_signing_key(empty)
    with pytest.raises(SigningKeyError, match="cannot read signing key file"):
        load_signing_key(tmp_path / "missing.key")
    binary = tmp_path / "binary.key"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(SigningKeyError, match=r"binary.key \(not UTF-8 text\); pass a text file"):
        load_signing_key(binary)
