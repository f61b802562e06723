"""A RoverSim behind one MAVLink UDP link, speaking as a PX4 rover does ([PX4-rover]).

Small and separate from vehicle_sim.mavlink (the multirotor endpoint): HEARTBEAT with
MAV_TYPE_GROUND_ROVER and the PX4 custom mode (main mode 6 = OFFBOARD), COMMAND_LONG
MAV_CMD_COMPONENT_ARM_DISARM and MAV_CMD_DO_SET_MODE (acknowledged; MANUAL, Hold = AUTO_LOITER
and OFFBOARD; the other AUTO modes, RTL, mission, land and takeoff, are denied),
AUTOPILOT_VERSION on request (MAV_CMD_REQUEST_MESSAGE 148, or 520), SET_MODE, and offboard
SET_POSITION_TARGET_LOCAL_NED with velocity + yaw rate: in MAV_FRAME_BODY_NED vx is the forward
speed; in MAV_FRAME_LOCAL_NED the speed is (vx, vy) projected on the heading; another frame is
refused, as the multirotor endpoint refuses it. Telemetry at
``telemetry_hz``: HEARTBEAT, LOCAL_POSITION_NED, ATTITUDE, ATTITUDE_QUATERNION and
GLOBAL_POSITION_INT (with the ground velocity, about a fixed origin, flat-earth), and at 1 Hz
what else MAVSDK's health check wants (SYS_STATUS with healthy sensors and the pre-arm bit,
GPS_RAW_INT and HOME_POSITION). Offboard without a setpoint for ``setpoint_timeout_s`` stops
the rover and switches to Hold (PX4's offboard loss failsafe), saying so in a STATUSTEXT.
A malformed message never stops the endpoint: a mode that is not a number is DENIED, a setpoint
with a non-finite speed or yaw rate, or without a velocity (a position setpoint, which this
rover does not fly), is refused with a STATUSTEXT (and is no proof of life), an
unknown command is UNSUPPORTED; whatever else fails in a handler is counted in
``handler_errors`` and the message dropped.

World frame mapping: the rover's x is north, its y is west (heading counter-clockwise from x),
so NED north = x_m, east = -y_m, yaw = -heading_rad.
"""

from __future__ import annotations

import math
import threading
import time

from pymavlink import mavutil

from vehicle_sim.mavlink.services import empty_log_list_reply
from vehicle_sim.mavlink.telemetry import PX4_VERSION
from vehicle_sim.rover.simulator import RoverSim

_PX4_MAIN_OFFBOARD = 6
_PX4_MAIN_MANUAL = 1
_PX4_MAIN_AUTO = 4
_PX4_SUB_AUTO_LOITER = 3  # PX4's Hold
_MAV = mavutil.mavlink
_ORIGIN_LAT_DEG, _ORIGIN_LON_DEG, _ORIGIN_ALT_M = 47.397742, 8.545594, 488.0  # PX4 SITL home
_M_PER_DEG_LAT = 111_320.0
_IGNORE_VELOCITY, _IGNORE_YAW, _IGNORE_YAW_RATE = 0x38, 0x400, 0x800  # POSITION_TARGET_TYPEMASK
_YAW_P = 2.0
_VERSION_REQUESTS = (_MAV.MAV_CMD_REQUEST_MESSAGE, _MAV.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES)
_CAPABILITIES = (
    _MAV.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
    | _MAV.MAV_PROTOCOL_CAPABILITY_MAVLINK2
)
_UID = 0x5349_4D00_0000_0002  # the multirotor endpoint's is ...01
_SENSORS = (
    _MAV.MAV_SYS_STATUS_SENSOR_3D_GYRO
    | _MAV.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | _MAV.MAV_SYS_STATUS_SENSOR_3D_MAG
    | _MAV.MAV_SYS_STATUS_SENSOR_GPS
    | _MAV.MAV_SYS_STATUS_PREARM_CHECK
)


def _lat_lon_e7(north_m: float, east_m: float) -> tuple[int, int]:
    lat = _ORIGIN_LAT_DEG + north_m / _M_PER_DEG_LAT
    lon = _ORIGIN_LON_DEG + east_m / (_M_PER_DEG_LAT * math.cos(math.radians(_ORIGIN_LAT_DEG)))
    return int(round(lat * 1e7)), int(round(lon * 1e7))


class RoverMavlinkEndpoint:
    """Runs ``sim`` in real time on a thread, on UDP ``host:port``.

    ``mode`` "udpin" listens there (a ground station sends first); "udpout" sends there, as
    PX4 SITL sends to a companion listening on udpin (companion.pymavlink_link, MAVSDK).
    """

    def __init__(
        self,
        sim: RoverSim,
        port: int,
        host: str = "127.0.0.1",
        physics_period_s: float = 0.02,
        telemetry_hz: float = 10.0,
        setpoint_timeout_s: float = 1.0,
        mode: str = "udpin",
    ) -> None:
        if mode not in ("udpin", "udpout"):
            raise ValueError(f"mode must be 'udpin' or 'udpout', got {mode!r}")
        self.sim = sim
        self._conn = mavutil.mavlink_connection(
            f"{mode}:{host}:{port}", source_system=1, source_component=1
        )
        self._period = physics_period_s
        self._telemetry_period = 1.0 / telemetry_hz
        self._timeout = setpoint_timeout_s
        self.offboard = False
        self.holding = False  # Hold (AUTO_LOITER), reported as such in HEARTBEAT
        self._last_sp = -math.inf
        self.handler_errors = 0
        self._refused_at: dict[bytes, float] = {}  # refusal text -> when last said [s]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self) -> None:
        self._thread.start()

    @property
    def running(self) -> bool:
        """True while the endpoint's loop runs (started and not closed)."""
        return self._thread.is_alive()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        self._conn.close()

    def _run(self) -> None:
        next_tel = next_slow = 0.0
        t_prev = time.monotonic()
        while not self._stop.is_set():
            while (msg := self._conn.recv_match(blocking=False)) is not None:
                try:
                    self._handle(msg)
                except Exception:  # a hostile message must never stop the rover's loop
                    self.handler_errors += 1
            now = time.monotonic()
            if self.offboard and now - self._last_sp > self._timeout:
                self._set_mode(_PX4_MAIN_AUTO, _PX4_SUB_AUTO_LOITER)  # offboard loss: Hold
                if self._conn.mav is not None:  # said, as PX4's failsafe says it
                    self._conn.mav.statustext_send(
                        _MAV.MAV_SEVERITY_CRITICAL, b"Failsafe: offboard lost, holding"
                    )
            self.sim.step(min(now - t_prev, 0.1))
            t_prev = now
            if now >= next_tel and self._conn.mav is not None:
                self._telemetry()
                next_tel = now + self._telemetry_period
            if now >= next_slow and self._conn.mav is not None:
                self._health_telemetry()
                next_slow = now + 1.0
            time.sleep(self._period)

    def _ack(self, msg: object, result: int) -> None:
        """COMMAND_ACK for ``msg``'s command with ``result`` (MAV_RESULT), addressed to its
        sender as PX4 does (the target fields are extensions: over MAVLink 1, which pymavlink
        speaks until it hears a MAVLink 2 peer, they are left out of the packet)."""
        ack = self._conn.mav.command_ack_encode(msg.command, result)
        ack.target_system, ack.target_component = msg.get_srcSystem(), msg.get_srcComponent()
        self._conn.mav.send(ack)

    def _set_mode(self, main_mode: float, sub_mode: float) -> bool:
        if not (math.isfinite(main_mode) and math.isfinite(sub_mode)):
            return False
        if main_mode == _PX4_MAIN_OFFBOARD:
            if time.monotonic() - self._last_sp > self._timeout:
                return False  # PX4 refuses OFFBOARD without a setpoint stream
            self.offboard, self.holding = True, False
            return True
        hold = main_mode == _PX4_MAIN_AUTO and sub_mode == _PX4_SUB_AUTO_LOITER
        if main_mode == _PX4_MAIN_MANUAL or hold:
            self.offboard, self.holding = False, hold
            self.sim.set_setpoint(0.0, 0.0)
            return True
        return False  # RTL, mission, land, takeoff, ...: nothing here flies them

    def _handle(self, msg: object) -> None:
        kind = msg.get_type()
        if kind == "COMMAND_LONG":
            if msg.command == _MAV.MAV_CMD_COMPONENT_ARM_DISARM:
                if msg.param1 > 0.5:
                    self.sim.arm()
                else:
                    self.sim.disarm()
                    self.offboard = self.holding = False
                self._ack(msg, _MAV.MAV_RESULT_ACCEPTED)
            elif msg.command in _VERSION_REQUESTS and (
                msg.command != _MAV.MAV_CMD_REQUEST_MESSAGE
                or msg.param1 == _MAV.MAVLINK_MSG_ID_AUTOPILOT_VERSION
            ):  # MAVSDK's info plugin asks for it on connecting
                self._ack(msg, _MAV.MAV_RESULT_ACCEPTED)
                self._conn.mav.autopilot_version_send(
                    _CAPABILITIES, PX4_VERSION, PX4_VERSION, 0, 0, [0] * 8, [0] * 8, [0] * 8,
                    0, 0, _UID,
                )  # fmt: skip
            elif msg.command == _MAV.MAV_CMD_DO_SET_MODE:
                ok = self._set_mode(msg.param2, msg.param3)
                self._ack(msg, _MAV.MAV_RESULT_ACCEPTED if ok else _MAV.MAV_RESULT_DENIED)
            else:
                self._ack(msg, _MAV.MAV_RESULT_UNSUPPORTED)
        elif kind == "SET_MODE":
            self._set_mode((msg.custom_mode >> 16) & 0xFF, (msg.custom_mode >> 24) & 0xFF)
        elif kind == "LOG_REQUEST_LIST":  # no logs, said at once as PX4 does (num_logs 0)
            self._conn.mav.send(empty_log_list_reply(msg))
        elif kind == "SET_POSITION_TARGET_LOCAL_NED":
            if msg.type_mask & _IGNORE_VELOCITY == _IGNORE_VELOCITY:
                self._refuse_setpoint(b"Offboard: rover flies velocity setpoints only")
                return
            if msg.coordinate_frame not in (_MAV.MAV_FRAME_LOCAL_NED, _MAV.MAV_FRAME_BODY_NED):
                text = f"Offboard: frame {msg.coordinate_frame} unsupported, use 1 or 8"
                self._refuse_setpoint(text.encode())
                return
            heading = self.sim.state.heading_rad
            if msg.coordinate_frame == _MAV.MAV_FRAME_BODY_NED:
                speed = msg.vx
            else:  # LOCAL_NED: project the ground velocity on the heading (north, east)
                speed = msg.vx * math.cos(-heading) + msg.vy * math.sin(-heading)
            yaw_rate = self._yaw_rate_sp(msg, heading)
            if not (math.isfinite(speed) and math.isfinite(yaw_rate)):
                self._refuse_setpoint(b"Offboard: setpoint refused: not finite")
                return
            self._last_sp = time.monotonic()
            if self.offboard and self.sim.armed:
                self.sim.set_setpoint(float(speed), float(yaw_rate))

    def _refuse_setpoint(self, text: bytes) -> None:
        """Say why a setpoint is not flown (STATUSTEXT of at most 50 characters, each text at
        most once a second, as PX4 limits its messages); it is no proof of life, so OFFBOARD
        is not entered on it and its loss failsafe still runs."""
        now = time.monotonic()
        if now - self._refused_at.get(text, -math.inf) >= 1.0:
            self._refused_at[text] = now
            self._conn.mav.statustext_send(_MAV.MAV_SEVERITY_WARNING, text)

    @staticmethod
    def _yaw_rate_sp(msg: object, heading_rad: float) -> float:
        """Yaw rate [rad/s, counter-clockwise] from a setpoint's yaw rate, or, when the mask
        uses the yaw angle instead (as MAVSDK's VelocityNedYaw does), from a heading P-loop
        (gain ``_YAW_P`` 1/s, as PX4 rover's heading controller turns towards a yaw setpoint)."""
        uses_yaw = not msg.type_mask & _IGNORE_YAW and math.isfinite(msg.yaw)
        if uses_yaw and msg.type_mask & _IGNORE_YAW_RATE:
            err = -msg.yaw - heading_rad  # NED yaw is clockwise
            return _YAW_P * math.atan2(math.sin(err), math.cos(err))
        return 0.0 if math.isnan(msg.yaw_rate) else -msg.yaw_rate

    def _telemetry(self) -> None:
        st = self.sim.state
        base = _MAV.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        if self.sim.armed:
            base |= _MAV.MAV_MODE_FLAG_SAFETY_ARMED
        main, sub = (_PX4_MAIN_OFFBOARD if self.offboard else _PX4_MAIN_MANUAL), 0
        if self.holding:
            main, sub = _PX4_MAIN_AUTO, _PX4_SUB_AUTO_LOITER
        state = _MAV.MAV_STATE_ACTIVE if self.sim.armed else _MAV.MAV_STATE_STANDBY
        mav = self._conn.mav
        mav.heartbeat_send(
            _MAV.MAV_TYPE_GROUND_ROVER, _MAV.MAV_AUTOPILOT_PX4, base, main << 16 | sub << 24, state
        )
        t_ms = int(st.t_s * 1000)
        v_north, v_east = self._ground_velocity_ne_mps()
        mav.local_position_ned_send(t_ms, st.x_m, -st.y_m, 0.0, v_north, v_east, 0.0)
        mav.attitude_send(t_ms, 0.0, 0.0, -st.heading_rad, 0.0, 0.0, -st.yaw_rate_radps)
        half = -st.heading_rad / 2
        mav.attitude_quaternion_send(
            t_ms, math.cos(half), 0.0, 0.0, math.sin(half), 0.0, 0.0, -st.yaw_rate_radps
        )
        if all(math.isfinite(v) for v in (st.x_m, st.y_m, st.heading_rad)):
            lat, lon = _lat_lon_e7(st.x_m, -st.y_m)
            hdg = int(round(math.degrees(-st.heading_rad) * 100.0)) % 36000
            vx_cms, vy_cms = (int(round(v * 100.0)) for v in (v_north, v_east))
            alt_mm = int(_ORIGIN_ALT_M * 1000)
            mav.global_position_int_send(t_ms, lat, lon, alt_mm, 0, vx_cms, vy_cms, 0, hdg)

    def _ground_velocity_ne_mps(self) -> tuple[float, float]:
        """The rover's ground velocity (north, east) [m/s], side slip included."""
        st = self.sim.state
        c, s = math.cos(st.heading_rad), math.sin(st.heading_rad)
        return st.speed_mps * c - st.lat_speed_mps * s, -(st.speed_mps * s + st.lat_speed_mps * c)

    def _health_telemetry(self) -> None:
        st, mav = self.sim.state, self._conn.mav
        mav.sys_status_send(_SENSORS, _SENSORS, _SENSORS, 200, 12600, -1, 100, 0, 0, 0, 0, 0, 0)
        if not all(math.isfinite(v) for v in (st.x_m, st.y_m, st.heading_rad)):
            return  # no fix to give (LOCAL_POSITION_NED still says NaN); the loop lives on
        lat, lon = _lat_lon_e7(st.x_m, -st.y_m)
        alt_mm = int(_ORIGIN_ALT_M * 1000)
        mav.gps_raw_int_send(int(st.t_s * 1e6), 3, lat, lon, alt_mm, 80, 120, 65535, 65535, 12)
        lat0, lon0 = _lat_lon_e7(0.0, 0.0)
        mav.home_position_send(lat0, lon0, alt_mm, 0.0, 0.0, 0.0, (1.0, 0.0, 0.0, 0.0), 0, 0, 0)
