"""PX4-like mission navigator: which target the position controller flies in AUTO.MISSION.

Pure state on simulated time. :meth:`MissionNavigator.step` looks at the vehicle's position and
says what to do: fly to a target (held by the commander's position control), land there, or
return to launch; it records each item reached (MISSION_ITEM_REACHED) and the current item
(MISSION_CURRENT). Waypoints count as reached within their acceptance radius (else NAV_ACC_RAD)
horizontally and NAV_MC_ALT_RAD vertically, then hold for their hold time ([PX4-params]).
A mission started on the ground takes off first (the commander flies it), to
:meth:`MissionNavigator.takeoff_down_m`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from vehicle_sim.mission_plan import (
    DO_CHANGE_SPEED,
    NAV_LAND,
    NAV_RETURN_TO_LAUNCH,
    NAV_TAKEOFF,
    NAV_WAYPOINT,
    POSITION_COMMANDS,
    MissionItem,
)

NAV_ACC_RAD_M = 2.0  # PX4's default horizontal acceptance radius
NAV_MC_ALT_RAD_M = 0.8  # PX4's default vertical acceptance radius (multicopter)
TAKEOFF_ACCEPT_M = 0.3

Action = Literal["fly", "land", "rtl", "done"]


@dataclass(frozen=True)
class NavigatorOutput:
    """What the commander should do now: fly to ``target_ned_m`` (NaN: keep that component),
    land at it, start RTL, or hold where the mission ended ("done")."""

    action: Action
    target_ned_m: np.ndarray
    speed_mps: float | None


class MissionNavigator:
    """Flies a list of :class:`MissionItem` from ``current``."""

    def __init__(self, items: tuple[MissionItem, ...], current: int = 0) -> None:
        if not 0 <= current <= len(items):
            raise ValueError(f"mission item {current} out of range 0..{len(items) - 1}")
        self.items = items
        self.current = current
        self.reached: list[int] = []
        self._hold_since_s: float | None = None
        self._speed_mps: float | None = None

    @property
    def speed_mps(self) -> float | None:
        """The speed the last DO_CHANGE_SPEED set [m/s], None for the default cruise speed."""
        return self._speed_mps

    @property
    def complete(self) -> bool:
        return self.current >= len(self.items)

    def takeoff_down_m(self, floor_down_m: float) -> float:
        """Where this mission, started on the ground, climbs before its items [m, NED down]:
        to ``floor_down_m`` (MIS_TAKEOFF_ALT above home), or higher, to its first position
        item's altitude when that item is a NAV_TAKEOFF or a waypoint: PX4 flies the take-off
        as a NAV_TAKEOFF, and before a first waypoint inserts one to that waypoint's altitude,
        at least MIS_TAKEOFF_ALT (``calculate_takeoff_altitude``, [PX4-mission-takeoff]); it
        reports either climb as a take-off."""
        first = next(
            (i for i in self.items[self.current :] if i.command in POSITION_COMMANDS), None
        )
        climbs_to = (NAV_TAKEOFF, NAV_WAYPOINT)
        if first is None or first.command not in climbs_to or not math.isfinite(first.pos_ned_m[2]):
            return floor_down_m
        return min(floor_down_m, first.pos_ned_m[2])

    def step(self, t_s: float, pos_ned_m: np.ndarray) -> NavigatorOutput:
        """Advance over every item already satisfied at ``pos_ned_m``; the action for the rest."""
        while not self.complete:
            item = self.items[self.current]
            if item.command == DO_CHANGE_SPEED:
                self._speed_mps = item.speed_mps or self._speed_mps
                self._advance()
                continue
            if item.command == NAV_RETURN_TO_LAUNCH:
                self._advance()
                return NavigatorOutput("rtl", pos_ned_m.copy(), self._speed_mps)
            target = np.where(np.isfinite(item.pos_ned_m), item.pos_ned_m, pos_ned_m)
            if item.command == NAV_TAKEOFF:
                target[:2] = pos_ned_m[:2]
                if abs(pos_ned_m[2] - target[2]) < TAKEOFF_ACCEPT_M:
                    self._advance()
                    continue
                return NavigatorOutput("fly", target, self._speed_mps)
            horizontal_m = float(np.hypot(*(pos_ned_m[:2] - target[:2])))
            if item.command == NAV_LAND:
                if horizontal_m < item.acceptance_m(NAV_ACC_RAD_M) / 4.0:
                    self._advance()
                    return NavigatorOutput("land", target, self._speed_mps)
                target[2] = pos_ned_m[2]  # go there at this altitude first, as PX4 does
                return NavigatorOutput("fly", target, self._speed_mps)
            arrived = (
                horizontal_m < item.acceptance_m(NAV_ACC_RAD_M)
                and abs(pos_ned_m[2] - target[2]) < NAV_MC_ALT_RAD_M
            )
            if arrived and self._hold_since_s is None:
                self._hold_since_s = t_s
            if arrived and t_s - self._hold_since_s >= item.hold_s - 1e-9:
                self._advance()
                continue
            return NavigatorOutput("fly", target, self._speed_mps)
        return NavigatorOutput("done", np.full(3, math.nan), self._speed_mps)

    def _advance(self) -> None:
        self.reached.append(self.current)
        self.current += 1
        self._hold_since_s = None
