"""The MAVLink mission protocol, as PX4 serves it ([MAVLink] mission microservice).

Upload: MISSION_COUNT -> MISSION_REQUEST_INT for each item in turn -> MISSION_ITEM_INT ... ->
MISSION_ACK. Download: MISSION_REQUEST_LIST -> MISSION_COUNT, MISSION_REQUEST_INT(seq) ->
MISSION_ITEM_INT. MISSION_CLEAR_ALL and MISSION_SET_CURRENT are answered with MISSION_ACK and
MISSION_CURRENT. Items in a global frame are mapped to local NED around home; an item the
simulator cannot fly (another command, another frame, another mission type such as a fence)
ends the upload at once with a MISSION_ACK saying so and a STATUSTEXT with the reason, never
silence. Pure: it returns the messages to send.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.geodetic import GeodeticOrigin
from vehicle_sim.mission_plan import POSITION_COMMANDS, MissionItem, unsupported_reason

_FACTORY = mavlink2.MAVLink(None)
_GLOBAL_FRAMES = {
    mavlink2.MAV_FRAME_GLOBAL_INT: False,  # -> relative altitude?
    mavlink2.MAV_FRAME_GLOBAL: False,
    mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: True,
    mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT: True,
}
_NO_POSITION_FRAMES = {mavlink2.MAV_FRAME_MISSION}


@dataclass(frozen=True)
class MissionReply:
    """Messages to send to the client, and a reason for a STATUSTEXT ("" if none)."""

    messages: tuple[mavlink2.MAVLink_message, ...] = ()
    problem: str = ""


class MissionProtocol:
    """Mission upload/download state for one simulator (see the module docstring)."""

    def __init__(self, sim, origin: GeodeticOrigin) -> None:
        self._sim = sim
        self._origin = origin
        self._stored: list[mavlink2.MAVLink_message] = []  # as uploaded, for downloads
        self._incoming: list[mavlink2.MAVLink_message] | None = None
        self._expected = 0
        self._count = 0

    def on_count(self, msg) -> MissionReply:
        if getattr(msg, "mission_type", 0) != mavlink2.MAV_MISSION_TYPE_MISSION:
            return self._ack(msg, mavlink2.MAV_MISSION_UNSUPPORTED, "Only missions, no fence/rally")
        if msg.count == 0:
            return self._finish(msg, [])
        self._incoming, self._expected, self._count = [], 0, int(msg.count)
        return MissionReply((self._request(msg, 0),))

    def on_item_int(self, msg) -> MissionReply:
        if self._incoming is None:
            return self._ack(msg, mavlink2.MAV_MISSION_ERROR, "Mission item without MISSION_COUNT")
        if msg.seq != self._expected:  # a repeat or a gap: ask again for the one expected
            return MissionReply((self._request(msg, self._expected),))
        reason = unsupported_reason(msg.command) or self._frame_problem(msg)
        if reason:
            self._incoming = None
            code = (
                mavlink2.MAV_MISSION_UNSUPPORTED_FRAME
                if reason.startswith("Mission item frame")
                else mavlink2.MAV_MISSION_UNSUPPORTED
            )
            return self._ack(msg, code, reason)
        self._incoming.append(msg)
        self._expected += 1
        if self._expected < self._count:
            return MissionReply((self._request(msg, self._expected),))
        return self._finish(msg, self._incoming)

    def on_request_list(self, msg) -> MissionReply:
        if getattr(msg, "mission_type", 0) != mavlink2.MAV_MISSION_TYPE_MISSION:
            count = _FACTORY.mission_count_encode(
                msg.get_srcSystem(), msg.get_srcComponent(), 0, msg.mission_type
            )
            return MissionReply((count,))
        count = _FACTORY.mission_count_encode(
            msg.get_srcSystem(), msg.get_srcComponent(), len(self._stored)
        )
        return MissionReply((count,))

    def on_request_item(self, msg) -> MissionReply:
        if not 0 <= msg.seq < len(self._stored):
            return self._ack(msg, mavlink2.MAV_MISSION_INVALID_SEQUENCE, "No such mission item")
        item = self._stored[msg.seq]
        out = _FACTORY.mission_item_int_encode(
            msg.get_srcSystem(),
            msg.get_srcComponent(),
            msg.seq,
            item.frame,
            item.command,
            int(msg.seq == self._sim.mission_current),
            item.autocontinue,
            item.param1,
            item.param2,
            item.param3,
            item.param4,
            item.x,
            item.y,
            item.z,
        )
        return MissionReply((out,))

    def on_clear_all(self, msg) -> MissionReply:
        self._stored = []
        self._incoming = None
        self._sim.set_mission(())
        return self._ack(msg, mavlink2.MAV_MISSION_ACCEPTED)

    def on_set_current(self, msg) -> MissionReply:
        result = self._sim.set_mission_current(int(msg.seq))
        if not result.accepted:
            return MissionReply((), result.reason)
        return MissionReply((self.current_message(),))

    def current_message(self) -> mavlink2.MAVLink_message:
        """MISSION_CURRENT: the item flown now, the count and the mission's state."""
        total = len(self._stored)
        seq = self._sim.mission_current
        if total == 0:
            state = mavlink2.MISSION_STATE_NO_MISSION
        elif seq >= total:
            state = mavlink2.MISSION_STATE_COMPLETE
        elif self._sim.state.mode.name == "MISSION":
            state = mavlink2.MISSION_STATE_ACTIVE
        else:
            state = mavlink2.MISSION_STATE_NOT_STARTED
        return _FACTORY.mission_current_encode(min(seq, max(total - 1, 0)), total, state)

    # -- helpers --------------------------------------------------------------------------------

    def _frame_problem(self, msg) -> str:
        if msg.command not in POSITION_COMMANDS:
            return ""
        if msg.frame in _GLOBAL_FRAMES or msg.frame in _NO_POSITION_FRAMES:
            return ""
        return f"Mission item frame {msg.frame} unsupported; use a global frame (6 or 5)"

    def _to_item(self, msg) -> MissionItem:
        params = (msg.param1, msg.param2, msg.param3, msg.param4)
        if msg.command not in POSITION_COMMANDS or msg.frame not in _GLOBAL_FRAMES:
            return MissionItem(msg.command, params=params)
        lat = msg.x / 1e7 if msg.x != 0 or msg.y != 0 else math.nan
        lon = msg.y / 1e7 if msg.x != 0 or msg.y != 0 else math.nan
        home_amsl_m = self._origin.alt_amsl_m + self._sim.state.home_alt_amsl_offset_m
        alt = msg.z + (home_amsl_m if _GLOBAL_FRAMES[msg.frame] else 0.0)
        here = self._origin.to_global(tuple(self._sim.state.pos_ned_m))
        north, east, down = self._origin.to_local(
            lat if math.isfinite(lat) else here[0],
            lon if math.isfinite(lon) else here[1],
            alt,
        )
        if not math.isfinite(lat):
            north = east = math.nan  # "here": where the vehicle is when it gets to the item
        return MissionItem(msg.command, (north, east, down), params)

    def _finish(self, msg, items: list) -> MissionReply:
        self._stored = list(items)
        self._incoming = None
        self._sim.set_mission(tuple(self._to_item(m) for m in items))
        return self._ack(msg, mavlink2.MAV_MISSION_ACCEPTED)

    def _request(self, msg, seq: int):
        return _FACTORY.mission_request_int_encode(msg.get_srcSystem(), msg.get_srcComponent(), seq)

    def _ack(self, msg, code: int, problem: str = "") -> MissionReply:
        ack = _FACTORY.mission_ack_encode(
            msg.get_srcSystem(), msg.get_srcComponent(), code, getattr(msg, "mission_type", 0)
        )
        return MissionReply((ack,), problem)
