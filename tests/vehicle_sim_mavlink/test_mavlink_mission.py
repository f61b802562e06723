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


def test_an_item_out_of_sequence_is_asked_for_again(endpoint, client):
    """[MAVLink] mission upload: the vehicle asks for items in order; an item other than the
    one asked for (here item 1 when item 0 was asked) is not stored, item 0 is asked again."""
    client.forget()
    with client.send_lock:
        client.mav.mission_count_send(1, 1, 2)
    assert client.recv("MISSION_REQUEST_INT", 3.0).seq == 0
    with client.send_lock:
        client.mav.send(MISSION[1])
    assert client.recv("MISSION_REQUEST_INT", 3.0).seq == 0
    with client.send_lock:
        client.mav.send(MISSION[0])
    assert client.recv("MISSION_REQUEST_INT", 3.0).seq == 1
    with client.send_lock:
        client.mav.send(MISSION[1])
    assert client.recv("MISSION_ACK", 3.0).type == mavlink2.MAV_MISSION_ACCEPTED
    assert [i.command for i in endpoint.sim.mission] == [
        mavlink2.MAV_CMD_NAV_TAKEOFF,
        mavlink2.MAV_CMD_NAV_WAYPOINT,
    ]


def test_a_download_marks_the_current_item_and_refuses_one_past_the_last(endpoint, client):
    """[MAVLink] MISSION_ITEM_INT.current is 1 for the item flown next (item 0 of a mission
    just uploaded), 0 for the others; asking for item 4 of a 4-item mission gets a
    MISSION_ACK MAV_MISSION_INVALID_SEQUENCE."""
    assert upload(client, MISSION).type == mavlink2.MAV_MISSION_ACCEPTED
    flags = []
    for seq in range(len(MISSION)):
        with client.send_lock:
            client.mav.mission_request_int_send(1, 1, seq)
        flags.append(client.recv("MISSION_ITEM_INT", 3.0).current)
    assert flags == [1, 0, 0, 0]
    client.forget()
    with client.send_lock:
        client.mav.mission_request_int_send(1, 1, len(MISSION))
    assert client.recv("MISSION_ACK", 3.0).type == mavlink2.MAV_MISSION_INVALID_SEQUENCE


def test_a_relative_altitude_item_is_flown_that_high_above_home(endpoint, client):
    """MAV_FRAME_GLOBAL_RELATIVE_ALT_INT's z is metres above home: the waypoint 12 m north at
    4 m is 4 m above home (down -4 m), not 4 m above mean sea level."""
    assert upload(client, MISSION).type == mavlink2.MAV_MISSION_ACCEPTED
    north, east, down = endpoint.sim.mission[1].pos_ned_m
    assert (north, east, down) == pytest.approx((12.0, 0.0, -4.0), abs=0.01)


def test_clearing_the_mission_abandons_an_upload_under_way(endpoint, client):
    """MISSION_CLEAR_ALL in the middle of an upload ends it: the item that follows belongs to
    no upload (MISSION_ACK MAV_MISSION_ERROR) and the vehicle keeps no mission."""
    client.forget()
    with client.send_lock:
        client.mav.mission_count_send(1, 1, 2)
    assert client.recv("MISSION_REQUEST_INT", 3.0).seq == 0
    with client.send_lock:
        client.mav.send(MISSION[0])
    assert client.recv("MISSION_REQUEST_INT", 3.0).seq == 1
    with client.send_lock:
        client.mav.mission_clear_all_send(1, 1)
    assert client.recv("MISSION_ACK", 3.0).type == mavlink2.MAV_MISSION_ACCEPTED
    with client.send_lock:
        client.mav.send(MISSION[1])
    assert client.recv("MISSION_ACK", 3.0).type == mavlink2.MAV_MISSION_ERROR
    assert endpoint.sim.mission == ()


def test_a_refused_item_ends_the_upload_and_a_count_of_zero_clears_the_mission(endpoint, client):
    """After an item is refused the upload is over: sending a good item in its place gets
    MAV_MISSION_ERROR, not a mission. [MAVLink]: a MISSION_COUNT of 0 clears the mission,
    acknowledged at once."""
    bad = [
        MISSION[0],
        item(1, mavlink2.MAV_CMD_DO_DIGICAM_CONTROL, frame=mavlink2.MAV_FRAME_MISSION),
    ]
    assert upload(client, bad).type == mavlink2.MAV_MISSION_UNSUPPORTED
    client.forget()
    with client.send_lock:
        client.mav.send(MISSION[1])
    assert client.recv("MISSION_ACK", 3.0).type == mavlink2.MAV_MISSION_ERROR
    assert endpoint.sim.mission == ()
    assert upload(client, MISSION).type == mavlink2.MAV_MISSION_ACCEPTED
    assert upload(client, []).type == mavlink2.MAV_MISSION_ACCEPTED
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
