"""PX4-like failsafe conditions and their actions (pure, on simulated time).

Conditions ([PX4-params]): offboard setpoints lost for COM_OF_LOSS_T (action COM_OBL_RC_ACT),
a pilot's sticks lost for COM_RC_LOSS_T in a manual mode (action NAV_RCL_ACT; the commander
watches the sticks),
no ground-station heartbeat for COM_DL_LOSS_T while NAV_DLL_ACT is set (data-link loss), and
battery below BAT_LOW_THR (a warning), BAT_CRIT_THR and BAT_EMERGEN_THR (action
COM_LOW_BAT_ACT). As in PX4's failsafe framework (v1.14+), the vehicle first holds for
COM_FAIL_ACT_T so a pilot can take over, then the action runs (at once when that delay is 0);
a mode change by the pilot in the meantime cancels it. COM_OBL_RC_ACT's position, altitude
and manual fallbacks (0-2) are a hold here, also while sticks are live (PX4 would hand the
vehicle to them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from vehicle_sim.params import Px4Params

FailsafeAction = Literal["hold", "rtl", "land", "disarm"]

# COM_OBL_RC_ACT: 0 position, 1 altitude, 2 manual, 3 return, 4 land, 5 hold, 6 terminate,
# 7 disarm.
OFFBOARD_LOSS_ACTIONS: dict[int, FailsafeAction] = {
    0: "hold", 1: "hold", 2: "hold", 3: "rtl", 4: "land", 5: "hold", 6: "disarm", 7: "disarm",
}  # fmt: skip
# NAV_DLL_ACT: 0 disabled, 1 hold, 2 return, 3 land, 5 terminate, 6 disarm.
DATALINK_LOSS_ACTIONS: dict[int, FailsafeAction] = {
    1: "hold", 2: "rtl", 3: "land", 5: "disarm", 6: "disarm",
}  # fmt: skip

# NAV_RCL_ACT: 1 hold, 2 return, 3 land, 5 terminate, 6 disarm (4, an old "RC auto recovery",
# is no longer PX4's: a hold).
MANUAL_CONTROL_LOSS_ACTIONS: dict[int, FailsafeAction] = {
    1: "hold", 2: "rtl", 3: "land", 4: "hold", 5: "disarm", 6: "disarm",
}  # fmt: skip


@dataclass(frozen=True)
class _Limits:
    """The parameters :meth:`FailsafeMonitor.check` reads at every stretch of physics, read
    once per parameter version: NAV_DLL_ACT, COM_DL_LOSS_T [s], the battery thresholds
    (fractions) and COM_LOW_BAT_ACT."""

    datalink_action: int
    datalink_loss_s: float
    battery_low: float
    battery_critical: float
    battery_emergency: float
    battery_action: int

    @classmethod
    def of(cls, params: Px4Params) -> _Limits:
        p = params.get
        return cls(
            int(p("NAV_DLL_ACT")),
            p("COM_DL_LOSS_T"),
            p("BAT_LOW_THR"),
            p("BAT_CRIT_THR"),
            p("BAT_EMERGEN_THR"),
            int(p("COM_LOW_BAT_ACT")),
        )


@dataclass(frozen=True)
class Trigger:
    """A failsafe that fired: what to do and why (for the STATUSTEXT)."""

    action: FailsafeAction
    reason: str


class FailsafeMonitor:
    """Watches the data link and the battery; the commander watches offboard setpoints."""

    def __init__(self, params: Px4Params) -> None:
        self._params = params
        self._last_gcs_s: float | None = None
        self._link_lost = False
        self._battery_level = 0  # 0 ok, 1 low, 2 critical, 3 emergency

    def gcs_heartbeat(self, t_s: float) -> None:
        """A ground-station heartbeat arrived (the data link is alive)."""
        self._last_gcs_s = t_s
        self._link_lost = False

    def offboard_lost(self) -> Trigger:
        action = int(self._params.get("COM_OBL_RC_ACT"))
        return Trigger(OFFBOARD_LOSS_ACTIONS.get(action, "hold"), "offboard setpoints lost")

    def manual_control_lost(self) -> Trigger:
        action = int(self._params.get("NAV_RCL_ACT"))
        return Trigger(MANUAL_CONTROL_LOSS_ACTIONS.get(action, "hold"), "manual control lost")

    def check(
        self, t_s: float, flying: bool, battery_remaining: float
    ) -> tuple[list[str], Trigger | None]:
        """Warnings to announce and the failsafe that fires now (None if none)."""
        warnings: list[str] = []
        trigger = None
        limits = self._params.derived(_Limits.of)
        action = limits.datalink_action
        silent_s = None if self._last_gcs_s is None else t_s - self._last_gcs_s
        if (
            flying
            and action in DATALINK_LOSS_ACTIONS
            and not self._link_lost
            and (silent_s is not None and silent_s > limits.datalink_loss_s)
        ):
            self._link_lost = True
            trigger = Trigger(DATALINK_LOSS_ACTIONS[action], "data link lost")
        level = (
            int(battery_remaining < limits.battery_low)
            + int(battery_remaining < limits.battery_critical)
            + int(battery_remaining < limits.battery_emergency)
        )
        if level > self._battery_level:
            self._battery_level = level
            name = ("", "low", "critical", "emergency")[level]
            warnings.append(f"Battery {name}: {battery_remaining:.0%} remaining")
            bat_action = limits.battery_action
            if flying and trigger is None and level >= 2 and bat_action in (2, 3):
                act: FailsafeAction = "rtl" if bat_action == 3 and level == 2 else "land"
                trigger = Trigger(act, f"battery {name}")
        return warnings, trigger

    def battery_thresholds(self) -> tuple[float, float, float]:
        """BAT_LOW_THR, BAT_CRIT_THR, BAT_EMERGEN_THR (fractions of charge remaining): the
        charges below which :meth:`check` warns and may act."""
        limits = self._params.derived(_Limits.of)
        return limits.battery_low, limits.battery_critical, limits.battery_emergency

    def next_check_s(self, t_s: float) -> float | None:
        """When the data link would count as lost, if it is being watched."""
        if self._last_gcs_s is None or self._link_lost:
            return None
        limits = self._params.derived(_Limits.of)
        if limits.datalink_action == 0:
            return None
        return max(t_s, self._last_gcs_s + limits.datalink_loss_s)
