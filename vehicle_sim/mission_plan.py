"""A mission as the simulated autopilot flies it: items in local NED, as PX4's navigator takes
them from the MAVLink mission protocol ([MAVLink] mission microservice, [PX4-params] NAV_*).

Supported items: NAV_WAYPOINT (param1 hold time [s], param2 acceptance radius [m]),
NAV_TAKEOFF, NAV_LAND, NAV_RETURN_TO_LAUNCH and DO_CHANGE_SPEED (param2 speed [m/s]). Any
other command is refused at upload, with the reason, never silently skipped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink2

NAV_WAYPOINT = mavlink2.MAV_CMD_NAV_WAYPOINT
NAV_TAKEOFF = mavlink2.MAV_CMD_NAV_TAKEOFF
NAV_LAND = mavlink2.MAV_CMD_NAV_LAND
NAV_RETURN_TO_LAUNCH = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
DO_CHANGE_SPEED = mavlink2.MAV_CMD_DO_CHANGE_SPEED
SUPPORTED_COMMANDS: dict[int, str] = {
    NAV_WAYPOINT: "NAV_WAYPOINT",
    NAV_TAKEOFF: "NAV_TAKEOFF",
    NAV_LAND: "NAV_LAND",
    NAV_RETURN_TO_LAUNCH: "NAV_RETURN_TO_LAUNCH",
    DO_CHANGE_SPEED: "DO_CHANGE_SPEED",
}
POSITION_COMMANDS = frozenset({NAV_WAYPOINT, NAV_TAKEOFF, NAV_LAND})


@dataclass(frozen=True)
class MissionItem:
    """One mission item.

    Attributes:
        command: MAV_CMD of the item (one of SUPPORTED_COMMANDS).
        pos_ned_m: (3,) local NED target [m] for position items; NaN components keep the
            current value (e.g. a landing where the vehicle is).
        params: param1..param4 as sent.
    """

    command: int
    pos_ned_m: tuple[float, float, float] = (math.nan, math.nan, math.nan)
    params: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)

    @property
    def name(self) -> str:
        return SUPPORTED_COMMANDS[self.command]

    @property
    def hold_s(self) -> float:
        """Time to hold at a waypoint before going on [s]."""
        p1 = self.params[0]
        return p1 if self.command == NAV_WAYPOINT and math.isfinite(p1) and p1 > 0 else 0.0

    def acceptance_m(self, default_m: float) -> float:
        """Horizontal distance at which a waypoint counts as reached [m]."""
        p2 = self.params[1]
        return p2 if self.command == NAV_WAYPOINT and math.isfinite(p2) and p2 > 0 else default_m

    @property
    def speed_mps(self) -> float | None:
        """The speed a DO_CHANGE_SPEED sets [m/s], None for other items or 'no change'."""
        p2 = self.params[1]
        ok = self.command == DO_CHANGE_SPEED and math.isfinite(p2) and p2 > 0
        return p2 if ok else None


def unsupported_reason(command: int) -> str | None:
    """Why an item cannot be flown, or None when it can."""
    if command in SUPPORTED_COMMANDS:
        return None
    return (
        f"Mission item command {command} unsupported; use {', '.join(SUPPORTED_COMMANDS.values())}"
    )
