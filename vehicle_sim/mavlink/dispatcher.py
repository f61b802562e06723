"""Vehicle-side handling of one received MAVLink message: what PX4's mavlink receiver does.

Checks the target, routes to commands / offboard / params / services, and returns the messages
to send. Touches only the simulator's public API and the link's scheduler; no sockets, no clock
(time comes in as arguments).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink import params, services
from vehicle_sim.mavlink.codec import COMPONENT_ID, SYSTEM_ID
from vehicle_sim.mavlink.commands import (
    CMD_DO_SET_MODE,
    MAV_RESULT_FAILED,
    MAV_RESULT_UNSUPPORTED,
    MAV_SEVERITY_CRITICAL,
    MAV_SEVERITY_WARNING,
    CommandContext,
    CommandOutcome,
    Notice,
    handle_command,
)
from vehicle_sim.mavlink.manual_control import parse_manual_control
from vehicle_sim.mavlink.mission_protocol import MissionProtocol, MissionReply
from vehicle_sim.mavlink.offboard import SetpointResult, parse_global_setpoint, parse_setpoint
from vehicle_sim.mavlink.scheduler import RateScheduler
from vehicle_sim.mavlink.stats import StatsCounter
from vehicle_sim.mavlink.telemetry import TelemetryContext
from vehicle_sim.vehicle_types import FlightMode

if TYPE_CHECKING:
    from vehicle_sim import Simulator

_FACTORY = mavlink2.MAVLink(None)
INT32_MAX = 2**31 - 1


@dataclass(frozen=True)
class Outgoing:
    """A message to send: to the sender of the request only, or to every peer of every link;
    or a notice (severity, text) for every peer, which the endpoint sends as STATUSTEXT."""

    msg: mavlink2.MAVLink_message | None = None
    broadcast: bool = False
    notice: Notice | None = None


_GLOBAL_FRAMES = frozenset(
    {
        mavlink2.MAV_FRAME_GLOBAL,
        mavlink2.MAV_FRAME_GLOBAL_INT,
        mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    }
)
_RELATIVE_ALT_FRAMES = frozenset(
    {mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT, mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT}
)


def _for_us(msg: mavlink2.MAVLink_message) -> bool:
    """Addressed to this system (or all) and, where the message names one, this component."""
    system_ok = msg.target_system in (0, SYSTEM_ID)
    component = getattr(msg, "target_component", None)
    return system_ok and (component is None or component in (0, COMPONENT_ID))


class Dispatcher:
    """Handles received messages for one simulator.

    Args:
        sim: the simulator (only its public API is used).
        telemetry: telemetry context (origin, battery cells) for on-request messages.
        stats: counters to update.
        on_setpoint: called with the setpoint's ``time_boot_ms`` each time a setpoint reaches
            the simulator while it is in OFFBOARD (used to trace setpoint-to-actuation latency).
    """

    def __init__(
        self,
        sim: Simulator,
        telemetry: TelemetryContext,
        stats: StatsCounter,
        on_setpoint: Callable[[int], None] | None = None,
    ) -> None:
        self._sim = sim
        self._telemetry = telemetry
        self._stats = stats
        self._on_setpoint = on_setpoint
        self.missions = MissionProtocol(sim, telemetry.origin)
        # Messages addressed to a system: checked once, in handle(), before their handler.
        self._addressed: dict[str, Callable[..., list[Outgoing]]] = {
            "COMMAND_LONG": self._command_long,
            "COMMAND_INT": self._command_int,
            "SET_POSITION_TARGET_LOCAL_NED": self._setpoint,
            "SET_POSITION_TARGET_GLOBAL_INT": self._global_setpoint,
            "PARAM_REQUEST_LIST": self._param_request_list,
            "PARAM_REQUEST_READ": self._param_request_read,
            "PARAM_SET": self._param_set,
            "MISSION_COUNT": self._mission(self.missions.on_count),
            "MISSION_ITEM_INT": self._mission(self.missions.on_item_int),
            "MISSION_ITEM": self._mission_float_item,
            "MISSION_REQUEST_LIST": self._mission(self.missions.on_request_list),
            "MISSION_REQUEST_INT": self._mission(self.missions.on_request_item),
            "MISSION_REQUEST": self._mission(self.missions.on_request_item),
            "MISSION_CLEAR_ALL": self._mission(self.missions.on_clear_all),
            "MISSION_SET_CURRENT": self._mission(self.missions.on_set_current),
            "FILE_TRANSFER_PROTOCOL": self._ftp,
            "LOG_REQUEST_LIST": self._log_request_list,
            "SET_MODE": self._set_mode_message,
            "SET_ATTITUDE_TARGET": self._not_flown(
                "Offboard: attitude setpoints not supported, send velocity or position"
            ),
        }
        # Services with their own addressing rules (a PING to 0 is a request to all).
        self._services: dict[str, Callable[..., list[Outgoing]]] = {
            "HEARTBEAT": self._heartbeat,
            "PING": self._ping,
            "TIMESYNC": self._timesync,
            "MANUAL_CONTROL": self._manual_control,  # its target field is ``target``
        }

    def handle(
        self, msg: mavlink2.MAVLink_message, scheduler: RateScheduler, now_ns: int
    ) -> list[Outgoing]:
        """Handle one message from a link; returns what to send. Never raises."""
        handler = self._services.get(msg.get_type())
        if handler is None:
            handler = self._addressed.get(msg.get_type())
            if handler is None:
                return []
            if not _for_us(msg):
                self._stats.add("wrong_target")
                return []
        try:
            return handler(msg, scheduler, now_ns)
        except Exception:  # a hostile message must never stop the endpoint
            self._stats.add("handler_errors")
            return []

    # -- commands -----------------------------------------------------------------------------

    def _command_long(self, msg, scheduler, _now_ns) -> list[Outgoing]:
        p = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
        return self._command(msg, msg.command, p, scheduler)

    def _command_int(self, msg, scheduler, _now_ns) -> list[Outgoing]:
        """COMMAND_INT -> the COMMAND_LONG parameters: x, y in degrees for a global frame (else
        metres, [MAVLink] COMMAND_INT; INT32_MAX is NaN, "unset"), z as altitude above mean sea
        level. DO_ORBIT's z is AMSL in every frame, as PX4 reads it (which ignores the frame):
        MAVSDK's do_orbit sends its absolute altitude in MAV_FRAME_GLOBAL_RELATIVE_ALT."""
        x, y, z = float(msg.x), float(msg.y), float(msg.z)
        x, y = (math.nan if v == INT32_MAX else v for v in (x, y))  # INT32_MAX: unset
        if msg.frame in _GLOBAL_FRAMES:
            x, y = x / 1e7, y / 1e7
            if msg.frame in _RELATIVE_ALT_FRAMES and msg.command != mavlink2.MAV_CMD_DO_ORBIT:
                z += self._telemetry.origin.alt_amsl_m + self._sim.state.home_alt_amsl_offset_m
        else:
            x, y = x / 1e4, y / 1e4
        p = (msg.param1, msg.param2, msg.param3, msg.param4, x, y, z)
        return self._command(msg, msg.command, p, scheduler)

    def _command(self, msg, command: int, p, scheduler: RateScheduler) -> list[Outgoing]:
        self._stats.add("commands_received")
        ctx = CommandContext(self._sim, self._telemetry, scheduler)
        try:
            outcome = handle_command(command, p, ctx)
        except Exception:  # a bug must still be answered: a command always gets its ACK
            self._stats.add("handler_errors")
            outcome = CommandOutcome(MAV_RESULT_FAILED)
        if outcome.result == MAV_RESULT_UNSUPPORTED:
            self._stats.add("commands_unsupported")
        ack = _FACTORY.command_ack_encode(
            command=command,
            result=outcome.result,
            progress=0,
            result_param2=0,
            target_system=msg.get_srcSystem(),
            target_component=msg.get_srcComponent(),
        )
        out = [Outgoing(ack)] + [Outgoing(reply) for reply in outcome.replies]
        return out + self._notices(outcome.notices)

    def _set_mode_message(self, msg, scheduler, _now_ns) -> list[Outgoing]:
        """Legacy SET_MODE message: handled like DO_SET_MODE, answered with a COMMAND_ACK."""
        custom = int(msg.custom_mode)
        p = (
            float(msg.base_mode),
            float((custom >> 16) & 0xFF),
            float((custom >> 24) & 0xFF),
            0.0,
            0.0,
            0.0,
            0.0,
        )
        outcome = handle_command(
            CMD_DO_SET_MODE, p, CommandContext(self._sim, self._telemetry, scheduler)
        )
        ack = _FACTORY.command_ack_encode(
            command=CMD_DO_SET_MODE,
            result=outcome.result,
            target_system=msg.get_srcSystem(),
            target_component=msg.get_srcComponent(),
        )
        return [Outgoing(ack)] + self._notices(outcome.notices)

    # -- offboard -----------------------------------------------------------------------------

    def _setpoint(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        result = parse_setpoint(
            msg.coordinate_frame,
            msg.type_mask,
            (msg.vx, msg.vy, msg.vz),
            msg.yaw,
            msg.yaw_rate,
            (msg.x, msg.y, msg.z),
        )
        return self._fly_setpoint(msg, result)

    def _global_setpoint(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        result = parse_global_setpoint(
            msg.coordinate_frame,
            msg.type_mask,
            msg.lat_int,
            msg.lon_int,
            msg.alt,
            (msg.vx, msg.vy, msg.vz),
            msg.yaw,
            msg.yaw_rate,
            self._telemetry.origin,
            self._sim.state.home_alt_amsl_offset_m,
        )
        return self._fly_setpoint(msg, result)

    def _fly_setpoint(self, msg, result: SetpointResult) -> list[Outgoing]:
        if result.setpoint is not None:
            try:
                self._sim.set_velocity_setpoint(result.setpoint)
            except ValueError as exc:
                result = SetpointResult(None, f"Offboard: setpoint rejected: {exc}")
        if result.setpoint is None:
            self._stats.add("setpoints_rejected")
            return self._notices(((MAV_SEVERITY_WARNING, result.reason),))
        self._stats.add("setpoints_accepted")
        if self._on_setpoint is not None and self._sim.state.mode == FlightMode.OFFBOARD:
            self._on_setpoint(int(msg.time_boot_ms))
        return []

    # -- parameters ---------------------------------------------------------------------------

    def _param_reply(self, reply: params.ParamReply, broadcast: bool) -> list[Outgoing]:
        if not reply.values:
            self._stats.add("params_unknown")
        out = [Outgoing(m, broadcast) for m in reply.values]
        if reply.problem and reply.values:
            out += self._notices(((MAV_SEVERITY_CRITICAL, reply.problem),))
        elif reply.problem:  # an unknown name or index: PX4 says "[pm] unknown param" (info)
            out += self._notices(((mavlink2.MAV_SEVERITY_INFO, reply.problem),))
        return out

    def _param_request_list(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        return self._param_reply(params.request_list(self._sim), broadcast=False)

    def _param_request_read(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        reply = params.request_read(self._sim, msg.param_id, msg.param_index)
        return self._param_reply(reply, broadcast=False)

    def _param_set(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        reply = params.param_set(self._sim, msg.param_id, msg.param_value, msg.param_type)
        return self._param_reply(reply, broadcast=True)

    # -- small services -----------------------------------------------------------------------

    def _heartbeat(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        """A ground station's heartbeat keeps the data link alive (NAV_DLL_ACT)."""
        if msg.type == mavlink2.MAV_TYPE_GCS:
            self._sim.on_gcs_heartbeat()
        return []

    def _ping(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        reply = services.ping_reply(msg)
        return [] if reply is None else [Outgoing(reply)]

    def _timesync(self, msg, _scheduler, now_ns: int) -> list[Outgoing]:
        reply = services.timesync_reply(msg, now_ns)
        return [] if reply is None else [Outgoing(reply)]

    def _mission(self, handler: Callable[..., MissionReply]) -> Callable[..., list[Outgoing]]:
        """A mission-protocol handler as a dispatcher handler (reply to the sender, problems
        as STATUSTEXT)."""

        def handle(msg, _scheduler, _now_ns) -> list[Outgoing]:
            reply = handler(msg)
            out = [Outgoing(m) for m in reply.messages]
            if reply.problem:
                out += self._notices(((MAV_SEVERITY_WARNING, reply.problem),))
            return out

        return handle

    def _mission_float_item(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        """The float MISSION_ITEM is not served (AUTOPILOT_VERSION does not claim it): say so."""
        ack = _FACTORY.mission_ack_encode(
            msg.get_srcSystem(),
            msg.get_srcComponent(),
            mavlink2.MAV_MISSION_UNSUPPORTED,
            getattr(msg, "mission_type", 0),
        )
        text = "Mission: send MISSION_ITEM_INT, MISSION_ITEM is not supported"
        return [Outgoing(ack), *self._notices(((MAV_SEVERITY_WARNING, text),))]

    def _not_flown(self, text: str) -> Callable[..., list[Outgoing]]:
        """A handler for a message the simulator does not act on: it says so (STATUSTEXT,
        limited per kind like every notice) instead of dropping the message in silence."""

        def handle(_msg, _scheduler, _now_ns) -> list[Outgoing]:
            return self._notices(((MAV_SEVERITY_WARNING, text),))

        return handle

    def _manual_control(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        """MANUAL_CONTROL (MAVSDK's manual_control, QGC's virtual joystick): the sticks fly
        POSCTL/ALTCTL and may override auto modes or OFFBOARD (``Simulator.set_sticks``).
        Another system's is counted as ``wrong_target``; out-of-range axes are clamped and an
        axis marked invalid drops the message, each said in a STATUSTEXT; sticks that the
        simulator ignores (COM_RC_IN_MODE 0 or 4) are said to be ignored too."""
        if msg.target not in (0, SYSTEM_ID):
            self._stats.add("wrong_target")
            return []
        parsed = parse_manual_control(msg.x, msg.y, msg.z, msg.r)
        notices: list[Notice] = []
        if parsed.problem:
            notices.append((MAV_SEVERITY_WARNING, parsed.problem))
        if parsed.sticks is None:
            self._stats.add("manual_control_rejected")
        elif self._sim.set_sticks(parsed.sticks):
            self._stats.add("manual_control_accepted")
        else:
            self._stats.add("manual_control_rejected")
            mode = int(self._sim.get_param("COM_RC_IN_MODE"))
            notices.append((MAV_SEVERITY_WARNING, f"Sticks ignored: COM_RC_IN_MODE is {mode}"))
        return self._notices(tuple(notices))

    def _ftp(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        return [Outgoing(services.ftp_nak_reply(msg))]

    def _log_request_list(self, msg, _scheduler, _now_ns) -> list[Outgoing]:
        return [Outgoing(services.empty_log_list_reply(msg))]

    def _notices(self, notices: tuple[Notice, ...]) -> list[Outgoing]:
        return [Outgoing(notice=notice, broadcast=True) for notice in notices]
