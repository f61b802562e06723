"""pymavlink against the endpoint over loopback UDP: offboard rules, failsafe, params, commands."""

from __future__ import annotations

import math

import pytest
from mavlink_test_client import (
    HOLD_CUSTOM_MODE,
    LAND_CUSTOM_MODE,
    MAV_RESULT_ACCEPTED,
    MAV_RESULT_TEMPORARILY_REJECTED,
    MAV_RESULT_UNSUPPORTED,
    OFFBOARD_CUSTOM_MODE,
    wait_until,
)

from vehicle_sim import FlightMode

CMD_ARM = 400
CMD_TAKEOFF = 22
CMD_SET_MODE = 176


def take_off(client, endpoint) -> None:
    assert client.command(CMD_ARM, 1).result == MAV_RESULT_ACCEPTED
    assert client.command(CMD_TAKEOFF, *[math.nan] * 7).result == MAV_RESULT_ACCEPTED
    wait_until(lambda: endpoint.state.mode == FlightMode.TAKEOFF, 2.0, "TAKEOFF mode")
    wait_until(lambda: endpoint.state.mode == FlightMode.HOLD, 15.0, "takeoff to end in HOLD")
    assert endpoint.state.armed
    assert -endpoint.state.pos_ned_m[2] == pytest.approx(2.5, abs=0.2)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("action", "custom_mode", "mode"),
    [(5.0, HOLD_CUSTOM_MODE, FlightMode.HOLD), (4.0, LAND_CUSTOM_MODE, FlightMode.LAND)],
)
def test_offboard_needs_a_stream_and_loss_triggers_the_configured_failsafe(
    endpoint, client, action, custom_mode, mode
):
    assert client.set_int_param("COM_OBL_RC_ACT", int(action)) == action
    assert client.set_param("COM_FAIL_ACT_T", 0.0) is not None  # act at once
    take_off(client, endpoint)

    refused = client.command(CMD_SET_MODE, 129, 6, 0)
    assert refused.result == MAV_RESULT_TEMPORARILY_REJECTED
    assert endpoint.state.mode == FlightMode.HOLD

    client.start_stream((0.0, 0.0, 0.0))
    wait_until(lambda: endpoint.stats.setpoints_accepted >= 3, 5.0, "setpoints to arrive")
    assert client.command(CMD_SET_MODE, 129, 6, 0).result == MAV_RESULT_ACCEPTED
    hb = client.recv("HEARTBEAT", 3.0, lambda m: m.custom_mode == OFFBOARD_CUSTOM_MODE)
    assert hb is not None and hb.base_mode & 128
    wait_until(lambda: endpoint.state.mode == FlightMode.OFFBOARD, 2.0, "OFFBOARD")

    client.stop_stream()
    text = client.recv("STATUSTEXT", 10.0, lambda m: "Failsafe" in m.text)
    assert text is not None and "offboard" in text.text
    assert client.recv("HEARTBEAT", 3.0, lambda m: m.custom_mode == custom_mode) is not None
    assert endpoint.state.mode == mode and endpoint.state.armed
    if mode == FlightMode.LAND:
        wait_until(lambda: not endpoint.state.armed, 20.0, "landing and auto-disarm")
        assert abs(endpoint.state.pos_ned_m[2]) < 0.1


def test_param_list_read_and_set(endpoint, client):
    names = endpoint.sim.param_names()
    client.mav.param_request_list_send(1, 1)
    seen = {}
    while len(seen) < len(names):
        msg = client.recv("PARAM_VALUE", 3.0)
        assert msg is not None, f"only {len(seen)} of {len(names)} parameters arrived"
        assert msg.param_count == len(names)
        seen[msg.param_index] = (msg.param_id, msg.param_value)
    assert sorted(seen) == list(range(len(names)))
    assert seen[names.index("MIS_TAKEOFF_ALT")] == ("MIS_TAKEOFF_ALT", 2.5)

    client.mav.param_request_read_send(1, 1, b"COM_OF_LOSS_T", -1)
    msg = client.recv("PARAM_VALUE", 3.0, lambda m: m.param_id == "COM_OF_LOSS_T")
    assert msg.param_value == 1.0 and msg.param_index == names.index("COM_OF_LOSS_T")

    assert client.set_param("MIS_TAKEOFF_ALT", 4.0).param_value == 4.0
    client.mav.param_request_read_send(1, 1, b"", names.index("MIS_TAKEOFF_ALT"))
    msg = client.recv("PARAM_VALUE", 3.0, lambda m: m.param_id == "MIS_TAKEOFF_ALT")
    assert msg.param_value == 4.0


def test_an_unknown_parameter_is_said_as_px4_says_it(endpoint, client):
    """PX4 answers a read or set of a name it does not have with "[pm] unknown param" (info),
    not with silence; nothing is set."""
    client.mav.param_set_send(1, 1, b"NO_SUCH_PARAM", 1.0, 9)
    notice = client.recv("STATUSTEXT", 3.0, lambda m: "NO_SUCH_PARAM" in m.text)
    assert notice is not None and notice.severity == 6 and "unknown" in notice.text
    client.mav.param_request_read_send(1, 1, b"", 30000)
    notice = client.recv("STATUSTEXT", 3.0, lambda m: "30000" in m.text)
    assert notice is not None and notice.severity == 6
    assert endpoint.stats.params_unknown == 2 and endpoint.stats.handler_errors == 0


def test_unknown_commands_are_answered_unsupported(endpoint, client):
    assert client.command(31999, 1, 2, 3).result == MAV_RESULT_UNSUPPORTED
    assert client.command(31998, use_int=True).result == MAV_RESULT_UNSUPPORTED
    assert endpoint.stats.commands_unsupported == 2


def test_commands_for_another_system_are_ignored_and_counted(endpoint, client):
    assert client.command(CMD_ARM, 1, target_system=42, timeout_s=1.0) is None
    assert not endpoint.state.armed
    assert endpoint.stats.wrong_target == 1
    assert client.command(CMD_ARM, 1).result == MAV_RESULT_ACCEPTED


def test_requests_and_small_services(endpoint, client):
    ack = client.command(512, 148)
    assert ack.result == MAV_RESULT_ACCEPTED
    version = client.recv("AUTOPILOT_VERSION", 2.0)
    assert version is not None and version.capabilities & 128 and version.capabilities & 8192
    assert client.command(512, 242).result == MAV_RESULT_ACCEPTED
    assert client.recv("HOME_POSITION", 2.0) is not None
    assert client.command(512, 11111).result != MAV_RESULT_ACCEPTED

    client.mav.ping_send(123456, 7, 0, 0)
    pong = client.recv("PING", 2.0)
    assert (pong.time_usec, pong.seq, pong.target_system) == (123456, 7, 245)
    client.mav.timesync_send(0, 987654321)
    sync = client.recv("TIMESYNC", 2.0)
    assert sync.ts1 == 987654321 and sync.tc1 > 0
    client.mav.mission_request_list_send(1, 1)
    assert client.recv("MISSION_COUNT", 2.0).count == 0
    client.mav.file_transfer_protocol_send(0, 1, 1, [1, 0, 0, 4] + [0] * 247)
    nak = client.recv("FILE_TRANSFER_PROTOCOL", 2.0)
    assert nak.payload[3] == 129 and nak.payload[5] == 4
    client.mav.log_request_list_send(1, 1, 0, 0xFFFF)  # MAVSDK's log_files.get_entries()
    entry = client.recv("LOG_ENTRY", 2.0)
    assert entry is not None and entry.num_logs == 0  # no logs: said at once, as PX4 does


def test_set_message_interval_stops_and_restores_a_stream(endpoint, client):
    assert client.recv("ATTITUDE", 2.0) is not None
    assert client.command(511, 30, -1).result == MAV_RESULT_ACCEPTED
    assert client.recv("ATTITUDE", 1.0) is None  # none sent after the ACK
    assert client.command(511, 30, 0).result == MAV_RESULT_ACCEPTED
    assert client.recv("ATTITUDE", 2.0) is not None
    assert client.command(511, 31999, 1000).result != MAV_RESULT_ACCEPTED
