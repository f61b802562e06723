"""COMMAND_LONG / COMMAND_INT handling: a table from MAV_CMD to handler, always an ACK result.

Handlers call the simulator's command API and the link's rate scheduler; they do no I/O. Each
returns a ``CommandOutcome``: the MAV_RESULT for the COMMAND_ACK, messages to send to the
requester (e.g. a requested AUTOPILOT_VERSION) and notices (STATUSTEXT) for everyone.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.orbit import start_orbit
from vehicle_sim.mavlink.scheduler import RateScheduler
from vehicle_sim.mavlink.telemetry import TELEMETRY_BUILDERS, TelemetryContext
from vehicle_sim.vehicle_types import FlightMode

if TYPE_CHECKING:
    from vehicle_sim import CommandResult, Simulator

_FACTORY = mavlink2.MAVLink(None)

MAV_RESULT_ACCEPTED = mavlink2.MAV_RESULT_ACCEPTED
MAV_RESULT_TEMPORARILY_REJECTED = mavlink2.MAV_RESULT_TEMPORARILY_REJECTED
MAV_RESULT_DENIED = mavlink2.MAV_RESULT_DENIED
MAV_RESULT_UNSUPPORTED = mavlink2.MAV_RESULT_UNSUPPORTED
MAV_RESULT_FAILED = mavlink2.MAV_RESULT_FAILED

MAV_SEVERITY_CRITICAL = mavlink2.MAV_SEVERITY_CRITICAL
MAV_SEVERITY_WARNING = mavlink2.MAV_SEVERITY_WARNING
MAV_SEVERITY_INFO = mavlink2.MAV_SEVERITY_INFO

CMD_NAV_RETURN_TO_LAUNCH = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
CMD_NAV_LAND = mavlink2.MAV_CMD_NAV_LAND
CMD_NAV_TAKEOFF = mavlink2.MAV_CMD_NAV_TAKEOFF
CMD_DO_SET_MODE = mavlink2.MAV_CMD_DO_SET_MODE
CMD_DO_REPOSITION = mavlink2.MAV_CMD_DO_REPOSITION
CMD_DO_ORBIT = mavlink2.MAV_CMD_DO_ORBIT
CMD_MISSION_START = mavlink2.MAV_CMD_MISSION_START
CMD_DO_SET_MISSION_CURRENT = mavlink2.MAV_CMD_DO_SET_MISSION_CURRENT
CMD_COMPONENT_ARM_DISARM = mavlink2.MAV_CMD_COMPONENT_ARM_DISARM
CMD_GET_HOME_POSITION = mavlink2.MAV_CMD_GET_HOME_POSITION
CMD_GET_MESSAGE_INTERVAL = mavlink2.MAV_CMD_GET_MESSAGE_INTERVAL
CMD_SET_MESSAGE_INTERVAL = mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL
CMD_REQUEST_MESSAGE = mavlink2.MAV_CMD_REQUEST_MESSAGE
CMD_REQUEST_AUTOPILOT_CAPABILITIES = mavlink2.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES

ARM_FORCE_MAGIC = 21196  # param2 of MAV_CMD_COMPONENT_ARM_DISARM that forces it ([MAVLink])
MODE_FLAG_CUSTOM_MODE_ENABLED = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED

_RESULT_CODES: dict[str, int] = {
    "accepted": MAV_RESULT_ACCEPTED,
    "temporarily_rejected": MAV_RESULT_TEMPORARILY_REJECTED,
    "denied": MAV_RESULT_DENIED,
    "failed": MAV_RESULT_FAILED,
}

Notice = tuple[int, str]
"""(MAV_SEVERITY, text) for a STATUSTEXT."""


@dataclass(frozen=True)
class CommandOutcome:
    """What a command produced.

    Attributes:
        result: MAV_RESULT for the COMMAND_ACK.
        replies: messages for the requester, sent after the ACK.
        notices: STATUSTEXTs for all peers.
    """

    result: int
    replies: tuple[mavlink2.MAVLink_message, ...] = ()
    notices: tuple[Notice, ...] = ()


@dataclass(frozen=True)
class CommandContext:
    """Everything a handler may use: the simulator, telemetry context, the link's scheduler."""

    sim: Simulator
    telemetry: TelemetryContext
    scheduler: RateScheduler


Params = tuple[float, float, float, float, float, float, float]
Handler = Callable[[Params, CommandContext], CommandOutcome]


def _from_sim(result: CommandResult) -> CommandOutcome:
    """The simulator's verdict as a MAV_RESULT (it announces its own reasons as events)."""
    return CommandOutcome(_RESULT_CODES.get(result.result, MAV_RESULT_FAILED))


def _denied(reason: str) -> CommandOutcome:
    return CommandOutcome(MAV_RESULT_DENIED, notices=((MAV_SEVERITY_CRITICAL, reason),))


def arm_disarm(p: Params, ctx: CommandContext) -> CommandOutcome:
    force = p[1] == ARM_FORCE_MAGIC
    if p[0] == 1.0:
        return _from_sim(ctx.sim.arm(force=force))
    if p[0] == 0.0:
        return _from_sim(ctx.sim.disarm(force=force))
    return _denied(f"Arm/disarm: param1 must be 0 or 1, got {p[0]}")


def set_mode(p: Params, ctx: CommandContext) -> CommandOutcome:
    """DO_SET_MODE: only bit 0 of param1 (custom mode) matters; param2/3 main/sub mode."""
    if not all(math.isfinite(v) and 0 <= v < 256 for v in p[:3]):
        return _denied("Set mode: invalid parameters")
    if not int(p[0]) & MODE_FLAG_CUSTOM_MODE_ENABLED:
        return _denied("Set mode: custom mode flag required")
    custom_mode = (int(p[1]) << 16) | (int(p[2]) << 24)
    try:
        mode = FlightMode(custom_mode)
    except ValueError:
        return _denied(f"Set mode: mode {int(p[1])}/{int(p[2])} unsupported")
    return _from_sim(ctx.sim.set_mode(mode))


def takeoff(p: Params, ctx: CommandContext) -> CommandOutcome:
    """NAV_TAKEOFF: param7 is AMSL altitude [m]; NaN or below the minimum -> MIS_TAKEOFF_ALT."""
    default_alt_m = ctx.sim.get_param("MIS_TAKEOFF_ALT")
    alt_m = None
    notices: tuple[Notice, ...] = ()
    if math.isfinite(p[6]):
        requested_m = p[6] - ctx.telemetry.origin.alt_amsl_m
        if requested_m > default_alt_m:
            alt_m = requested_m
        else:
            text = f"Using minimum takeoff altitude: {default_alt_m:.2f} m"
            notices = ((MAV_SEVERITY_INFO, text),)
    outcome = _from_sim(ctx.sim.takeoff(alt_m=alt_m))
    return CommandOutcome(outcome.result, outcome.replies, notices + outcome.notices)


def land(_p: Params, ctx: CommandContext) -> CommandOutcome:
    return _from_sim(ctx.sim.land())


def return_to_launch(_p: Params, ctx: CommandContext) -> CommandOutcome:
    return _from_sim(ctx.sim.set_mode(FlightMode.RTL))


def reposition(p: Params, ctx: CommandContext) -> CommandOutcome:
    """DO_REPOSITION (MAVSDK's goto): param5/6 latitude/longitude [deg], param7 altitude AMSL
    [m]; NaN keeps the current value. Flown in HOLD, as PX4 does; the ground speed (param1)
    is MPC_XY_CRUISE here, a requested one is not applied."""
    lat, lon, alt = p[4], p[5], p[6]
    if any(math.isinf(v) for v in (lat, lon, alt)) or (
        math.isfinite(lat) and not -90.0 <= lat <= 90.0
    ):
        return _denied("Reposition: invalid position")
    origin = ctx.telemetry.origin
    here = origin.to_global(tuple(ctx.sim.state.pos_ned_m))
    north, east, down = origin.to_local(
        lat if math.isfinite(lat) else here[0],
        lon if math.isfinite(lon) else here[1],
        alt if math.isfinite(alt) else here[2],
    )
    return _from_sim(ctx.sim.reposition((north, east, down)))


def do_orbit(p: Params, ctx: CommandContext) -> CommandOutcome:
    """DO_ORBIT (MAVSDK's do_orbit): PX4's Orbit mode, see :mod:`vehicle_sim.mavlink.orbit`."""
    return _from_sim(start_orbit(ctx.sim, p, ctx.telemetry.origin))


def _mission_item(value: float, ctx: CommandContext) -> int | None:
    """A mission item index from a command parameter: None for NaN or negative ("no change");
    ValueError for anything that is not an item of the uploaded mission."""
    if math.isnan(value) or value < 0:
        return None
    count = len(ctx.sim.mission)
    if value != int(value) or not value < count:
        raise ValueError(f"mission item {value:g} does not exist (mission has {count})")
    return int(value)


def mission_start(p: Params, ctx: CommandContext) -> CommandOutcome:
    """MISSION_START: param1 the first item (NaN or -1: the current one), then AUTO.MISSION
    as PX4's commander does; param2 (last item) is not honoured: the mission runs to its end."""
    first = _mission_item(p[0], ctx)
    if first is not None:
        selected = ctx.sim.set_mission_current(first)
        if not selected.accepted:
            return _from_sim(selected)
    return _from_sim(ctx.sim.set_mode(FlightMode.MISSION))


def set_mission_current(p: Params, ctx: CommandContext) -> CommandOutcome:
    """DO_SET_MISSION_CURRENT (what MAVSDK's set_current_mission_item sends): param1 the item
    (-1: keep), param2 1 restarts the mission from item 0; MISSION_CURRENT follows on change."""
    seq = _mission_item(p[0], ctx)
    if p[1] == 1.0 and seq is None:
        seq = 0 if ctx.sim.mission else None
    if seq is None:
        return CommandOutcome(MAV_RESULT_ACCEPTED)
    return _from_sim(ctx.sim.set_mission_current(seq))


def _message_id(value: float) -> int | None:
    if math.isfinite(value) and value >= 0 and value == int(value):
        return int(value)
    return None


def request_message(p: Params, ctx: CommandContext) -> CommandOutcome:
    msg_id = _message_id(p[0])
    builder = TELEMETRY_BUILDERS.get(msg_id) if msg_id is not None else None
    if builder is None:
        return CommandOutcome(MAV_RESULT_DENIED)
    return CommandOutcome(MAV_RESULT_ACCEPTED, (builder(ctx.sim.state, ctx.telemetry),))


def request_capabilities(_p: Params, ctx: CommandContext) -> CommandOutcome:
    return request_message((float(mavlink2.MAVLINK_MSG_ID_AUTOPILOT_VERSION),) + (0.0,) * 6, ctx)


def get_home_position(_p: Params, ctx: CommandContext) -> CommandOutcome:
    return request_message((float(mavlink2.MAVLINK_MSG_ID_HOME_POSITION),) + (0.0,) * 6, ctx)


def set_message_interval(p: Params, ctx: CommandContext) -> CommandOutcome:
    msg_id = _message_id(p[0])
    if msg_id is None or msg_id not in TELEMETRY_BUILDERS:
        return CommandOutcome(MAV_RESULT_DENIED)
    try:
        ctx.scheduler.set_interval_us(msg_id, p[1])
    except ValueError:
        return CommandOutcome(MAV_RESULT_DENIED)
    return CommandOutcome(MAV_RESULT_ACCEPTED)


def get_message_interval(p: Params, ctx: CommandContext) -> CommandOutcome:
    msg_id = _message_id(p[0])
    if msg_id is None or msg_id > 0xFFFF:
        return CommandOutcome(MAV_RESULT_DENIED)
    interval_s = ctx.scheduler.interval_s(msg_id)
    interval_us = -1 if interval_s is None else int(round(interval_s * 1e6))
    return CommandOutcome(
        MAV_RESULT_ACCEPTED, (_FACTORY.message_interval_encode(msg_id, interval_us),)
    )


COMMAND_HANDLERS: dict[int, Handler] = {
    CMD_NAV_RETURN_TO_LAUNCH: return_to_launch,
    CMD_DO_REPOSITION: reposition,
    CMD_DO_ORBIT: do_orbit,
    CMD_MISSION_START: mission_start,
    CMD_DO_SET_MISSION_CURRENT: set_mission_current,
    CMD_NAV_LAND: land,
    CMD_NAV_TAKEOFF: takeoff,
    CMD_DO_SET_MODE: set_mode,
    CMD_COMPONENT_ARM_DISARM: arm_disarm,
    CMD_GET_HOME_POSITION: get_home_position,
    CMD_GET_MESSAGE_INTERVAL: get_message_interval,
    CMD_SET_MESSAGE_INTERVAL: set_message_interval,
    CMD_REQUEST_MESSAGE: request_message,
    CMD_REQUEST_AUTOPILOT_CAPABILITIES: request_capabilities,
}
"""MAV_CMD -> handler; any other command is answered UNSUPPORTED."""


def handle_command(command: int, params: Params, ctx: CommandContext) -> CommandOutcome:
    """Run a command; unknown commands -> UNSUPPORTED, a handler's ValueError -> DENIED."""
    handler = COMMAND_HANDLERS.get(command)
    if handler is None:
        return CommandOutcome(MAV_RESULT_UNSUPPORTED)
    try:
        return handler(params, ctx)
    except ValueError as exc:
        return _denied(f"Command {command}: {exc}")
