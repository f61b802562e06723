"""Hostile input: garbage, truncated and mutated datagrams, wrong targets, unusable setpoints.

Everything is rejected and counted, PX4-style STATUSTEXTs announce rejected setpoints, and the
simulated vehicle keeps flying.
"""

from __future__ import annotations

import math
import random
import socket

import numpy as np
import pytest
from mavlink_test_client import (
    LOOPBACK,
    MAV_RESULT_ACCEPTED,
    MAV_RESULT_TEMPORARILY_REJECTED,
    MAV_RESULT_UNSUPPORTED,
    wait_until,
)
from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim import FlightMode

MASK_VELOCITY = 0b110111000111


def frame(msg: mavlink2.MAVLink_message, source_system: int = 245) -> bytes:
    return bytes(msg.pack(mavlink2.MAVLink(None, srcSystem=source_system, srcComponent=190)))


def setpoint(
    vel=(0.0, 0.0, 0.0),
    frame_id: int = 1,
    mask: int = MASK_VELOCITY,
    target_system: int = 1,
    yaw_rate: float = 0.0,
):
    return mavlink2.MAVLink_set_position_target_local_ned_message(
        0, target_system, 1, frame_id, mask, 0, 0, 0, *vel, 0, 0, 0, 0, yaw_rate
    )


def is_finite_state(state) -> bool:
    arrays = (state.pos_ned_m, state.vel_ned_mps, state.q_wxyz, state.rates_frd_radps)
    return all(np.all(np.isfinite(a)) for a in arrays) and math.isfinite(state.battery_v)


@pytest.mark.parametrize(
    ("vel", "frame_id", "yaw_rate", "text"),
    [
        ((math.nan, 0.0, 0.0), 1, 0.0, "invalid velocity"),
        ((1e9, 0.0, 0.0), 1, 0.0, "invalid velocity"),
        ((0.0, 0.0, 0.0), 8, math.inf, "invalid yaw rate"),
        ((1.0, 0.0, 0.0), 7, 0.0, "frame 7 unsupported"),
        ((1.0, 0.0, 0.0), 0, 0.0, "frame 0 unsupported"),
    ],
)
def test_unusable_setpoints_are_rejected_announced_and_no_proof_of_life(
    endpoint, client, vel, frame_id, yaw_rate, text
):
    for _ in range(5):
        client.send_velocity(vel, frame=frame_id, yaw_rate_radps=yaw_rate)
    notice = client.recv("STATUSTEXT", 3.0, lambda m: text in m.text)
    assert notice is not None and notice.severity == 4
    wait_until(lambda: endpoint.stats.setpoints_rejected == 5, 3.0, "5 rejections counted")
    assert endpoint.stats.setpoints_accepted == 0
    assert endpoint.stats.notices_suppressed >= 1  # one STATUSTEXT for a burst, not five
    assert client.command(400, 1).result == MAV_RESULT_ACCEPTED
    assert client.command(176, 1, 6, 0).result == MAV_RESULT_TEMPORARILY_REJECTED


def test_attitude_setpoints_are_answered_not_dropped_in_silence(endpoint, client):
    """MAVSDK's offboard_attitude example sends what the simulator does not fly: it is told
    why (STATUSTEXT), and the attitude stream is no proof of life. (MANUAL_CONTROL is flown:
    test_mavlink_manual_control.py.)"""
    for _ in range(5):
        client.mav.set_attitude_target_send(0, 1, 1, 0b0000_0111, [1, 0, 0, 0], 0, 0, 0, 0.6)
    notice = client.recv("STATUSTEXT", 3.0, lambda m: "attitude setpoints" in m.text)
    assert notice is not None and notice.severity == 4
    assert client.command(400, 1).result == MAV_RESULT_ACCEPTED
    assert client.command(176, 1, 6, 0).result == MAV_RESULT_TEMPORARILY_REJECTED
    assert endpoint.stats.handler_errors == 0


def test_setpoints_for_another_system_are_ignored(endpoint, client):
    client.send_velocity((1.0, 0.0, 0.0), target_system=7)
    wait_until(lambda: endpoint.stats.wrong_target == 1, 3.0, "wrong target counted")
    assert endpoint.stats.setpoints_accepted == 0


def test_damaged_datagrams_are_counted_and_the_endpoint_still_answers(endpoint, client):
    good = frame(mavlink2.MAVLink_ping_message(1, 2, 0, 0))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.sendto(b"\x00" * 40, (LOOPBACK, endpoint.local_port))
        sock.sendto(good[:-4], (LOOPBACK, endpoint.local_port))
        sock.sendto(good[:-1] + bytes([good[-1] ^ 0x55]), (LOOPBACK, endpoint.local_port))
        sock.sendto(b"", (LOOPBACK, endpoint.local_port))
    wait_until(lambda: endpoint.stats.datagrams_received >= 5, 3.0, "datagrams to arrive")
    stats = endpoint.stats
    assert stats.garbage_datagrams == 4
    assert stats.truncated_datagrams == 1 and stats.bad_frames >= 2
    assert client.command(31999).result == MAV_RESULT_UNSUPPORTED


def hostile_packets(rng: random.Random, n: int) -> list[bytes]:
    """Seeded mix of random bytes, mutated valid frames and well-formed hostile messages."""
    templates = [
        frame(mavlink2.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3)),
        frame(setpoint((math.nan, 0.0, 0.0))),
        frame(setpoint((1e9, -1e9, 0.0))),
        frame(setpoint((1.0, 0.0, 0.0), frame_id=9)),
        frame(mavlink2.MAVLink_command_long_message(1, 1, 31999, 0, 1, 2, 3, 4, 5, 6, 7)),
        frame(mavlink2.MAVLink_ping_message(5, 6, 0, 0)),
        frame(mavlink2.MAVLink_param_request_read_message(1, 1, b"NO_SUCH_PARAM", -1)),
    ]
    packets = []
    for i in range(n):
        kind = i % 5
        if kind == 0:  # random bytes, sometimes with a MAVLink 2 start byte
            data = bytes(rng.getrandbits(8) for _ in range(rng.randint(0, 280)))
            packets.append((b"\xfd" + data) if rng.random() < 0.5 else data)
        elif kind in (1, 2):  # a valid frame, damaged
            data = bytearray(rng.choice(templates))
            for _ in range(rng.randint(1, 4)):
                op = rng.random()
                pos = rng.randrange(len(data))
                if op < 0.5:
                    data[pos] ^= 1 << rng.randrange(8)
                elif op < 0.75:
                    del data[pos:]
                    data = data or bytearray(b"\xfd")
                else:
                    data[pos:pos] = bytes([rng.getrandbits(8)])
            packets.append(bytes(data))
        elif kind == 3:  # well-formed, for another system, from random sources
            target = rng.randint(2, 255)
            msg = rng.choice(
                [
                    mavlink2.MAVLink_command_long_message(
                        target, 1, 400, 0, 0, 21196, 0, 0, 0, 0, 0
                    ),
                    mavlink2.MAVLink_command_int_message(
                        target, 1, 0, 21, 0, 0, 0, 0, 0, 0, 0, 0, 0
                    ),
                    setpoint((5.0, 5.0, 5.0), target_system=target),
                    mavlink2.MAVLink_param_set_message(target, 1, b"COM_OF_LOSS_T", 0.0, 9),
                ]
            )
            packets.append(frame(msg, source_system=rng.randint(1, 255)))
        else:  # well-formed, for us, unusable
            vel = tuple(rng.choice([math.nan, math.inf, -1e9, 1e9, 0.5]) for _ in range(3))
            frame_id = rng.choice([0, 1, 5, 7, 8, 9, 21])
            msg = setpoint(vel, frame_id=frame_id, yaw_rate=rng.choice([math.nan, 1e9, 0.0]))
            packets.append(frame(msg) + (frame(msg)[:7] if rng.random() < 0.3 else b""))
    return packets


@pytest.mark.slow
def test_ten_thousand_hostile_packets_leave_the_vehicle_flying(endpoint, client):
    assert client.command(400, 1).result == MAV_RESULT_ACCEPTED
    assert client.command(22, *[math.nan] * 7).result == MAV_RESULT_ACCEPTED
    wait_until(
        lambda: endpoint.state.mode == FlightMode.HOLD and -endpoint.state.pos_ned_m[2] > 2.3,
        15.0,
        "takeoff",
    )
    wait_until(lambda: np.linalg.norm(endpoint.state.vel_ned_mps) < 0.05, 10.0, "settled hover")
    hover_m = endpoint.state.pos_ned_m.copy()
    before = endpoint.stats

    packets = hostile_packets(random.Random(2024), 10_000)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        for start in range(0, len(packets), 200):
            for data in packets[start : start + 200]:
                sock.sendto(data, (LOOPBACK, endpoint.local_port))
            sent = start + min(200, len(packets) - start)
            wait_until(
                lambda n=sent: endpoint.stats.datagrams_received - before.datagrams_received >= n,
                10.0,
                "the endpoint to read the packets",
            )

    pong = None
    for _ in range(3):
        client.mav.ping_send(42, 99, 0, 0)
        pong = client.recv("PING", 1.0, lambda m: m.seq == 99)
        if pong is not None:
            break
    assert pong is not None, "no PING reply after the flood"
    assert client.command(31999).result == MAV_RESULT_UNSUPPORTED
    assert endpoint.running
    state = endpoint.state
    assert is_finite_state(state)
    assert state.armed and state.mode == FlightMode.HOLD
    assert np.linalg.norm(state.pos_ned_m - hover_m) < 0.3

    stats = endpoint.stats
    assert stats.datagrams_received - before.datagrams_received >= 10_000
    for name in (
        "garbage_datagrams",
        "bad_frames",
        "truncated_datagrams",
        "wrong_target",
        "setpoints_rejected",
    ):
        assert getattr(stats, name) > getattr(before, name), name
    assert stats.handler_errors == 0
