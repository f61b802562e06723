"""The failsafe monitor on its own: PX4's battery levels and actions (COM_LOW_BAT_ACT), the data
link's loss and return (NAV_DLL_ACT, COM_DL_LOSS_T) and the offboard-loss actions
(COM_OBL_RC_ACT), as [PX4-params] defines them, on simulated time."""

from __future__ import annotations

import pytest

from vehicle_sim.failsafe import FailsafeMonitor
from vehicle_sim.params import Px4Params

# BAT_LOW_THR 0.15, BAT_CRIT_THR 0.07, BAT_EMERGEN_THR 0.05 (PX4's defaults)
LOW, CRITICAL, EMERGENCY = 0.10, 0.06, 0.04


def _battery_run(action: int, flying: bool = True) -> list[tuple[list[str], object]]:
    monitor = FailsafeMonitor(Px4Params({"COM_LOW_BAT_ACT": action}))
    return [
        monitor.check(t, flying, level) for t, level in enumerate((0.5, LOW, CRITICAL, EMERGENCY))
    ]


def test_com_low_bat_act_3_returns_at_critical_and_lands_at_emergency():
    (full, low, critical, emergency) = _battery_run(3)
    assert full == ([], None)
    assert low[0] == ["Battery low: 10% remaining"] and low[1] is None
    assert critical[0] == ["Battery critical: 6% remaining"] and critical[1].action == "rtl"
    assert emergency[0] == ["Battery emergency: 4% remaining"]
    assert emergency[1].action == "land"


@pytest.mark.parametrize(("action", "at_critical"), [(0, None), (2, "land")])
def test_com_low_bat_act_0_only_warns_and_2_lands_at_critical(action, at_critical):
    (_, low, critical, emergency) = _battery_run(action)
    assert low[1] is None
    assert (critical[1] and critical[1].action) == at_critical
    assert (emergency[1] and emergency[1].action) == ("land" if action else None)


def test_a_battery_level_warns_once_and_never_acts_on_the_ground():
    monitor = FailsafeMonitor(Px4Params({"COM_LOW_BAT_ACT": 3}))
    assert monitor.check(0.0, False, CRITICAL) == (
        ["Battery critical: 6% remaining"],
        None,
    )
    assert monitor.check(1.0, True, CRITICAL) == ([], None)  # the level has not changed


def test_the_data_link_is_lost_after_com_dl_loss_t_of_silence_and_again_after_it_returns():
    monitor = FailsafeMonitor(Px4Params({"NAV_DLL_ACT": 2, "COM_DL_LOSS_T": 5}))
    assert monitor.next_check_s(0.0) is None  # no ground station yet: nothing to lose
    monitor.gcs_heartbeat(1.0)
    assert monitor.next_check_s(2.0) == 6.0
    assert monitor.check(6.0, True, 1.0)[1] is None  # 5 s of silence is not more than 5 s
    trigger = monitor.check(6.1, True, 1.0)[1]
    assert trigger is not None and trigger.action == "rtl" and trigger.reason == "data link lost"
    assert monitor.check(7.0, True, 1.0)[1] is None  # lost once, acted once
    assert monitor.next_check_s(7.0) is None
    monitor.gcs_heartbeat(8.0)  # the link is back, then silent again
    assert monitor.next_check_s(20.0) == 20.0  # overdue: check now, not in the past
    assert monitor.check(13.5, True, 1.0)[1].action == "rtl"


def test_no_data_link_failsafe_on_the_ground_or_with_nav_dll_act_0():
    grounded = FailsafeMonitor(Px4Params({"NAV_DLL_ACT": 2, "COM_DL_LOSS_T": 5}))
    grounded.gcs_heartbeat(0.0)
    assert grounded.check(30.0, False, 1.0) == ([], None)
    off = FailsafeMonitor(Px4Params({"NAV_DLL_ACT": 0, "COM_DL_LOSS_T": 5}))
    off.gcs_heartbeat(0.0)
    assert off.check(30.0, True, 1.0) == ([], None)
    assert off.next_check_s(1.0) is None


@pytest.mark.parametrize(
    ("nav_dll_act", "action"), [(1, "hold"), (2, "rtl"), (3, "land"), (5, "disarm"), (6, "disarm")]
)
def test_nav_dll_act_values(nav_dll_act, action):
    monitor = FailsafeMonitor(Px4Params({"NAV_DLL_ACT": nav_dll_act, "COM_DL_LOSS_T": 5}))
    monitor.gcs_heartbeat(0.0)
    assert monitor.check(10.0, True, 1.0)[1].action == action


@pytest.mark.parametrize(
    ("com_obl_rc_act", "action"),
    [(0, "hold"), (1, "hold"), (2, "hold"), (3, "rtl"), (4, "land"), (5, "hold"), (6, "disarm"),
     (7, "disarm")],
)  # fmt: skip
def test_com_obl_rc_act_values(com_obl_rc_act, action):
    trigger = FailsafeMonitor(Px4Params({"COM_OBL_RC_ACT": com_obl_rc_act})).offboard_lost()
    assert trigger.action == action and trigger.reason == "offboard setpoints lost"


def test_parameters_set_between_checks_take_effect_at_the_next_check():
    params = Px4Params({"NAV_DLL_ACT": 0, "COM_DL_LOSS_T": 5})
    monitor = FailsafeMonitor(params)
    monitor.gcs_heartbeat(0.0)
    assert monitor.check(10.0, True, 0.5) == ([], None)
    params.set("NAV_DLL_ACT", 3)
    params.set("BAT_LOW_THR", 0.5)
    assert monitor.next_check_s(10.0) == 10.0
    warnings, trigger = monitor.check(10.0, True, 0.4)
    assert warnings == ["Battery low: 40% remaining"] and trigger.action == "land"
