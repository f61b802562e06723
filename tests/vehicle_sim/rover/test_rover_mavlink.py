"""The rover speaks MAVLink like a PX4 rover: pymavlink arm, offboard velocity + yaw rate."""

import time

import pytest
from pymavlink import mavutil

from tests.free_port import free_udp_port
from vehicle_sim.rover import RoverSim, rover_preset
from vehicle_sim.rover.mavlink_rover import RoverMavlinkEndpoint

_MAV = mavutil.mavlink


@pytest.mark.slow
def test_pymavlink_arm_offboard_velocity_and_yaw_rate() -> None:
    port = free_udp_port()
    ep = RoverMavlinkEndpoint(RoverSim(rover_preset("husky_50kg")), port)
    ep.start()
    gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=255)
    try:
        gcs.mav.heartbeat_send(_MAV.MAV_TYPE_GCS, _MAV.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        hb = gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=20)
        assert hb is not None and hb.type == _MAV.MAV_TYPE_GROUND_ROVER

        def setpoint() -> None:
            mask = 0b0000_0101_1100_0111  # velocity + yaw rate only
            gcs.mav.set_position_target_local_ned_send(
                0, 1, 1, _MAV.MAV_FRAME_BODY_NED, mask, 0, 0, 0, 0.5, 0, 0, 0, 0, 0, 0, -0.3
            )

        gcs.mav.command_long_send(1, 1, _MAV.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0)
        ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=20)
        assert ack.result == _MAV.MAV_RESULT_ACCEPTED
        setpoint()
        time.sleep(0.1)
        gcs.mav.command_long_send(1, 1, _MAV.MAV_CMD_DO_SET_MODE, 0, 1, 6, 0, 0, 0, 0, 0)
        ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=20)
        assert ack.result == _MAV.MAV_RESULT_ACCEPTED
        t_end = time.monotonic() + 4.0
        while time.monotonic() < t_end:
            setpoint()
            time.sleep(0.05)
        while gcs.recv_match(blocking=False) is not None:
            pass  # drop telemetry queued while streaming; read fresh messages
        pos = att = None
        t_end = time.monotonic() + 10.0
        while (pos is None or att is None) and time.monotonic() < t_end:
            m = gcs.recv_match(type=["LOCAL_POSITION_NED", "ATTITUDE"], blocking=True, timeout=5)
            if m is not None and m.get_type() == "LOCAL_POSITION_NED":
                pos = m
            elif m is not None:
                att = m
        assert pos is not None and att is not None
        assert pos.x > 0.5  # drove forwards (north at heading 0)
        assert att.yaw < -0.3  # turned left: NED yaw decreases (yaw rate -0.3 rad/s in NED)
    finally:
        gcs.close()
        ep.close()


@pytest.mark.slow
def test_malformed_messages_get_an_answer_and_never_stop_the_rover() -> None:
    """A mode that is not a number is DENIED, NaN / position-only setpoints and those in a
    frame other than LOCAL_NED or BODY_NED (as the multirotor endpoint: BODY_FRD's forward speed
    was read as a north one) are refused with a STATUSTEXT (no proof of life: OFFBOARD is
    refused), an unknown command is UNSUPPORTED; the rover keeps answering and then drives a
    good setpoint stream."""
    port = free_udp_port()
    ep = RoverMavlinkEndpoint(RoverSim(rover_preset("husky_50kg")), port)
    ep.start()
    gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=255)
    nan = float("nan")

    def command(cmd: int, *params: float) -> object:
        gcs.mav.command_long_send(1, 1, cmd, 0, *params)
        ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=20)
        assert ack is not None and ack.command == cmd
        return ack.result

    def setpoint(mask: int, vx: float, frame: int = _MAV.MAV_FRAME_BODY_NED) -> None:
        gcs.mav.set_position_target_local_ned_send(
            0, 1, 1, frame, mask, 1, 0, 0, vx, 0, 0, 0, 0, 0, 0, 0.0
        )

    try:
        gcs.mav.heartbeat_send(_MAV.MAV_TYPE_GCS, _MAV.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=20) is not None
        assert command(_MAV.MAV_CMD_COMPONENT_ARM_DISARM, 1, 0, 0, 0, 0, 0, 0) == 0
        assert command(_MAV.MAV_CMD_DO_SET_MODE, 1, nan, 0, 0, 0, 0, 0) == (_MAV.MAV_RESULT_DENIED)
        assert command(_MAV.MAV_CMD_DO_ORBIT, 0, 0, 0, 0, 0, 0, 0) == (_MAV.MAV_RESULT_UNSUPPORTED)
        texts = set()
        for mask, vx, frame in (
            (0b0000_0101_1100_0111, nan, _MAV.MAV_FRAME_BODY_NED),
            (0b0000_1101_1111_1000, 0.0, _MAV.MAV_FRAME_BODY_NED),
            (0b0000_0101_1100_0111, 0.5, _MAV.MAV_FRAME_BODY_FRD),
        ):
            setpoint(mask, vx, frame)
            text = gcs.recv_match(type="STATUSTEXT", blocking=True, timeout=20)
            assert text is not None
            texts.add(text.text)
        assert texts == {
            "Offboard: setpoint refused: not finite",
            "Offboard: rover flies velocity setpoints only",
            "Offboard: frame 12 unsupported, use 1 or 8",
        }
        assert command(_MAV.MAV_CMD_DO_SET_MODE, 1, 6, 0, 0, 0, 0, 0) == (
            _MAV.MAV_RESULT_DENIED
        )  # no usable setpoint arrived: no OFFBOARD
        setpoint(0b0000_0101_1100_0111, 0.5)
        assert command(_MAV.MAV_CMD_DO_SET_MODE, 1, 6, 0, 0, 0, 0, 0) == (_MAV.MAV_RESULT_ACCEPTED)
        assert ep.offboard and ep.handler_errors == 0
        assert command(_MAV.MAV_CMD_REQUEST_MESSAGE, 148, 0, 0, 0, 0, 0, 0) == 0  # MAVSDK info
        version = gcs.recv_match(type="AUTOPILOT_VERSION", blocking=True, timeout=20)
        assert version is not None and version.flight_sw_version >> 16 == 0x010F  # PX4 1.15
        gcs.mav.log_request_list_send(1, 1, 0, 0xFFFF)  # MAVSDK's log_files.get_entries()
        entry = gcs.recv_match(type="LOG_ENTRY", blocking=True, timeout=20)
        assert entry is not None and entry.num_logs == 0
    finally:
        gcs.close()
        ep.close()


def _latest(gcs: mavutil.mavfile, kind: str, wait_s: float) -> object:
    """The newest ``kind`` message received within ``wait_s`` seconds after dropping the queue."""
    while gcs.recv_match(blocking=False) is not None:
        pass
    newest = None
    t_end = time.monotonic() + wait_s
    while time.monotonic() < t_end:
        m = gcs.recv_match(type=kind, blocking=True, timeout=0.2)
        newest = m if m is not None else newest
    return newest


def _command(gcs: mavutil.mavfile, command: int, *params: float) -> int:
    p = list(params) + [0.0] * (7 - len(params))
    gcs.mav.command_long_send(1, 1, command, 0, *p)
    ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=20)
    assert ack is not None
    return ack.result


@pytest.mark.slow
def test_modes_hold_is_reported_other_auto_modes_refused_bad_setpoints_ignored() -> None:
    """PX4 reports Hold as AUTO_LOITER (main 4, sub 3) and refuses the AUTO modes a rover
    cannot fly here (RTL, mission, land, takeoff); an offboard stream that stops puts the rover
    in Hold (PX4's failsafe, which says so); a setpoint with NaN speed is ignored, the endpoint
    keeps running; GLOBAL_POSITION_INT carries the ground velocity (MAVSDK's velocity_ned reads
    it)."""
    port = free_udp_port()
    ep = RoverMavlinkEndpoint(RoverSim(rover_preset("husky_50kg")), port, setpoint_timeout_s=0.5)
    ep.start()
    gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=255)
    mask = 0b0000_0101_1100_0111  # velocity + yaw rate only

    def stream(speed_mps: float, seconds: float) -> None:
        t_end = time.monotonic() + seconds
        while time.monotonic() < t_end:
            gcs.mav.set_position_target_local_ned_send(
                0, 1, 1, _MAV.MAV_FRAME_BODY_NED, mask, 0, 0, 0, speed_mps, 0, 0, 0, 0, 0, 0, 0
            )
            time.sleep(0.05)

    try:
        gcs.mav.heartbeat_send(_MAV.MAV_TYPE_GCS, _MAV.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=20) is not None
        assert _command(gcs, _MAV.MAV_CMD_COMPONENT_ARM_DISARM, 1) == _MAV.MAV_RESULT_ACCEPTED
        stream(0.0, 0.2)
        assert _command(gcs, _MAV.MAV_CMD_DO_SET_MODE, 1, 6) == _MAV.MAV_RESULT_ACCEPTED
        stream(0.8, 2.0)
        # what arrived while streaming: waiting for a newer one past the 0.5 s setpoint
        # timeout would see the rover braking in Hold (on a busy machine it did: 1 cm/s)
        queued = iter(lambda: gcs.recv_match(blocking=False), None)
        gp = [m for m in queued if m.get_type() == "GLOBAL_POSITION_INT"][-1]
        assert abs(gp.vx) + abs(gp.vy) > 30  # cm/s
        gcs.mav.set_position_target_local_ned_send(
            0, 1, 1, _MAV.MAV_FRAME_BODY_NED, mask, 0, 0, 0, float("nan"), 0, 0, 0, 0, 0, 0, 0
        )
        assert _latest(gcs, "HEARTBEAT", 1.2) is not None  # still alive
        for sub in (5, 4, 6, 2):  # RTL, mission, land, takeoff
            assert _command(gcs, _MAV.MAV_CMD_DO_SET_MODE, 1, 4, sub) == _MAV.MAV_RESULT_DENIED
        assert _command(gcs, _MAV.MAV_CMD_DO_SET_MODE, 1, 4, 3) == _MAV.MAV_RESULT_ACCEPTED
        hb = _latest(gcs, "HEARTBEAT", 1.2)
        assert (hb.custom_mode >> 16 & 0xFF, hb.custom_mode >> 24) == (4, 3)
        stream(0.0, 0.2)
        assert _command(gcs, _MAV.MAV_CMD_DO_SET_MODE, 1, 6) == _MAV.MAV_RESULT_ACCEPTED
        said = gcs.recv_match(type="STATUSTEXT", blocking=True, timeout=1.5)  # after the timeout
        assert said is not None and said.text == "Failsafe: offboard lost, holding"
        hb = _latest(gcs, "HEARTBEAT", 1.0)
        assert (hb.custom_mode >> 16 & 0xFF, hb.custom_mode >> 24) == (4, 3)
    finally:
        gcs.close()
        ep.close()


@pytest.mark.slow
def test_the_global_position_comes_as_often_as_the_local_one() -> None:
    """GLOBAL_POSITION_INT (MAVSDK's position, heading and velocity_ned) at the telemetry rate
    with LOCAL_POSITION_NED, as PX4 streams both, not once a second: a MAVSDK client reading
    the rover's heading while it turns got values up to a second old."""
    port = free_udp_port()
    ep = RoverMavlinkEndpoint(RoverSim(rover_preset("husky_50kg")), port, telemetry_hz=10.0)
    ep.start()
    gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=255)
    try:
        gcs.mav.heartbeat_send(_MAV.MAV_TYPE_GCS, _MAV.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=20) is not None
        counts = {"GLOBAL_POSITION_INT": 0, "LOCAL_POSITION_NED": 0}
        t_end = time.monotonic() + 2.0
        while time.monotonic() < t_end:
            m = gcs.recv_match(type=list(counts), blocking=True, timeout=0.2)
            if m is not None:
                counts[m.get_type()] += 1
    finally:
        gcs.close()
        ep.close()
    assert counts["LOCAL_POSITION_NED"] >= 10
    assert counts["GLOBAL_POSITION_INT"] >= 0.8 * counts["LOCAL_POSITION_NED"], counts
