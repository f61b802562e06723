"""Commander behaviour on simulated time: takeoff, land, auto-disarm, offboard, failsafe."""

from __future__ import annotations

import numpy as np
import pytest

from tests.vehicle_sim.sim_flying import fly, hovering
from vehicle_sim import (
    FlightMode,
    LandedState,
    Simulator,
    Sticks,
    VelocitySetpoint,
    load_sim_config,
)
from vehicle_sim.manual_control import CENTRED


def new_sim(**params) -> Simulator:
    sim = Simulator(load_sim_config("iris"))
    for name, value in params.items():
        sim.set_param(name, value)
    return sim


def run_until(sim: Simulator, predicate, limit_s: float, dt_s: float = 0.02) -> float:
    """Step until ``predicate(state)``; returns the time it first held."""
    for _ in range(round(limit_s / dt_s)):
        state = sim.step(dt_s)
        if predicate(state):
            return state.t_s
    raise AssertionError(f"condition not reached within {limit_s} s")


def test_takeoff_climbs_at_tko_speed_to_takeoff_alt_then_holds():
    sim = new_sim()
    assert sim.takeoff().result == "denied"  # not armed
    assert sim.arm().accepted and sim.takeoff(float("nan")).accepted
    states = [sim.step(0.1) for _ in range(100)]
    climb = [-s.vel_ned_mps[2] for s in states if s.mode is FlightMode.TAKEOFF]
    assert max(climb) == pytest.approx(1.5, abs=0.15)
    assert states[-1].mode is FlightMode.HOLD
    assert -states[-1].pos_ned_m[2] == pytest.approx(2.5, abs=0.03)
    assert states[-1].landed_state is LandedState.IN_AIR
    assert (6, "Takeoff complete, holding") in sim.drain_events()


def test_takeoff_to_a_given_altitude_and_bad_altitudes():
    sim = new_sim()
    sim.arm()
    assert sim.takeoff(-3.0).result == "denied"
    assert sim.takeoff(float("inf")).result == "denied"
    assert sim.takeoff(5.0).accepted
    sim.step(15.0)
    assert -sim.state.pos_ned_m[2] == pytest.approx(5.0, abs=0.05)


def test_land_descends_at_land_speed_and_disarms_2_s_after_touchdown():
    sim = hovering(settle_s=1.0)
    assert sim.land().accepted
    sink = []
    t_touch = None
    for _ in range(600):
        s = sim.step(0.02)
        if s.landed_state is LandedState.LANDING:
            sink.append(s.vel_ned_mps[2])
        if t_touch is None and s.landed_state is LandedState.ON_GROUND:
            t_touch = s.t_s
        if not s.armed:
            break
    assert float(np.median(sink)) == pytest.approx(0.7, abs=0.02)
    assert max(sink) < 0.7 * 1.15
    assert t_touch is not None and s.t_s - t_touch == pytest.approx(2.0, abs=0.03)
    assert s.pos_ned_m[2] == 0.0 and s.mode is FlightMode.HOLD
    events = [text for _, text in sim.drain_events()]
    assert events.count("Landing detected") == 1 and "Disarmed after landing" in events


def test_land_from_high_descends_at_auto_speed_then_slows_near_the_ground():
    """As PX4's FlightTaskAuto: MPC_Z_V_AUTO_DN (1.5 m/s) above MPC_LAND_ALT1 (10 m),
    MPC_LAND_SPEED (0.7 m/s) below MPC_LAND_ALT2 (5 m); sampled in one-second steps."""
    sim = hovering(settle_s=1.0, alt_m=20.0)
    assert sim.land().accepted
    sink_at_height = []
    for _ in range(60):
        s = sim.step(1.0)
        if s.landed_state is LandedState.LANDING:
            sink_at_height.append((-s.pos_ned_m[2], s.vel_ned_mps[2]))
    high = [v for h, v in sink_at_height if 11.0 < h < 17.0]
    low = [v for h, v in sink_at_height if 0.5 < h < 4.0]
    assert high and float(np.median(high)) == pytest.approx(1.5, abs=0.05)
    assert low and float(np.median(low)) == pytest.approx(0.7, abs=0.05)
    assert not sim.state.armed and sim.state.pos_ned_m[2] == 0.0


def test_auto_disarm_10_s_after_arming_without_takeoff():
    sim = new_sim()
    assert sim.arm().accepted
    t = run_until(sim, lambda s: not s.armed, 12.0, dt_s=0.1)
    assert t == pytest.approx(10.0, abs=1e-9)
    assert any("no takeoff" in text for _, text in sim.drain_events())
    assert sim.state.pos_ned_m[2] == 0.0  # idle on the ground, never lifted


def test_offboard_needs_a_fresh_setpoint():
    sim = new_sim()
    sim.arm()
    result = sim.set_mode(FlightMode.OFFBOARD)
    assert (result.accepted, result.result) == (False, "temporarily_rejected")
    assert any("Offboard" in text for _, text in sim.drain_events())
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.step(1.0)  # now stale (COM_OF_LOSS_T = 1 s)
    assert sim.set_mode(FlightMode.OFFBOARD).result == "temporarily_rejected"
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.step(0.5)
    assert sim.set_mode(FlightMode.OFFBOARD).accepted
    assert sim.state.mode is FlightMode.OFFBOARD


def test_offboard_climb_from_the_ground_takes_off():
    sim = new_sim()
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    assert sim.set_mode(FlightMode.OFFBOARD).accepted and sim.arm().accepted
    fly(sim, (0.0, 0.0, 0.0), 1.0)
    assert sim.state.pos_ned_m[2] == 0.0  # zero velocity on the ground: stays landed
    fly(sim, (0.0, 0.0, -1.0), 3.0)
    assert -sim.state.pos_ned_m[2] > 2.0 and sim.state.landed_state is LandedState.IN_AIR


@pytest.mark.parametrize(("action", "mode"), [(0.0, FlightMode.HOLD), (4.0, FlightMode.LAND)])
def test_failsafe_after_com_of_loss_t_without_setpoints(action, mode):
    sim = hovering(settle_s=1.0)
    sim.set_param("COM_OBL_RC_ACT", action)
    sim.set_param("COM_OF_LOSS_T", 0.5)
    sim.set_param("COM_FAIL_ACT_T", 0.0)  # act at once (the hold-first delay: next test)
    fly(sim, (1.0, 0.0, 0.0), 2.0)
    t_last = sim.state.t_s - 0.05
    t = run_until(sim, lambda s: s.mode is not FlightMode.OFFBOARD, 2.0, dt_s=0.002)
    assert t - t_last == pytest.approx(0.5, abs=0.0021)
    assert sim.state.mode is mode
    severities = [sev for sev, text in sim.drain_events() if text.startswith("Failsafe")]
    assert severities == [2]
    if mode is FlightMode.HOLD:
        sim.step(6.0)
        assert abs(sim.state.vel_ned_mps[0]) < 0.05 and sim.state.armed


def test_disarm_in_air_refused_without_force():
    sim = hovering(settle_s=1.0)
    result = sim.disarm()
    assert (result.accepted, result.result) == (False, "denied") and sim.state.armed
    assert sim.disarm(force=True).accepted and not sim.state.armed
    sim.step(0.5)
    assert sim.state.vel_ned_mps[2] > 4.0  # motors off: falling


def test_unsupported_modes_are_denied_and_hold_is_accepted():
    sim = new_sim()
    assert sim.set_mode(FlightMode.MISSION).result == "denied"
    assert sim.set_mode(FlightMode.POSCTL).accepted
    with pytest.raises(ValueError, match="FlightMode"):
        sim.set_mode("HOLD")  # type: ignore[arg-type]


def test_rtl_climbs_to_the_return_altitude_returns_home_and_lands():
    sim = hovering(settle_s=1.0)
    sim.set_param("RTL_RETURN_ALT", 6.0)
    home_xy = sim.state.pos_ned_m[:2].copy()
    fly(sim, (2.0, 1.0, 0.0), 5.0)  # away from home
    away = sim.state.pos_ned_m.copy()
    assert np.hypot(*(away[:2] - home_xy)) > 8.0
    assert sim.set_mode(FlightMode.RTL).accepted
    states = [sim.step(0.1) for _ in range(450)]
    assert FlightMode.LAND in [s.mode for s in states]
    in_rtl = [s for s in states if s.mode is FlightMode.RTL]
    assert max(-s.pos_ned_m[2] for s in in_rtl) == pytest.approx(6.0, abs=0.4)
    climb_end = next(i for i, s in enumerate(in_rtl) if -s.pos_ned_m[2] > 5.7)
    # climbs first (no long horizontal flight at low altitude), then returns at altitude
    assert np.hypot(*(in_rtl[climb_end].pos_ned_m[:2] - away[:2])) < 2.0
    final = states[-1]
    assert np.hypot(*(final.pos_ned_m[:2] - home_xy)) < 0.7
    assert final.landed_state is LandedState.ON_GROUND and not final.armed
    events = [text for _, text in sim.drain_events()]
    assert "RTL: landing at home" in events


def test_rtl_and_reposition_are_refused_on_the_ground():
    sim = new_sim()
    assert sim.set_mode(FlightMode.RTL).result == "denied"
    assert sim.reposition((1.0, 2.0, -3.0)).result == "denied"


def test_reposition_flies_to_the_point_and_holds_there():
    sim = hovering(settle_s=1.0)
    assert sim.reposition((8.0, -4.0, float("nan"))).accepted
    assert sim.state.mode is FlightMode.HOLD
    altitude_m = -sim.state.pos_ned_m[2]
    for _ in range(200):
        state = sim.step(0.1)
    np.testing.assert_allclose(state.pos_ned_m[:2], (8.0, -4.0), atol=0.2)
    assert -state.pos_ned_m[2] == pytest.approx(altitude_m, abs=0.2)
    with pytest.raises(ValueError, match="finite or NaN"):
        sim.reposition((float("inf"), 0.0, 0.0))


def test_home_is_where_the_vehicle_last_armed():
    sim = hovering(settle_s=1.0)
    np.testing.assert_allclose(sim.state.home_ned_m, 0.0, atol=1e-6)
    assert sim.reposition((8.0, -4.0, float("nan"))).accepted
    sim.step(20.0)
    assert sim.land().accepted
    for _ in range(60):
        if not sim.step(0.5).armed:
            break
    assert not sim.state.armed
    landed_ned_m = sim.state.pos_ned_m.copy()
    assert sim.arm().accepted
    np.testing.assert_allclose(sim.state.home_ned_m, landed_ned_m)
    assert np.hypot(*sim.state.home_ned_m[:2]) > 8.0


def test_a_failsafe_holds_for_com_fail_act_t_then_acts_unless_the_pilot_takes_over():
    sim = hovering(settle_s=1.0)
    sim.set_param("COM_OBL_RC_ACT", 4)  # land
    sim.set_param("COM_FAIL_ACT_T", 3.0)
    t_lost = run_until(sim, lambda s: s.mode is not FlightMode.OFFBOARD, 3.0)
    assert sim.state.mode is FlightMode.HOLD
    t_land = run_until(sim, lambda s: s.mode is FlightMode.LAND, 5.0)
    assert t_land - t_lost == pytest.approx(3.0, abs=0.05)
    assert any("landing in 3 s" in text for _, text in sim.drain_events())

    sim = hovering(settle_s=1.0)
    sim.set_param("COM_OBL_RC_ACT", 4)
    run_until(sim, lambda s: s.mode is not FlightMode.OFFBOARD, 3.0)
    assert sim.set_mode(FlightMode.POSCTL).accepted  # the pilot takes over within the delay
    sim.step(8.0)
    assert sim.state.mode is FlightMode.POSCTL and sim.state.armed


def test_a_pilot_who_moves_the_sticks_during_the_failsafe_hold_cancels_its_action():
    """As a mode switch does (above), sticks moved past COM_RC_STICK_OV during the
    COM_FAIL_ACT_T hold (5 s) take the vehicle into POSCTL and the pending landing never
    runs."""
    sim = hovering(settle_s=1.0)
    sim.set_param("COM_OBL_RC_ACT", 4)  # land
    run_until(sim, lambda s: s.mode is not FlightMode.OFFBOARD, 3.0)
    assert sim.state.mode is FlightMode.HOLD
    assert sim.set_sticks(CENTRED)  # the joystick connects centred, then the pilot moves it
    sim.step(0.05)
    assert sim.set_sticks(Sticks(0.5, 0.0, 0.5, 0.0))
    sim.step(0.05)
    assert sim.state.mode is FlightMode.POSCTL
    for _ in range(160):  # 8 s of centred sticks
        sim.set_sticks(CENTRED)
        sim.step(0.05)
    assert sim.state.mode is FlightMode.POSCTL and sim.state.armed


def test_sticks_moved_on_the_ground_take_nothing_over():
    """PX4 overrides a flying vehicle's auto mode with the sticks; an armed vehicle still on
    the ground keeps its mode however far they move."""
    sim = Simulator(load_sim_config("iris"), seed=0)
    assert sim.arm().accepted
    sim.step(0.5)
    mode = sim.state.mode
    sim.set_sticks(CENTRED)
    sim.step(0.05)
    for _ in range(10):
        sim.set_sticks(Sticks(1.0, 0.0, 0.5, 0.0))
        sim.step(0.05)
    assert sim.state.mode is mode and sim.state.armed


@pytest.mark.parametrize(("action", "mode"), [(2, FlightMode.RTL), (3, FlightMode.LAND)])
def test_data_link_loss_runs_nav_dll_act_after_com_dl_loss_t(action, mode):
    sim = hovering(settle_s=1.0)
    sim.set_param("NAV_DLL_ACT", action)
    sim.set_param("COM_DL_LOSS_T", 5)
    sim.set_param("COM_FAIL_ACT_T", 0.0)
    sim.set_param("RTL_RETURN_ALT", 4.0)
    sim.set_mode(FlightMode.HOLD)
    t0 = sim.state.t_s
    for _ in range(20):  # a ground station heartbeat every 0.5 s, then silence
        sim.on_gcs_heartbeat()
        sim.step(0.5)
    t_last = sim.state.t_s - 0.5
    t_act = run_until(sim, lambda s: s.mode is mode, 10.0)
    assert t_act - t_last == pytest.approx(5.0, abs=0.1) and t_act > t0 + 10.0
    assert any("data link lost" in text for _, text in sim.drain_events())


def test_no_data_link_failsafe_without_nav_dll_act_or_without_a_ground_station():
    sim = hovering(settle_s=1.0)
    sim.set_mode(FlightMode.HOLD)
    sim.on_gcs_heartbeat()
    sim.step(30.0)  # NAV_DLL_ACT 0 (PX4's default): disabled
    assert sim.state.mode is FlightMode.HOLD


def test_battery_warns_when_low_and_returns_when_critical_with_com_low_bat_act_3():
    effects = {"battery_sag": {"full_flight_time_s": 60.0, "max_thrust_loss": 0.1}}
    sim = hovering(effects=effects, settle_s=1.0)
    sim.set_param("COM_LOW_BAT_ACT", 3)
    sim.set_param("COM_FAIL_ACT_T", 0.0)
    sim.set_param("RTL_RETURN_ALT", 4.0)
    sim.set_mode(FlightMode.HOLD)
    texts: list[str] = []
    for _ in range(120):
        sim.step(0.5)
        texts += [text for _, text in sim.drain_events()]
        if sim.state.mode is FlightMode.RTL:
            break
    assert sim.state.mode is FlightMode.RTL
    low = next(i for i, t in enumerate(texts) if t.startswith("Battery low"))
    critical = next(i for i, t in enumerate(texts) if t.startswith("Battery critical"))
    assert low < critical
    assert any(t.startswith("Failsafe: battery critical, returning") for t in texts)
