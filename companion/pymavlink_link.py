"""A Link over pymavlink: plain MAVLink on UDP, single-threaded.

The link's clock is the wall clock, but its ``sleep_until`` keeps the link serviced: it reads
and decodes incoming messages, re-sends the current setpoint every 50 ms while streaming (as
MAVSDK does, so OFFBOARD never sees a gap while the app waits for an answer) and sends the
companion's 1 Hz heartbeat. Commands are COMMAND_LONG with retries and wait for COMMAND_ACK.
Wire units (mm, cm/s, degE7, mV) never leave this module.
"""

from __future__ import annotations

import math
import struct
from collections import deque
from collections.abc import Callable, Mapping, Sequence

import numpy as np
from pymavlink import mavutil

from companion.clocks import WallClock
from companion.link import (
    STATUS_TEXTS_KEPT,
    CommandOutcome,
    LandedPhase,
    LinkError,
    LinkState,
    ObstacleDistances,
    StatusText,
    VehicleKind,
    VelocityCommand,
    vehicle_kind,
)
from companion.obstacle_distance_wire import obstacle_distances_of
from companion.px4_modes import PX4_MAIN_SUB, mode_name_of

_MAV = mavutil.mavlink
MAVLink_message = _MAV.MAVLink_message
# Use velocity and yaw rate; ignore position, acceleration (and force) and yaw.
_VELOCITY_YAW_RATE_MASK = (
    _MAV.POSITION_TARGET_TYPEMASK_X_IGNORE
    | _MAV.POSITION_TARGET_TYPEMASK_Y_IGNORE
    | _MAV.POSITION_TARGET_TYPEMASK_Z_IGNORE
    | _MAV.POSITION_TARGET_TYPEMASK_AX_IGNORE
    | _MAV.POSITION_TARGET_TYPEMASK_AY_IGNORE
    | _MAV.POSITION_TARGET_TYPEMASK_AZ_IGNORE
    | _MAV.POSITION_TARGET_TYPEMASK_YAW_IGNORE
)
_HEARTBEAT_LOST_S = 3.0
_STATUSTEXT_CHARS = 50  # STATUSTEXT.text, a chunk of a longer text when full
_MSG_LOCAL_POSITION_NED = _MAV.MAVLINK_MSG_ID_LOCAL_POSITION_NED
_MSG_ATTITUDE_QUATERNION = _MAV.MAVLINK_MSG_ID_ATTITUDE_QUATERNION


def pymavlink_device(url: str) -> str:
    """MAVSDK-style ``udpin://host:port`` (listen) or ``udpout://host:port`` (send to) ->
    pymavlink's ``udpin:host:port``; ValueError naming the accepted forms otherwise."""
    scheme, sep, rest = url.partition("://")
    host, colon, port = rest.rpartition(":")
    if not sep or scheme not in ("udpin", "udpout") or not colon or not port.isdigit():
        raise ValueError(
            f"unsupported MAVLink URL {url!r}; use udpin://HOST:PORT (listen, as for PX4 SITL) "
            "or udpout://HOST:PORT (send to)"
        )
    return f"{scheme}:{host}:{port}"


class _PumpClock:
    """Wall time whose sleep services the link (receive, re-send setpoint, heartbeat)."""

    real_time = True

    def __init__(self, link: PymavlinkLink) -> None:
        self._link = link
        self._wall = WallClock()

    def now_s(self) -> float:
        return self._wall.now_s()

    def sleep_until(self, t_s: float) -> None:
        self._link.service_until(t_s)


class PymavlinkLink:
    """A Link to a PX4-like autopilot over pymavlink.

    Args:
        url: ``udpin://HOST:PORT`` to listen where the autopilot sends (PX4 SITL: 14540).
        source_system, source_component: the companion's MAVLink ids.
        command_timeout_s: wait for one COMMAND_ACK [s]; ``command_attempts`` tries in all.
        setpoint_period_s: re-send period of the current setpoint while streaming [s].
        telemetry_rate_hz: rate requested for position and attitude messages [Hz].
    """

    def __init__(
        self,
        url: str,
        *,
        source_system: int = 245,
        source_component: int = 191,
        command_timeout_s: float = 1.0,
        command_attempts: int = 3,
        setpoint_period_s: float = 0.05,
        telemetry_rate_hz: float = 50.0,
    ) -> None:
        self._url = url
        self._device = pymavlink_device(url)
        self._ids = (source_system, source_component)
        self._command_timeout_s = command_timeout_s
        self._command_attempts = command_attempts
        self._setpoint_period_s = setpoint_period_s
        self._telemetry_rate_hz = telemetry_rate_hz
        self._clock = _PumpClock(self)
        self._mav: mavutil.mavfile | None = None
        self._target: tuple[int, int] | None = None
        self._setpoint: VelocityCommand | None = None
        self._setpoint_sent_s = -math.inf
        self._heartbeat_sent_s = -math.inf
        self._heartbeat_seen_s = -math.inf
        self._acks: dict[int, int] = {}
        self._params: dict[str, float] = {}
        self._status_texts: deque[StatusText] = deque(maxlen=STATUS_TEXTS_KEPT)
        self._texts_received = 0
        self._open_chunk: tuple[int, int] | None = None  # (id, chunk_seq) of a full last chunk
        self._pos = np.full(3, np.nan)
        self._vel = np.full(3, np.nan)
        self._q = np.full(4, np.nan)
        self._rates = np.full(3, np.nan)
        self._armed = False
        self._mode = "UNKNOWN"
        self._landed = LandedPhase.UNKNOWN
        self._battery_v: float | None = None
        self._obstacle_distances: ObstacleDistances | None = None
        self._vehicle_kind: VehicleKind | None = None

    @property
    def name(self) -> str:
        return "pymavlink"

    @property
    def clock(self) -> _PumpClock:
        return self._clock

    def connect(self, timeout_s: float) -> None:
        try:
            self._mav = mavutil.mavlink_connection(
                self._device,
                source_system=self._ids[0],
                source_component=self._ids[1],
            )
        except OSError as exc:
            raise LinkError(f"cannot open {self._url}: {exc}") from None
        deadline_s = self._clock.now_s() + timeout_s
        self.service_until(deadline_s, stop=lambda: self._target is not None)
        if self._target is None:
            raise LinkError(f"no autopilot heartbeat on {self._url} within {timeout_s:g} s")
        for msg_id in (_MSG_LOCAL_POSITION_NED, _MSG_ATTITUDE_QUATERNION):
            interval_us = 1e6 / self._telemetry_rate_hz
            self._command(_MAV.MAV_CMD_SET_MESSAGE_INTERVAL, (msg_id, interval_us), attempts=1)
        self.service_until(deadline_s, stop=lambda: self._telemetry_complete())
        if not self._telemetry_complete():
            raise LinkError(f"no position/attitude telemetry on {self._url} within {timeout_s:g} s")

    def read_state(self) -> LinkState:
        now_s = self._clock.now_s()
        if self._target is not None and now_s - self._heartbeat_seen_s > _HEARTBEAT_LOST_S:
            raise LinkError(f"link lost: no autopilot heartbeat for {_HEARTBEAT_LOST_S:g} s")
        return LinkState(
            t_s=now_s,
            pos_ned_m=self._pos.copy(),
            vel_ned_mps=self._vel.copy(),
            q_wxyz=self._q.copy(),
            rates_frd_radps=self._rates.copy(),
            armed=self._armed,
            mode=self._mode,
            landed=self._landed,
            battery_v=self._battery_v,
            obstacle_distances=self._obstacle_distances,
            vehicle_kind=self._vehicle_kind,
        )

    def arm(self) -> CommandOutcome:
        return self._command(_MAV.MAV_CMD_COMPONENT_ARM_DISARM, (1.0,))

    def takeoff(self, alt_m: float) -> CommandOutcome:
        set_alt = self._set_param("MIS_TAKEOFF_ALT", float(alt_m))
        if not set_alt.accepted:
            return set_alt
        return self._command(_MAV.MAV_CMD_NAV_TAKEOFF, (math.nan,) * 7)

    def send_velocity(self, command: VelocityCommand) -> None:
        self._setpoint = command
        self._send_setpoint()

    def start_offboard(self) -> CommandOutcome:
        return self._set_mode("OFFBOARD")

    def read_param(self, name: str) -> float | None:
        mav = self._require_open()
        target = self._require_target()
        for _ in range(self._command_attempts):
            self._params.pop(name, None)
            mav.mav.param_request_read_send(*target, name.encode(), -1)
            deadline_s = self._clock.now_s() + self._command_timeout_s
            self.service_until(deadline_s, stop=lambda: name in self._params)
            if name in self._params:
                return self._params[name]
        return None

    def stop_streaming(self) -> None:
        self._setpoint = None

    def hold(self) -> CommandOutcome:
        self._setpoint = None
        return self._set_mode("HOLD")

    def land(self) -> CommandOutcome:
        self._setpoint = None
        return self._command(_MAV.MAV_CMD_NAV_LAND, (math.nan,) * 7)

    def status_texts(self) -> Sequence[StatusText]:
        return tuple(self._status_texts)

    def metadata(self) -> Mapping[str, object]:
        return {"link": self.name, "url": self._url}

    def close(self) -> None:
        if self._mav is not None:
            self._mav.close()
            self._mav = None

    def service_until(self, t_s: float, stop: Callable[[], bool] | None = None) -> None:
        """Receive, re-send the setpoint and heartbeat until ``t_s`` (link clock) or until
        ``stop()`` holds. This is how the link's clock sleeps."""
        mav = self._require_open()
        while True:
            now_s = self._clock.now_s()
            self._service(now_s)
            if now_s >= t_s or (stop is not None and stop()):
                return
            # nothing is sent before the autopilot is known (_service): wait for it in the socket
            next_service_s = (
                math.inf
                if self._target is None
                else min(
                    self._setpoint_sent_s + self._setpoint_period_s
                    if self._setpoint is not None
                    else math.inf,
                    self._heartbeat_sent_s + 1.0,
                )
            )
            wait_s = max(0.0, min(t_s, next_service_s) - now_s)
            msg = mav.recv_match(blocking=True, timeout=wait_s)
            while msg is not None:
                self._handle(msg)
                msg = mav.recv_match(blocking=False)

    def _service(self, now_s: float) -> None:
        if self._target is None:
            return
        if self._setpoint is not None and now_s - self._setpoint_sent_s >= self._setpoint_period_s:
            self._send_setpoint()
        if now_s - self._heartbeat_sent_s >= 1.0:
            self._require_open().mav.heartbeat_send(
                _MAV.MAV_TYPE_ONBOARD_CONTROLLER,
                _MAV.MAV_AUTOPILOT_INVALID,
                0,
                0,
                _MAV.MAV_STATE_ACTIVE,
            )
            self._heartbeat_sent_s = now_s

    def _send_setpoint(self) -> None:
        if self._setpoint is None or self._target is None:
            return
        vn, ve, vd = self._setpoint.vel_ned_mps
        time_boot_ms = int(self._clock.now_s() * 1000) & 0xFFFFFFFF
        self._require_open().mav.set_position_target_local_ned_send(
            time_boot_ms,
            *self._target,
            _MAV.MAV_FRAME_LOCAL_NED,
            _VELOCITY_YAW_RATE_MASK,
            0.0,
            0.0,
            0.0,
            vn,
            ve,
            vd,
            0.0,
            0.0,
            0.0,
            0.0,
            self._setpoint.yaw_rate_radps,
        )
        self._setpoint_sent_s = self._clock.now_s()

    def _handle(self, msg: MAVLink_message) -> None:
        kind = msg.get_type()
        source = (msg.get_srcSystem(), msg.get_srcComponent())
        if kind == "HEARTBEAT" and self._target is None and _is_autopilot(msg):
            self._target = source
        if source != self._target:
            return
        handler = self._HANDLERS.get(kind)
        if handler is not None:
            handler(self, msg)

    def _on_heartbeat(self, msg: MAVLink_message) -> None:
        self._heartbeat_seen_s = self._clock.now_s()
        self._armed = bool(msg.base_mode & _MAV.MAV_MODE_FLAG_SAFETY_ARMED)
        self._mode = mode_name_of(msg.custom_mode)
        self._vehicle_kind = vehicle_kind(msg.type)

    def _on_local_position(self, msg: MAVLink_message) -> None:
        self._pos = np.array([msg.x, msg.y, msg.z], dtype=float)
        self._vel = np.array([msg.vx, msg.vy, msg.vz], dtype=float)

    def _on_attitude_quaternion(self, msg: MAVLink_message) -> None:
        self._q = np.array([msg.q1, msg.q2, msg.q3, msg.q4], dtype=float)
        self._rates = np.array([msg.rollspeed, msg.pitchspeed, msg.yawspeed], dtype=float)

    def _on_extended_sys_state(self, msg: MAVLink_message) -> None:
        self._landed = LandedPhase.of(msg.landed_state)

    def _on_sys_status(self, msg: MAVLink_message) -> None:
        if msg.voltage_battery not in (0, 0xFFFF):
            self._battery_v = msg.voltage_battery / 1000.0

    def _on_command_ack(self, msg: MAVLink_message) -> None:
        self._acks[int(msg.command)] = int(msg.result)

    def _on_param_value(self, msg: MAVLink_message) -> None:
        name = msg.param_id.decode() if isinstance(msg.param_id, bytes) else msg.param_id
        value = float(msg.param_value)
        if msg.param_type == _MAV.MAV_PARAM_TYPE_INT32:  # PX4 encodes integers bytewise
            value = float(struct.unpack("<i", struct.pack("<f", value))[0])
        self._params[name.rstrip("\x00")] = value

    def _on_obstacle_distance(self, msg: MAVLink_message) -> None:
        self._obstacle_distances = obstacle_distances_of(msg, self._pos.copy(), self._clock.now_s())

    def _on_status_text(self, msg: MAVLink_message) -> None:
        """A text of more than STATUSTEXT's 50 characters comes in chunks (PX4 sends its texts
        of up to 127 so): MAVLink 2's ``id`` and ``chunk_seq``, each chunk but the last full.
        A chunk that continues the last text (its id, the next chunk_seq, after a full chunk)
        is joined to it, so the text is kept, timed and counted once, whole."""
        text = (msg.text.decode() if isinstance(msg.text, bytes) else msg.text).rstrip("\x00")
        chunk = (getattr(msg, "id", 0), getattr(msg, "chunk_seq", 0))
        last = self._status_texts[-1] if self._status_texts else None
        if last is not None and self._open_chunk == (chunk[0], chunk[1] - 1):
            self._status_texts[-1] = StatusText(self._clock.now_s(), last.text + text)
        else:
            self._status_texts.append(StatusText(self._clock.now_s(), text))
            self._texts_received += 1
        self._open_chunk = chunk if len(text) == _STATUSTEXT_CHARS else None

    _HANDLERS = {
        "HEARTBEAT": _on_heartbeat,
        "LOCAL_POSITION_NED": _on_local_position,
        "ATTITUDE_QUATERNION": _on_attitude_quaternion,
        "EXTENDED_SYS_STATE": _on_extended_sys_state,
        "SYS_STATUS": _on_sys_status,
        "COMMAND_ACK": _on_command_ack,
        "PARAM_VALUE": _on_param_value,
        "STATUSTEXT": _on_status_text,
        "OBSTACLE_DISTANCE": _on_obstacle_distance,
    }

    # -- commands ---------------------------------------------------------------------------

    def _command(
        self, command: int, params: tuple[float, ...], attempts: int | None = None
    ) -> CommandOutcome:
        """COMMAND_LONG with retries; waits for its COMMAND_ACK (IN_PROGRESS keeps waiting)."""
        mav = self._require_open()
        target = self._require_target()
        p = (*params, *(0.0,) * (7 - len(params)))
        texts_before = self._texts_received
        for confirmation in range(attempts or self._command_attempts):
            self._acks.pop(command, None)
            mav.mav.command_long_send(*target, command, confirmation, *p)
            deadline_s = self._clock.now_s() + self._command_timeout_s
            while True:
                self.service_until(deadline_s, stop=lambda: command in self._acks)
                result = self._acks.pop(command, None)
                if result != _MAV.MAV_RESULT_IN_PROGRESS:
                    break
                deadline_s = self._clock.now_s() + self._command_timeout_s
            if result is not None:
                new = min(self._texts_received - texts_before, len(self._status_texts))
                recent = list(self._status_texts)[len(self._status_texts) - new :]
                texts = "; ".join(t.text for t in recent)
                name = (
                    _MAV.enums["MAV_RESULT"][result].name
                    if result in _MAV.enums["MAV_RESULT"]
                    else str(result)
                )
                detail = name if not texts else f"{name} ({texts})"
                return CommandOutcome(result == _MAV.MAV_RESULT_ACCEPTED, detail)
        return CommandOutcome(False, f"no COMMAND_ACK for command {command}")

    def _set_mode(self, mode: str) -> CommandOutcome:
        main, sub = PX4_MAIN_SUB[mode]
        return self._command(
            _MAV.MAV_CMD_DO_SET_MODE, (_MAV.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, main, sub)
        )

    def _set_param(self, name: str, value: float) -> CommandOutcome:
        mav = self._require_open()
        target = self._require_target()
        for _ in range(self._command_attempts):
            self._params.pop(name, None)
            mav.mav.param_set_send(*target, name.encode(), value, _MAV.MAV_PARAM_TYPE_REAL32)
            deadline_s = self._clock.now_s() + self._command_timeout_s
            self.service_until(deadline_s, stop=lambda: name in self._params)
            if name in self._params:
                echoed = self._params[name]
                ok = math.isclose(echoed, value, rel_tol=1e-6, abs_tol=1e-6)
                return CommandOutcome(ok, "" if ok else f"{name} stayed {echoed}")
        return CommandOutcome(False, f"no PARAM_VALUE for {name}")

    def _telemetry_complete(self) -> bool:
        return bool(np.all(np.isfinite(self._pos)) and np.all(np.isfinite(self._q)))

    def _require_open(self) -> mavutil.mavfile:
        if self._mav is None:
            raise LinkError(f"link {self._url} is not connected; call connect() first")
        return self._mav

    def _require_target(self) -> tuple[int, int]:
        if self._target is None:
            raise LinkError(f"no autopilot seen on {self._url} yet")
        return self._target


def _is_autopilot(msg: MAVLink_message) -> bool:
    return msg.autopilot != _MAV.MAV_AUTOPILOT_INVALID and msg.type != _MAV.MAV_TYPE_GCS
