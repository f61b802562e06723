"""The mission protocol with pymavlink: upload, download round trip, refusals, AUTO.MISSION."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mavlink_test_client import MAV_RESULT_ACCEPTED, wait_until
from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim import FlightMode
from vehicle_sim.mavlink.geodetic import GeodeticOrigin

ORIGIN = GeodeticOrigin()
REL_ALT = mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT


def item(
    seq, command, north_m=0.0, east_m=0.0, alt_m=0.0, params=(0, 0, 0, math.nan), frame=REL_ALT
):
    if north_m or east_m:
        lat, lon, _ = ORIGIN.to_global((north_m, east_m, 0.0))
        x, y = round(lat * 1e7), round(lon * 1e7)
    else:
        x = y = 0
    return mavlink2.MAVLink_mission_item_int_message(
        1, 1, seq, frame, command, 0, 1, *params, x, y, alt_m
    )


def upload(client, items):
    """Answer the endpoint's MISSION_REQUEST_INTs; returns the final MISSION_ACK."""
    client.forget()
    with client.send_lock:
        client.mav.mission_count_send(1, 1, len(items))
    for _ in range(len(items)):
        request = client.recv("MISSION_REQUEST_INT", 3.0)
        if request is None:
            break
        with client.send_lock:
            client.mav.send(items[request.seq])
    return client.recv("MISSION_ACK", 3.0)


MISSION = [
    item(0, mavlink2.MAV_CMD_NAV_TAKEOFF, alt_m=4.0),
    item(1, mavlink2.MAV_CMD_NAV_WAYPOINT, 12.0, 0.0, 4.0, (0, 1.0, 0, math.nan)),
    item(2, mavlink2.MAV_CMD_NAV_WAYPOINT, 12.0, 6.0, 4.0, (0, 1.0, 0, math.nan)),
    item(3, mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink2.MAV_FRAME_MISSION),
]


def test_upload_then_download_returns_the_same_items(endpoint, client):
    ack = upload(client, MISSION)
    assert ack is not None and ack.type == mavlink2.MAV_MISSION_ACCEPTED
    client.forget()
    with client.send_lock:
        client.mav.mission_request_list_send(1, 1)
    count = client.recv("MISSION_COUNT", 3.0)
    assert count is not None and count.count == len(MISSION)
    for sent in MISSION:
        with client.send_lock:
            client.mav.mission_request_int_send(1, 1, sent.seq)
        got = client.recv("MISSION_ITEM_INT", 3.0)
        assert (got.seq, got.command, got.frame, got.x, got.y) == (
            sent.seq,
            sent.command,
            sent.frame,
            sent.x,
            sent.y,
        )
        assert got.z == sent.z
    with client.send_lock:
        client.mav.mission_clear_all_send(1, 1)
    assert client.recv("MISSION_ACK", 3.0).type == mavlink2.MAV_MISSION_ACCEPTED
    assert endpoint.sim.mission == ()


def test_an_item_it_cannot_fly_is_refused_at_once_with_the_reason(endpoint, client):
    bad = [
        MISSION[0],
        item(1, mavlink2.MAV_CMD_DO_DIGICAM_CONTROL, frame=mavlink2.MAV_FRAME_MISSION),
    ]
    ack = upload(client, bad)
    assert ack is not None and ack.type == mavlink2.MAV_MISSION_UNSUPPORTED
    text = client.recv("STATUSTEXT", 3.0)
    assert text is not None and "unsupported" in text.text
    local = [
        item(0, mavlink2.MAV_CMD_NAV_WAYPOINT, 1.0, 1.0, 3.0, frame=mavlink2.MAV_FRAME_LOCAL_NED)
    ]
    assert upload(client, local).type == mavlink2.MAV_MISSION_UNSUPPORTED_FRAME
    with client.send_lock:
        client.mav.mission_count_send(1, 1, 1, mavlink2.MAV_MISSION_TYPE_FENCE)
    assert client.recv("MISSION_ACK", 3.0).type == mavlink2.MAV_MISSION_UNSUPPORTED
    assert endpoint.sim.mission == ()


@pytest.mark.slow
def test_auto_mission_flies_the_items_reports_progress_and_returns(endpoint, client):
    assert client.set_param("RTL_RETURN_ALT", 5.0) is not None
    assert upload(client, MISSION).type == mavlink2.MAV_MISSION_ACCEPTED
    assert client.command(400, 1).result == MAV_RESULT_ACCEPTED
    custom = FlightMode.MISSION.value
    set_mode = client.command(176, 1, (custom >> 16) & 0xFF, (custom >> 24) & 0xFF)
    assert set_mode.result == MAV_RESULT_ACCEPTED
    reached = []

    def progress() -> bool:
        msg = client.recv("MISSION_ITEM_REACHED", 0.2)
        if msg is not None:
            reached.append(msg.seq)
        return not endpoint.state.armed and endpoint.state.t_s > 10.0

    wait_until(progress, 90.0, "the mission, its RTL and the landing")
    assert reached[: len(MISSION)] == [0, 1, 2, 3]
    assert float(np.hypot(*endpoint.state.pos_ned_m[:2])) < 0.8
    current = client.recv("MISSION_CURRENT", 3.0)
    assert current is not None and current.mission_state == mavlink2.MISSION_STATE_COMPLETE


@pytest.mark.slow
def test_a_silent_ground_station_triggers_nav_dll_act(endpoint, client):
    assert client.set_int_param("NAV_DLL_ACT", 3) == 3  # land
    assert client.set_int_param("COM_DL_LOSS_T", 5) == 5
    assert client.set_param("COM_FAIL_ACT_T", 0.0) is not None
    assert client.command(400, 1).result == MAV_RESULT_ACCEPTED
    assert client.command(22, *[math.nan] * 7).result == MAV_RESULT_ACCEPTED
    wait_until(
        lambda: endpoint.state.mode == FlightMode.HOLD and -endpoint.state.pos_ned_m[2] > 2.3,
        30.0,
        "takeoff",
    )
    with client.send_lock:
        client.mav.heartbeat_send(mavlink2.MAV_TYPE_GCS, 8, 0, 0, 0)
    # The client now stays silent: after COM_DL_LOSS_T of simulated time the vehicle lands.
    text = client.recv("STATUSTEXT", 15.0, lambda m: "data link lost" in m.text)
    assert text is not None
    wait_until(lambda: endpoint.state.mode == FlightMode.LAND, 5.0, "LAND")
