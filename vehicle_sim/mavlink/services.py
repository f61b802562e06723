"""Small request/response services PX4 answers: PING, TIMESYNC, FTP NAK, the (empty) log list.

Pure builders of the reply message (or None when the message needs no reply).
"""

from __future__ import annotations

import struct

from pymavlink.dialects.v20 import common as mavlink2

_FACTORY = mavlink2.MAVLink(None)

FTP_OPCODE_NAK = 129
FTP_ERR_UNKNOWN_COMMAND = 7
FTP_ERR_FILE_NOT_FOUND = 10
FTP_OPENING_OPCODES = frozenset({3, 4, 6, 11, 14})  # list dir, open RO/create/WO, CRC32
FTP_PAYLOAD_LEN = 251


def ping_reply(msg: mavlink2.MAVLink_ping_message) -> mavlink2.MAVLink_message | None:
    """Echo a PING request (target 0/0) back to its sender."""
    if msg.target_system != 0 or msg.target_component != 0:
        return None
    return _FACTORY.ping_encode(
        time_usec=msg.time_usec,
        seq=msg.seq,
        target_system=msg.get_srcSystem(),
        target_component=msg.get_srcComponent(),
    )


def timesync_reply(
    msg: mavlink2.MAVLink_timesync_message, now_ns: int
) -> mavlink2.MAVLink_message | None:
    """Answer a TIMESYNC request (tc1 == 0) with our clock [ns]."""
    if msg.tc1 != 0:
        return None
    return _FACTORY.timesync_encode(tc1=now_ns, ts1=msg.ts1)


def ftp_nak_reply(msg: mavlink2.MAVLink_file_transfer_protocol_message) -> mavlink2.MAVLink_message:
    """NAK any MAVLink FTP request: no file system here."""
    payload = bytes(msg.payload) if not isinstance(msg.payload, bytes) else msg.payload
    payload = payload.ljust(FTP_PAYLOAD_LEN, b"\x00")
    seq, session, opcode = struct.unpack_from("<HBB", payload)
    error = FTP_ERR_FILE_NOT_FOUND if opcode in FTP_OPENING_OPCODES else FTP_ERR_UNKNOWN_COMMAND
    header = struct.pack(
        "<HBBBBBBI", (seq + 1) & 0xFFFF, session, FTP_OPCODE_NAK, 1, opcode, 0, 0, 0
    )
    reply = (header + bytes([error])).ljust(FTP_PAYLOAD_LEN, b"\x00")
    return _FACTORY.file_transfer_protocol_encode(
        target_network=0,
        target_system=msg.get_srcSystem(),
        target_component=msg.get_srcComponent(),
        payload=list(reply),
    )


def empty_log_list_reply(
    msg: mavlink2.MAVLink_log_request_list_message,
) -> mavlink2.MAVLink_message:
    """Answer LOG_REQUEST_LIST as PX4 does with no log on its SD card: one LOG_ENTRY with
    ``num_logs`` 0 (MAVSDK's log_files then reports "no logfiles" at once instead of waiting
    for a timeout). The onboard log (``vehicle-sim --log``) is a CSV file, not served here."""
    del msg  # every request gets the same answer
    return _FACTORY.log_entry_encode(id=0, num_logs=0, last_log_num=0, time_utc=0, size=0)
