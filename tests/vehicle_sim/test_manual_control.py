"""Sticks as PX4's manual modes read them: the mapping against hand-computed values, and the
simulator flying POSCTL/ALTCTL from them, failing over when they stop, and handing the vehicle
to a pilot who moves them (COM_RC_OVERRIDE)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vehicle_sim import FlightMode, Simulator, Sticks, VelocitySetpoint, load_sim_config
from vehicle_sim.manual_control import (
    CENTRED,
    StickMotion,
    check_sticks,
    deadzone,
    expo,
    stick_command,
)
from vehicle_sim.mavlink.manual_control import INT16_MAX, parse_manual_control
from vehicle_sim.params import Px4Params

# PX4's defaults: MAN_DEADZONE 0.1, MPC_*_EXPO 0.6, MPC_VEL_MANUAL 10 m/s,
# MPC_Z_VEL_MAX_UP 3 m/s, MPC_Z_VEL_MAX_DN 1.5 m/s, MPC_MAN_Y_MAX 150 deg/s.
# A stick at 0.55: deadzone (0.55 - 0.1) / 0.9 = 0.5; expo 0.4 * 0.5 + 0.6 * 0.125 = 0.275.


@pytest.mark.parametrize(
    ("sticks", "forward", "right", "down", "yaw_rate_degps"),
    [
        (Sticks(1.0, 0.0, 0.5, 0.0), 10.0, 0.0, 0.0, 0.0),
        (Sticks(0.55, -0.55, 0.5, 0.0), 2.75, -2.75, 0.0, 0.0),
        (Sticks(0.05, -0.09, 0.525, 0.1), 0.0, 0.0, 0.0, 0.0),  # all inside the deadzone
        (Sticks(1.0, 1.0, 0.5, 0.0), 10.0 / math.sqrt(2), 10.0 / math.sqrt(2), 0.0, 0.0),
        (Sticks(0.0, 0.0, 1.0, 0.0), 0.0, 0.0, -3.0, 0.0),  # full up: MPC_Z_VEL_MAX_UP
        (Sticks(0.0, 0.0, 0.0, 0.0), 0.0, 0.0, 1.5, 0.0),  # full down: MPC_Z_VEL_MAX_DN
        (Sticks(0.0, 0.0, 0.775, 0.0), 0.0, 0.0, -0.825, 0.0),  # (0.775-0.5)*2 = 0.55
        (Sticks(0.0, 0.0, 0.225, 0.0), 0.0, 0.0, 0.4125, 0.0),  # 0.275 * 1.5
        (Sticks(0.0, 0.0, 0.5, -0.55), 0.0, 0.0, 0.0, -41.25),  # 0.275 * 150
        (Sticks(0.0, 0.0, 0.5, 1.0), 0.0, 0.0, 0.0, 150.0),
    ],
)
def test_stick_command_at_px4_defaults(sticks, forward, right, down, yaw_rate_degps) -> None:
    cmd = stick_command(sticks, Px4Params())
    assert cmd.forward_mps == pytest.approx(forward, abs=1e-12)
    assert cmd.right_mps == pytest.approx(right, abs=1e-12)
    assert cmd.down_mps == pytest.approx(down, abs=1e-12)
    assert math.degrees(cmd.yaw_rate_radps) == pytest.approx(yaw_rate_degps, abs=1e-9)


def test_stick_command_follows_the_parameters() -> None:
    linear = Px4Params(
        {"MPC_XY_MAN_EXPO": 0.0, "MPC_Z_MAN_EXPO": 0.0, "MPC_YAW_EXPO": 0.0, "MAN_DEADZONE": 0.0}
    )
    cmd = stick_command(Sticks(0.3, -0.2, 0.6, 0.5), linear)
    assert (cmd.forward_mps, cmd.right_mps) == pytest.approx((3.0, -2.0))
    assert cmd.down_mps == pytest.approx(-0.2 * 3.0)  # (0.6 - 0.5) * 2 = 0.2 of 3 m/s up
    assert math.degrees(cmd.yaw_rate_radps) == pytest.approx(75.0)
    faster = Px4Params({"MPC_VEL_MANUAL": 5.0, "MPC_MAN_Y_MAX": 90.0, "MPC_XY_MAN_EXPO": 0.0})
    cmd = stick_command(Sticks(0.55, 0.0, 0.5, 1.0), faster)
    assert cmd.forward_mps == pytest.approx(2.5) and math.degrees(cmd.yaw_rate_radps) == 90.0


def test_each_axis_takes_its_own_expo() -> None:
    """Sticks at 0.55 (x, yaw) and throttle 0.775 are 0.5 past the 0.1 deadzone on every
    axis; MPC_XY_MAN_EXPO 0 keeps x at 0.5 (5 m/s of 10), MPC_Z_MAN_EXPO 1 makes the throttle
    0.5^3 = 0.125 (of 3 m/s up), MPC_YAW_EXPO 0.5 makes yaw 0.25 + 0.0625 = 0.3125 (of 150
    deg/s)."""
    params = Px4Params({"MPC_XY_MAN_EXPO": 0.0, "MPC_Z_MAN_EXPO": 1.0, "MPC_YAW_EXPO": 0.5})
    cmd = stick_command(Sticks(0.55, 0.0, 0.775, 0.55), params)
    assert cmd.forward_mps == pytest.approx(5.0)
    assert cmd.down_mps == pytest.approx(-0.375)
    assert math.degrees(cmd.yaw_rate_radps) == pytest.approx(46.875)


def test_deadzone_and_expo_by_hand() -> None:
    assert deadzone(0.1, 0.1) == 0.0 and deadzone(-0.55, 0.1) == pytest.approx(-0.5)
    assert expo(0.5, 0.6) == pytest.approx(0.275) and expo(-1.0, 0.6) == -1.0
    # PX4's math::expo limits its input to [-1, 1] first
    assert expo(1.5, 0.6) == 1.0 and expo(-2.0, 0.3) == -1.0


def test_stick_motion_by_hand() -> None:
    """PX4's MovingDiff: the rate of change low-passed with tau 0.1 s, none at the first
    reading; the throttle over [-1, 1]; a held stick's rate decays, however far out it is."""
    motion = StickMotion()
    assert motion.update(Sticks(0.0, 0.0, 0.3, 0.0), 0.0) == 0.0
    assert motion.update(CENTRED, 0.0) == pytest.approx(0.4 / 0.1)
    motion = StickMotion()
    assert motion.update(CENTRED, 0.1) == 0.0
    assert motion.update(Sticks(0.2, 0.0, 0.5, 0.0), 0.1) == pytest.approx(0.2 / 0.2)
    assert motion.update(Sticks(0.2, 0.0, 0.5, 0.0), 0.1) == pytest.approx(0.5)
    for _ in range(30):
        held = motion.update(Sticks(0.2, 0.0, 0.5, 0.0), 0.1)
    assert held < 1e-6


@pytest.mark.parametrize(
    "bad",
    [
        Sticks(math.nan, 0.0, 0.5, 0.0),
        Sticks(0.0, math.inf, 0.5, 0.0),
        Sticks(0.0, 0.0, -0.1, 0.0),
        Sticks(0.0, 0.0, 0.5, 1.5),
        Sticks(0.0, "0", 0.5, 0.0),
    ],
)
def test_invalid_sticks_are_refused_naming_the_axis(bad) -> None:
    with pytest.raises(ValueError, match="stick [xyzr]"):
        check_sticks(bad)
    sim = Simulator(load_sim_config("iris"), seed=0)
    with pytest.raises(ValueError):
        sim.set_sticks(bad)


def test_manual_control_wire_values() -> None:
    parsed = parse_manual_control(1000, -500, 500, 250)
    assert parsed.sticks == Sticks(1.0, -0.5, 0.5, 0.25) and parsed.problem == ""
    parsed = parse_manual_control(1500, 0, -1000, 0)  # MAVSDK's z of -1 gives -1000
    assert parsed.sticks == Sticks(1.0, 0.0, 0.0, 0.0)
    assert parsed.problem == "Sticks clamped: x 1500 not in -1000..1000, z -1000 not in 0..1000"
    parsed = parse_manual_control(0, 0, INT16_MAX, 0)
    assert parsed.sticks is None and parsed.problem == "Sticks ignored: axis z invalid (INT16_MAX)"


# -- the simulator flying them ------------------------------------------------------------------


def _hovering(**params: float) -> Simulator:
    sim = Simulator(load_sim_config("iris"), seed=3)
    for name, value in params.items():
        sim.set_param(name, value)
    assert sim.arm().accepted and sim.takeoff().accepted
    sim.step(4.0)
    assert sim.state.mode is FlightMode.HOLD
    return sim


def _in_offboard(sim: Simulator, setpoint) -> Simulator:
    """``sim`` switched to OFFBOARD after 0.5 s of ``setpoint`` streamed at 20 Hz."""
    for _ in range(10):
        sim.set_velocity_setpoint(setpoint)
        sim.step(0.05)
    assert sim.set_mode(FlightMode.OFFBOARD).accepted
    return sim


def _fly(sim: Simulator, sticks: Sticks, duration_s: float, rate_hz: float = 20.0) -> None:
    """Send ``sticks`` at ``rate_hz`` for ``duration_s`` of simulated time."""
    for _ in range(round(duration_s * rate_hz)):
        sim.set_sticks(sticks)
        sim.step(1.0 / rate_hz)


def test_posctl_sticks_fly_the_heading_frame_then_hold() -> None:
    sim = _hovering()
    assert sim.set_mode(FlightMode.POSCTL).accepted
    _fly(sim, Sticks(0.0, 0.0, 0.5, 1.0), 0.6)  # yaw right at 150 deg/s for 0.6 s
    _fly(sim, CENTRED, 1.0)
    heading = sim.state.yaw_rad
    assert math.degrees(heading) == pytest.approx(90.0, abs=10.0)
    _fly(sim, Sticks(1.0, 0.0, 0.5, 0.0), 5.0)
    vel = sim.state.vel_ned_mps
    assert np.hypot(vel[0], vel[1]) == pytest.approx(10.0, abs=0.5)  # MPC_VEL_MANUAL
    assert math.atan2(vel[1], vel[0]) == pytest.approx(heading, abs=0.05)
    assert sim.state.yaw_rad == pytest.approx(heading, abs=0.02)  # centred yaw holds heading
    _fly(sim, CENTRED, 6.0)  # brakes, then holds
    held = sim.state.pos_ned_m.copy()
    _fly(sim, CENTRED, 3.0)
    assert np.linalg.norm(sim.state.pos_ned_m - held) < 0.1
    alt_m = -sim.state.pos_ned_m[2]
    _fly(sim, Sticks(0.0, 0.0, 1.0, 0.0), 3.0)
    assert -sim.state.vel_ned_mps[2] == pytest.approx(3.0, abs=0.2)  # MPC_Z_VEL_MAX_UP
    assert -sim.state.pos_ned_m[2] > alt_m + 6.0
    assert sim.state.mode is FlightMode.POSCTL


def test_altctl_climbs_and_descends_at_the_stick_limits() -> None:
    sim = _hovering()
    assert sim.set_mode(FlightMode.ALTCTL).accepted
    _fly(sim, Sticks(0.0, 0.0, 1.0, 0.0), 3.0)
    assert sim.state.vel_ned_mps[2] == pytest.approx(-3.0, abs=0.2)  # MPC_Z_VEL_MAX_UP
    _fly(sim, Sticks(0.0, 0.0, 0.0, 0.0), 3.0)
    assert sim.state.vel_ned_mps[2] == pytest.approx(1.5, abs=0.1)  # MPC_Z_VEL_MAX_DN
    _fly(sim, Sticks(0.0, 0.55, 0.5, 0.0), 4.0)
    assert sim.state.vel_ned_mps[1] == pytest.approx(2.75, abs=0.2)
    assert sim.state.mode is FlightMode.ALTCTL


@pytest.mark.parametrize(("action", "then"), [(2, FlightMode.RTL), (3, FlightMode.LAND)])
def test_sticks_that_stop_in_posctl_trigger_nav_rcl_act(action: int, then: FlightMode) -> None:
    sim = _hovering(NAV_RCL_ACT=action)
    sim.set_mode(FlightMode.POSCTL)
    _fly(sim, Sticks(0.5, 0.0, 0.5, 0.0), 1.0)
    sim.drain_events()
    sim.step(0.4)  # the last sticks are 0.45 s old: less than COM_RC_LOSS_T (0.5 s)
    assert sim.state.mode is FlightMode.POSCTL
    sim.step(0.1)
    assert sim.state.mode is FlightMode.HOLD
    texts = [text for _severity, text in sim.drain_events()]
    assert any(text.startswith("Failsafe: manual control lost, holding;") for text in texts)
    sim.step(5.0)  # COM_FAIL_ACT_T
    assert sim.state.mode is then
    _fly(sim, CENTRED, 0.2)
    assert (6, "Manual control regained") in sim.drain_events()


def test_without_sticks_ever_posctl_holds_and_never_fails_over() -> None:
    sim = _hovering()
    sim.set_mode(FlightMode.POSCTL)
    start = sim.state.pos_ned_m.copy()
    sim.step(10.0)
    assert sim.state.mode is FlightMode.POSCTL
    assert np.linalg.norm(sim.state.pos_ned_m - start) < 0.1


@pytest.mark.parametrize("seed", [0, 1])
def test_posctl_entered_at_speed_without_sticks_brakes_and_holds_where_it_stopped(seed) -> None:
    """As PX4's centred sticks: the vehicle stops ahead of where POSCTL was entered (its
    braking distance) and holds there; it does not fly back to the entry point."""
    rng = np.random.default_rng(seed)
    speed_mps, heading = rng.uniform(3.0, 6.0), rng.uniform(-math.pi, math.pi)
    direction = np.array([math.cos(heading), math.sin(heading)])
    sim = _in_offboard(_hovering(), VelocitySetpoint((*(speed_mps * direction), 0.0)))
    for _ in range(round(4.0 / 0.05)):
        sim.set_velocity_setpoint(VelocitySetpoint((*(speed_mps * direction), 0.0)))
        sim.step(0.05)
    assert sim.set_mode(FlightMode.POSCTL).accepted
    entered = sim.state.pos_ned_m.copy()
    ahead = []
    for _ in range(round(8.0 / 0.05)):
        sim.step(0.05)
        ahead.append(float((sim.state.pos_ned_m[:2] - entered[:2]) @ direction))
    stopped = sim.state.pos_ned_m.copy()
    assert ahead[-1] > 0.1 * speed_mps, ahead[-1]  # at least the stop from speed_mps
    assert max(ahead) - ahead[-1] < 0.3, (max(ahead), ahead[-1])  # never flew back
    assert abs(stopped[2] - entered[2]) < 0.3
    sim.step(3.0)
    assert np.linalg.norm(sim.state.pos_ned_m - stopped) < 0.1
    assert sim.state.mode is FlightMode.POSCTL


@pytest.mark.parametrize(("rcl_except", "exempt"), [(0, False), (1, False), (2, True), (7, True)])
def test_sticks_that_stop_in_hold_fail_over_unless_com_rcl_except_exempts_hold(
    rcl_except: int, exempt: bool
) -> None:
    """PX4's failsafe runs NAV_RCL_ACT (default 2, return) on a manual-control loss in HOLD
    unless COM_RCL_EXCEPT's bit 1 (value 2) is set; bit 0 (mission) does not exempt HOLD."""
    sim = _hovering(COM_RC_OVERRIDE=0, COM_RCL_EXCEPT=rcl_except)
    _fly(sim, Sticks(1.0, 0.0, 0.5, 0.0), 1.0)  # in HOLD, override off: not flown
    sim.step(3.0)
    texts = [text for _severity, text in sim.drain_events()]
    assert ("Manual control lost" in texts) is exempt
    assert any(t.startswith("Failsafe: manual control lost, holding;") for t in texts) is not exempt
    sim.step(3.0)  # COM_FAIL_ACT_T (5 s) after the loss at 0.5 s
    assert sim.state.mode is (FlightMode.HOLD if exempt else FlightMode.RTL)
    if exempt:
        assert np.hypot(*sim.state.pos_ned_m[:2]) < 0.1


@pytest.mark.parametrize(("rcl_except", "exempt"), [(0, False), (3, False), (4, True)])
def test_a_joystick_that_goes_away_in_offboard_fails_over_unless_bit_2_is_set(
    rcl_except: int, exempt: bool
) -> None:
    """A ground station's joystick sent sticks (held still: no override), then stopped while a
    companion flies OFFBOARD: PX4 runs NAV_RCL_ACT unless COM_RCL_EXCEPT has bit 2 (value 4)."""
    from vehicle_sim import VelocitySetpoint

    sim = _in_offboard(_hovering(COM_RCL_EXCEPT=rcl_except), VelocitySetpoint((0.5, 0.0, 0.0)))
    for k in range(60):
        sim.set_velocity_setpoint(VelocitySetpoint((0.5, 0.0, 0.0)))
        if k < 20:
            sim.set_sticks(CENTRED)
        sim.step(0.05)
    texts = [text for _severity, text in sim.drain_events()]
    assert ("Manual control lost" in texts) is exempt
    assert sim.state.mode is (FlightMode.OFFBOARD if exempt else FlightMode.HOLD)


@pytest.mark.parametrize("mode", [FlightMode.RTL, FlightMode.LAND])
def test_sticks_that_stop_while_returning_or_landing_change_nothing(mode: FlightMode) -> None:
    sim = _hovering()
    assert sim.set_mode(mode).accepted
    _fly(sim, CENTRED, 0.5)
    sim.step(1.0)
    assert sim.state.mode is mode
    assert (5, "Manual control lost") in sim.drain_events()


def test_moved_sticks_take_over_from_auto_modes_by_default() -> None:
    sim = _hovering()
    _fly(sim, CENTRED, 1.0)
    for i in range(20):  # 0.2 of travel per s: slower than COM_RC_STICK_OV (30 %/s)
        _fly(sim, Sticks(0.01 * i, 0.0, 0.5, 0.0), 0.05)
    assert sim.state.mode is FlightMode.HOLD
    sim.drain_events()
    _fly(sim, Sticks(0.35, 0.0, 0.5, 0.0), 0.05)
    assert sim.state.mode is FlightMode.POSCTL
    assert (6, "Pilot took over using sticks") in sim.drain_events()


def test_a_joystick_that_connects_or_comes_back_with_a_stick_out_takes_nothing_over() -> None:
    """PX4's MovingDiff has no rate before its second reading (it leaves its difference at 0
    without a last value, and is reset when the sticks are lost): a joystick that connects, or
    comes back after a loss, with a stick off centre moves nothing until the stick moves. The
    first reading counted as a move from centre, so HOLD (or a mission) went to POSCTL."""
    sim = _hovering(COM_RCL_EXCEPT=2)  # a loss in HOLD is only noted
    _fly(sim, Sticks(0.3, 0.0, 0.5, 0.0), 1.0)
    assert sim.state.mode is FlightMode.HOLD
    sim.step(1.0)  # lost
    _fly(sim, Sticks(0.0, -0.2, 0.6, 0.0), 1.0)  # back, held off centre
    assert sim.state.mode is FlightMode.HOLD
    _fly(sim, Sticks(0.4, -0.2, 0.6, 0.0), 0.05)  # the pilot moves one: takes over
    assert sim.state.mode is FlightMode.POSCTL


def test_a_stick_held_out_does_not_take_back_a_mode_the_pilot_chose() -> None:
    """PX4 overrides on stick motion, not position: flying POSCTL with the stick held forward,
    a switch to HOLD (or RTL, a failsafe) stays while the stick stays where it is."""
    sim = _hovering()
    assert sim.set_mode(FlightMode.POSCTL).accepted
    _fly(sim, Sticks(0.6, 0.0, 0.5, 0.0), 2.0)
    assert sim.set_mode(FlightMode.HOLD).accepted
    _fly(sim, Sticks(0.6, 0.0, 0.5, 0.0), 2.0)
    assert sim.state.mode is FlightMode.HOLD
    _fly(sim, Sticks(0.1, 0.0, 0.5, 0.0), 0.05)  # the pilot moves it: takes over
    assert sim.state.mode is FlightMode.POSCTL


@pytest.mark.parametrize(("bits", "taken_over"), [(1, False), (2, True), (3, True)])
def test_sticks_take_over_from_offboard_only_with_its_override_bit(bits, taken_over) -> None:
    from vehicle_sim import VelocitySetpoint

    sim = _in_offboard(_hovering(COM_RC_OVERRIDE=bits), VelocitySetpoint((1.0, 0.0, 0.0)))
    sim.set_sticks(CENTRED)  # the joystick connects centred, then the pilot moves the yaw stick
    for _ in range(20):
        sim.set_velocity_setpoint(VelocitySetpoint((1.0, 0.0, 0.0)))
        sim.set_sticks(Sticks(0.0, 0.0, 0.5, -0.8))
        sim.step(0.05)
    assert (sim.state.mode is FlightMode.POSCTL) is taken_over


def test_stick_input_disabled_by_com_rc_in_mode_is_ignored() -> None:
    sim = _hovering(COM_RC_IN_MODE=4)
    assert sim.set_sticks(Sticks(1.0, 0.0, 0.5, 0.0)) is False
    sim.step(1.0)
    assert sim.state.mode is FlightMode.HOLD
