"""The companion never fights a pilot: a mode change it did not ask for hands the vehicle over.

Mid-mission, "the pilot" (in process: the simulator's own mode switch; over MAVLink: a second,
GCS-like pymavlink client on its own link, commanding a mode or moving its joystick's sticks
with COM_RC_OVERRIDE's offboard bit set) switches the vehicle out of OFFBOARD. The companion
must stop streaming, command nothing (checked on the endpoint's received-message counters over
MAVLink), end with status "handed_over" and the one-line reason, and the vehicle must do what
the pilot chose.
"""

from __future__ import annotations

import dataclasses
import os
import threading
import time

import numpy as np
import pytest

from companion.handover import (
    FAILSAFE_TEXT_RECENT_S,
    FAILSAFE_TEXT_WAIT_S,
    failsafe_said,
    handover_detail,
)
from companion.inprocess_link import InProcessLink
from companion.link import CommandOutcome, StatusText, VelocityCommand
from companion.mavsdk_link import MavsdkLink
from companion.mission import load_mission
from companion.mission_reference import reference_of
from companion.planner_registry import make_planner
from companion.pymavlink_link import PymavlinkLink
from companion.runner import (
    FlightOutcome,
    RunnerConfig,
    fly_mission,
    mission_beyond_vehicle_limits,
)
from tests.companion.test_companion_control_loop import ManualClock
from tests.companion.test_companion_mission_on_every_link import LINE, free_udp_port
from vehicle_sim import FlightMode, Simulator, load_sim_config
from vehicle_sim.mavlink import EndpointConfig, LinkConfig, MavlinkEndpoint
from vehicle_sim.mavlink.params import int32_as_float

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402

TAKEOVER_AFTER_S = 3.0  # of following, then the pilot switches
PILOT_MODES = ("POSCTL", "HOLD", "RTL", "LAND")


class CountingInProcessLink(InProcessLink):
    """The real in-process link, counting what the companion sends after a given moment."""

    def __init__(self, sim: Simulator) -> None:
        super().__init__(sim)
        self.counting = False
        self.sent_after: list[str] = []

    def send_velocity(self, command: VelocityCommand) -> None:
        if self.counting:
            self.sent_after.append("setpoint")
        super().send_velocity(command)

    def hold(self):
        if self.counting:
            self.sent_after.append("hold")
        return super().hold()

    def land(self):
        if self.counting:
            self.sent_after.append("land")
        return super().land()


@pytest.mark.parametrize("mode", PILOT_MODES)
def test_pilot_takeover_in_process_hands_over_and_commands_nothing(mode: str) -> None:
    _take_over_in_process(mode, TAKEOVER_AFTER_S)


def test_a_takeover_soon_after_offboard_is_handed_over_at_once() -> None:
    """Once telemetry has shown OFFBOARD, any other mode is the pilot's, even within the grace
    the runner allows telemetry to first report OFFBOARD (2.5 s): no setpoint follows it."""
    _take_over_in_process("POSCTL", 0.5)


class PilotAtTheSwitchLink(CountingInProcessLink):
    """The pilot switches to POSCTL the instant the vehicle enters OFFBOARD, so telemetry
    never shows OFFBOARD; counting starts then."""

    def __init__(self, sim: Simulator) -> None:
        super().__init__(sim)
        self._pilot_sim = sim

    def start_offboard(self):
        outcome = super().start_offboard()
        if outcome.accepted:
            assert self._pilot_sim.set_mode(FlightMode.POSCTL).accepted
            self.counting = True
        return outcome


def test_a_vehicle_that_never_reports_offboard_is_handed_over_after_the_grace() -> None:
    """A vehicle that accepted OFFBOARD but reports another mode for longer than the grace
    the runner allows telemetry (offboard_grace_s, 2.5 s) is someone else's: the companion
    hands it over saying so, and neither holds nor lands it."""
    sim = Simulator(load_sim_config("iris"), seed=5)
    link = PilotAtTheSwitchLink(sim)
    mission = load_mission(LINE)
    outcome = fly_quietly(link, mission)
    assert outcome.status == "handed_over", outcome.detail
    assert outcome.detail.startswith("the vehicle never reported OFFBOARD (it reports POSCTL")
    assert "hold" not in link.sent_after and "land" not in link.sent_after
    assert sim.state.mode is FlightMode.POSCTL


def _names_who_took_over(detail: str, mode: str) -> None:
    """A manual mode is a pilot's; an automatic one may be a failsafe's, so it is only named."""
    if mode == "POSCTL":
        assert detail.startswith("pilot took control in POSCTL at t="), detail
    else:
        assert detail.startswith(f"the vehicle left OFFBOARD for {mode} at t="), detail
        assert "pilot" in detail and "PX4 failsafe" in detail, detail


def _take_over_in_process(mode: str, after_s: float) -> None:
    """Fly LINE in process; ``after_s`` of following in OFFBOARD, the pilot switches to
    ``mode``: the companion hands over and sends nothing more."""
    sim = Simulator(load_sim_config("iris"), seed=5)
    link = CountingInProcessLink(sim)
    mission = load_mission(LINE)
    following_since: list[float] = []

    def pilot(tick) -> None:
        if tick.state.mode != "OFFBOARD" or link.counting:
            return
        following_since.append(tick.t_s)
        if tick.t_s - following_since[0] >= after_s:
            assert sim.set_mode(FlightMode[mode]).accepted
            link.counting = True

    outcome = fly_quietly(link, mission, on_tick=pilot)
    assert outcome.status == "handed_over", outcome.detail
    _names_who_took_over(outcome.detail, mode)
    assert outcome.detail.endswith("; mission abandoned")
    assert link.sent_after == []
    assert sim.state.mode is FlightMode[mode]


def test_a_px4_failsafe_mid_mission_is_handed_over_without_blaming_a_pilot() -> None:
    """The ground station falls silent while the companion follows (NAV_DLL_ACT 2): PX4's
    data-link failsafe returns the vehicle and says so, and the companion yields to it naming
    the failsafe (not "pilot took control"), holding or landing nothing."""
    sim = Simulator(load_sim_config("iris"), seed=5)
    for name, value in (("NAV_DLL_ACT", 2), ("COM_DL_LOSS_T", 6), ("COM_FAIL_ACT_T", 0.0)):
        sim.set_param(name, value)
    link = CountingInProcessLink(sim)
    mission = load_mission(LINE)
    link.counting = True
    sim.on_gcs_heartbeat()  # a ground station was there at take-off, then went silent

    def note_failsafe(tick) -> None:
        if tick.state.mode == "OFFBOARD":
            link.sent_after.clear()  # count only what follows the failsafe's mode change

    outcome = fly_quietly(link, mission, on_tick=note_failsafe)
    assert outcome.status == "handed_over", outcome.detail
    start = "a PX4 failsafe took the vehicle out of OFFBOARD into RTL at t="
    assert outcome.detail.startswith(start), outcome.detail
    assert '("Failsafe: data link lost, returning"); mission abandoned' in outcome.detail
    assert link.sent_after == [], link.sent_after
    assert outcome.tracking_rmse_m is not None  # it had been following in OFFBOARD
    assert sim.state.mode is FlightMode.RTL


def _await_offboard(
    gcs: mavutil.mavfile, endpoint: MavlinkEndpoint, deadline: float, rate_s: float = 0.1
) -> None:
    """As a GCS (``gcs``, a pymavlink connection), send heartbeats every ``rate_s`` [s] until
    the vehicle has been in OFFBOARD for TAKEOVER_AFTER_S, or until ``deadline``
    (time.monotonic() [s])."""
    offboard_since = None
    while time.monotonic() < deadline:
        gcs.mav.heartbeat_send(6, 8, 0, 0, 0)
        if endpoint.state.mode is FlightMode.OFFBOARD:
            offboard_since = offboard_since or time.monotonic()
            if time.monotonic() - offboard_since >= TAKEOVER_AFTER_S:
                return
        time.sleep(rate_s)


def _ground_station_goes_silent(port: int, endpoint: MavlinkEndpoint) -> None:
    """A ground station with a joystick on its own link: sets the manual-control-loss
    failsafe to return at once (NAV_RCL_ACT 2, COM_FAIL_ACT_T 0, COM_RC_LOSS_T 2 s), sends
    heartbeats and centred sticks until the vehicle has followed in OFFBOARD a while, then falls
    silent (a radio out of range)."""
    gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=245)
    try:
        gcs.mav.heartbeat_send(6, 8, 0, 0, 0)
        for name, value, kind in (
            (b"NAV_RCL_ACT", int32_as_float(2), 6),
            (b"COM_FAIL_ACT_T", 0.0, 9),
            (b"COM_RC_LOSS_T", 2.0, 9),
        ):
            gcs.mav.param_set_send(1, 1, name, value, kind)
        offboard_since, deadline = None, time.monotonic() + 90.0
        while time.monotonic() < deadline:
            gcs.mav.heartbeat_send(6, 8, 0, 0, 0)
            gcs.mav.manual_control_send(1, 0, 0, 500, 0, 0)
            if endpoint.state.mode is FlightMode.OFFBOARD:
                offboard_since = offboard_since or time.monotonic()
                if time.monotonic() - offboard_since >= TAKEOVER_AFTER_S:
                    return
            time.sleep(0.1)
    finally:
        gcs.close()


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["pymavlink", "mavsdk"])
def test_a_failsafe_over_mavlink_is_named_with_what_px4_said(kind: str) -> None:
    """The ground station's radio goes silent mid-mission: PX4's manual-control-loss failsafe
    returns the vehicle and says so in a STATUSTEXT; the companion, over either link, hands
    over naming the failsafe and its text, and sends nothing more."""
    companion_port = free_udp_port()
    endpoint = _iris_with_a_ground_station(companion_port)
    url = f"udpin://127.0.0.1:{companion_port}"
    link = MavsdkLink(url) if kind == "mavsdk" else PymavlinkLink(url)
    gcs = threading.Thread(
        target=_ground_station_goes_silent, args=(endpoint.local_ports["gcs"], endpoint)
    )
    gcs.start()
    outcome: FlightOutcome | None = None
    try:
        outcome = fly_quietly(link, load_mission(LINE))
        at_return = endpoint.stats
        time.sleep(2.0)  # anything still streaming or commanding would show now
        later = endpoint.stats
        final_mode = endpoint.state.mode
    finally:
        gcs.join(10.0)
        link.close()
        endpoint.stop()
    assert outcome is not None and outcome.status == "handed_over", outcome
    start = "a PX4 failsafe took the vehicle out of OFFBOARD into RTL at t="
    assert outcome.detail.startswith(start), outcome.detail
    assert '("Failsafe: manual control lost, returning")' in outcome.detail, outcome.detail
    assert outcome.tracking_rmse_m is not None  # it had been following in OFFBOARD
    assert final_mode is FlightMode.RTL
    assert later.commands_received == at_return.commands_received
    assert later.setpoints_accepted + later.setpoints_rejected == (
        at_return.setpoints_accepted + at_return.setpoints_rejected
    )


def _pilot_switches(port: int, mode: str, endpoint: MavlinkEndpoint, marks: dict) -> None:
    """A GCS on its own link: waits for OFFBOARD plus a while, then commands ``mode``."""
    gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=245)
    try:
        _await_offboard(gcs, endpoint, time.monotonic() + 90.0)
        custom = FlightMode[mode].value
        main_mode, sub_mode = (custom >> 16) & 0xFF, (custom >> 24) & 0xFF
        for _ in range(20):  # until the endpoint reports the pilot's mode
            gcs.mav.command_long_send(
                1,
                1,
                mavutil.mavlink.MAV_CMD_DO_SET_MODE,
                0,
                mavutil.mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                main_mode,
                sub_mode,
                0,
                0,
                0,
                0,
            )
            time.sleep(0.2)
            if endpoint.state.mode is FlightMode[mode]:
                break
        marks["after_switch"] = endpoint.stats
        marks["switched_at"] = time.monotonic()
    finally:
        gcs.close()


@pytest.mark.slow
@pytest.mark.parametrize(("kind", "mode"), [("pymavlink", "POSCTL"), ("mavsdk", "LAND")])
def test_pilot_takeover_over_mavlink_no_command_after_the_mode_change(kind: str, mode: str) -> None:
    companion_port = free_udp_port()
    endpoint = _iris_with_a_ground_station(companion_port)
    gcs_port = endpoint.local_ports["gcs"]
    url = f"udpin://127.0.0.1:{companion_port}"
    link = MavsdkLink(url) if kind == "mavsdk" else PymavlinkLink(url)
    mission = load_mission(LINE)
    marks: dict = {}
    pilot = threading.Thread(target=_pilot_switches, args=(gcs_port, mode, endpoint, marks))
    pilot.start()
    outcome: FlightOutcome | None = None
    try:
        outcome = fly_quietly(link, mission)
        returned_at = time.monotonic()
        pilot.join(10.0)
        at_return = endpoint.stats
        pos_at_return = endpoint.state.pos_ned_m.copy()
        time.sleep(2.0)  # anything still streaming would show now
        later = endpoint.stats
        final = endpoint.state
    finally:
        link.close()
        endpoint.stop()
    assert outcome is not None and outcome.status == "handed_over", outcome
    _names_who_took_over(outcome.detail, mode)
    switch = marks["after_switch"]
    # No command at all after the pilot's: the pilot's own DO_SET_MODE retries are its only ones.
    assert later.commands_received == switch.commands_received
    # Setpoints stop once telemetry shows the new mode (one heartbeat at most), then none.
    heard_within_s = returned_at - marks["switched_at"]
    assert heard_within_s < 2.0
    assert later.setpoints_accepted + later.setpoints_rejected == (
        at_return.setpoints_accepted + at_return.setpoints_rejected
    )
    assert final.mode is FlightMode[mode]
    moved_m = float(np.linalg.norm(final.pos_ned_m[:2] - pos_at_return[:2]))
    if mode == "LAND":
        assert final.pos_ned_m[2] > pos_at_return[2] - 0.05  # descending (NED: down is +)
    elif mode == "POSCTL":  # centred sticks: brakes from the mission's speed, then holds
        assert float(np.hypot(*final.vel_ned_mps[:2])) < 0.3 and moved_m < 3.0, moved_m
    else:
        assert moved_m < 1.0


def fly_quietly(  # noqa: ANN001
    link, mission, progress=lambda _m: None, on_tick=lambda _t: None
) -> FlightOutcome:
    """The mission flown with the PD planner and the default runner settings; the progress
    lines go to ``progress`` (dropped by default), each control tick to ``on_tick``."""
    return fly_mission(
        link,
        make_planner("pd", 3.0),
        reference_of(mission),
        mission,
        RunnerConfig(),
        on_tick,
        progress,
    )


@pytest.mark.parametrize(
    ("param", "value", "named"),
    [("MPC_XY_VEL_MAX", 2.0, "command limit"), ("MPC_Z_VEL_MAX_UP", 1.0, "climb limit")],
)
def test_a_mission_beyond_the_vehicles_px4_limits_is_refused_before_take_off(
    param: str, value: float, named: str
) -> None:
    sim = Simulator(load_sim_config("iris"), seed=5)
    sim.set_param(param, value)
    link = CountingInProcessLink(sim)
    link.counting = True
    mission = load_mission(LINE)
    outcome = fly_quietly(link, mission)
    assert outcome.status == "refused"
    assert named in outcome.detail and param in outcome.detail and "\n" not in outcome.detail
    assert link.sent_after == [] and not sim.state.armed


def test_a_mission_longer_than_the_endurance_is_refused_before_take_off(tmp_path) -> None:
    short = tmp_path / "short_battery.toml"
    short.write_text(LINE.read_text().replace("[reference]", "endurance_s = 20.0\n\n[reference]"))
    sim = Simulator(load_sim_config("iris"), seed=5)
    link = CountingInProcessLink(sim)
    mission = load_mission(short)
    outcome = fly_quietly(link, mission)
    assert outcome.status == "refused" and "endurance_s 20 s" in outcome.detail
    assert "BAT_LOW_THR" in outcome.detail and not sim.state.armed


def _least_endurance_accepted_s(link, mission, config: RunnerConfig, reference_s: float) -> float:
    """Bisect the mission's endurance_s [s] down to the least the endurance check accepts."""
    low_s, high_s = 1.0, 10_000.0
    while high_s - low_s > 0.01:
        mid_s = 0.5 * (low_s + high_s)
        trial = dataclasses.replace(mission, endurance_s=mid_s)
        problem = mission_beyond_vehicle_limits(link, trial, config, reference_s)
        low_s, high_s = (mid_s, high_s) if "endurance_s" in problem else (low_s, mid_s)
    return high_s


def test_the_endurance_check_counts_the_longest_start_hold() -> None:
    rng = np.random.default_rng(17)
    hold_s = float(rng.uniform(5.0, 60.0))
    reserve = float(rng.uniform(0.1, 0.4))
    sim = Simulator(load_sim_config("iris"), seed=5)
    sim.set_param("BAT_LOW_THR", reserve)
    link = InProcessLink(sim)
    mission = load_mission(LINE)
    reference_s = reference_of(mission).duration_s
    without_s = _least_endurance_accepted_s(
        link, mission, RunnerConfig(start_settle_timeout_s=0.0), reference_s
    )
    with_s = _least_endurance_accepted_s(
        link, mission, RunnerConfig(start_settle_timeout_s=hold_s), reference_s
    )
    assert with_s - without_s == pytest.approx(hold_s / (1.0 - reserve), abs=0.05)


def test_a_pilot_switch_during_the_climb_is_handed_over_too() -> None:
    sim = Simulator(load_sim_config("iris"), seed=5)
    mission = load_mission(LINE)

    class PilotDuringClimb(CountingInProcessLink):
        def read_state(self):
            state = super().read_state()
            if state.mode == "TAKEOFF" and state.altitude_m > 1.0 and not self.counting:
                assert sim.set_mode(FlightMode.POSCTL).accepted
                self.counting = True
                state = super().read_state()
            return state

    link = PilotDuringClimb(sim)
    outcome = fly_quietly(link, mission)
    assert outcome.status == "handed_over", outcome.detail
    assert outcome.detail.startswith("pilot took control in POSCTL at t=")
    assert link.sent_after == [] and sim.state.mode is FlightMode.POSCTL


def test_a_pilot_switch_during_the_start_hold_is_handed_over_and_never_switched_back() -> None:
    """Climbed and holding, the companion streams zero setpoints before asking for OFFBOARD;
    a pilot who switches to POSCTL then has the vehicle: the companion hands over and never
    asks for OFFBOARD (which would take the vehicle back from the pilot)."""
    sim = Simulator(load_sim_config("iris"), seed=5)
    mission = load_mission(LINE)

    class PilotDuringTheHold(CountingInProcessLink):
        offboard_asked = False

        def send_velocity(self, command: VelocityCommand) -> None:
            super().send_velocity(command)
            if sim.state.mode is FlightMode.HOLD and not self.counting:
                assert sim.set_mode(FlightMode.POSCTL).accepted
                self.counting = True

        def start_offboard(self):
            self.offboard_asked = True
            return super().start_offboard()

    link = PilotDuringTheHold(sim)
    outcome = fly_quietly(link, mission)
    assert outcome.status == "handed_over", outcome.detail
    assert outcome.detail.startswith("pilot took control in POSCTL at t=")
    assert not link.offboard_asked
    assert "hold" not in link.sent_after and "land" not in link.sent_after
    assert sim.state.mode is FlightMode.POSCTL


STICKS_FORWARD_S = 3.0  # the pilot pushes forward this long, then centres and keeps sending


def _pilot_takes_over_with_sticks(
    port: int, endpoint: MavlinkEndpoint, marks: dict, done: threading.Event
) -> None:
    """A pilot with a MAVLink joystick (QGC's virtual one) on its own link: allows the stick
    override of OFFBOARD (COM_RC_OVERRIDE 3), waits for OFFBOARD plus a while, connects with
    centred sticks, then pushes the pitch stick forward, centres it and keeps sending centred
    sticks (so the manual-control-loss failsafe stays quiet) until ``done``; notes every mode
    seen after its takeover."""
    gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=245)
    rate_s = 0.1  # 10 Hz, as QGC's joystick
    try:
        gcs.mav.heartbeat_send(6, 8, 0, 0, 0)
        gcs.mav.param_set_send(1, 1, b"COM_RC_OVERRIDE", int32_as_float(3), 6)
        deadline = time.monotonic() + 90.0
        _await_offboard(gcs, endpoint, deadline, rate_s)
        marks["before_sticks"] = endpoint.stats
        for _ in range(3):  # the joystick connects centred (a first reading moves nothing)
            gcs.mav.manual_control_send(1, 0, 0, 500, 0, 0)
            time.sleep(rate_s)
        pushed_at = time.monotonic()
        modes_after: set[FlightMode] = set()
        while not done.is_set() and time.monotonic() < deadline:
            forward = time.monotonic() - pushed_at < STICKS_FORWARD_S
            gcs.mav.manual_control_send(1, 600 if forward else 0, 0, 500, 0, 0)
            mode = endpoint.state.mode
            if mode is FlightMode.POSCTL and "switched_at" not in marks:
                marks["switched_at"] = time.monotonic()
                marks["after_switch"] = endpoint.stats
            if "switched_at" in marks:
                modes_after.add(mode)
            time.sleep(rate_s)
        marks["modes_after"] = modes_after
    finally:
        gcs.close()


@pytest.mark.slow
def test_pilot_sticks_in_offboard_take_over_and_the_companion_yields() -> None:
    """COM_RC_OVERRIDE's offboard bit set, a pilot moving the sticks beyond COM_RC_STICK_OV
    puts the vehicle in POSCTL (PX4's "Pilot took over using sticks"); the companion, flying
    over pymavlink against a real endpoint, hands over: it stops its setpoints, never asks for
    OFFBOARD again, sends no command, and says so in one line."""
    companion_port = free_udp_port()
    endpoint = _iris_with_a_ground_station(companion_port)
    link = PymavlinkLink(f"udpin://127.0.0.1:{companion_port}")
    mission = load_mission(LINE)
    marks: dict = {}
    done = threading.Event()
    pilot = threading.Thread(
        target=_pilot_takes_over_with_sticks,
        args=(endpoint.local_ports["gcs"], endpoint, marks, done),
    )
    pilot.start()
    lines: list[str] = []
    outcome: FlightOutcome | None = None
    try:
        outcome = fly_quietly(link, mission, lines.append)
        at_return = endpoint.stats
        time.sleep(STICKS_FORWARD_S + 1.0)  # anything still streaming or commanding shows now
        later = endpoint.stats
        final_mode = endpoint.state.mode
    finally:
        done.set()
        pilot.join(10.0)
        link.close()
        endpoint.stop()
    assert outcome is not None and outcome.status == "handed_over", outcome
    assert outcome.detail.startswith("pilot took control in POSCTL at t=")
    assert "\n" not in outcome.detail
    assert any(line.startswith(outcome.detail) for line in lines)
    assert final_mode is FlightMode.POSCTL
    assert marks["modes_after"] == {FlightMode.POSCTL}  # never back to OFFBOARD
    switch = marks["after_switch"]
    assert later.commands_received == switch.commands_received  # no command after the pilot's
    assert later.setpoints_accepted + later.setpoints_rejected == (
        at_return.setpoints_accepted + at_return.setpoints_rejected
    )
    assert later.manual_control_accepted > switch.manual_control_accepted  # the pilot flies


def _iris_with_a_ground_station(companion_port: int) -> MavlinkEndpoint:
    """An iris endpoint sending to the companion's port, with a ground-station link of its own
    (``local_ports["gcs"]``) for the pilot."""
    links = (LinkConfig("offboard", remote=("127.0.0.1", companion_port)), LinkConfig("gcs"))
    sim = Simulator(load_sim_config("iris"), seed=7)
    return MavlinkEndpoint(sim, EndpointConfig(links=links)).start()


class RefusedOnceLink(CountingInProcessLink):
    """The real in-process link whose first OFFBOARD request the autopilot refuses (as PX4
    may, e.g. a setpoint stream it has not yet taken as fresh); the pilot then takes POSCTL
    while the companion streams before asking again."""

    def __init__(self, sim: Simulator) -> None:
        super().__init__(sim)
        self.offboard_requests = 0

    def start_offboard(self):
        self.offboard_requests += 1
        if self.counting:
            self.sent_after.append("offboard")
        if self.offboard_requests > 1:
            return super().start_offboard()
        assert self._sim.set_mode(FlightMode.POSCTL).accepted  # the pilot, meanwhile
        self.counting = True
        return CommandOutcome(False, "Offboard denied: no setpoint stream")


def test_a_pilot_who_takes_over_while_offboard_is_retried_is_not_fought() -> None:
    """OFFBOARD refused, then the pilot switches to POSCTL: the companion must not ask for
    OFFBOARD again (that would take the vehicle back from the pilot); it hands over."""
    sim = Simulator(load_sim_config("iris"), seed=5)
    link = RefusedOnceLink(sim)
    outcome = fly_quietly(link, load_mission(LINE))
    assert outcome.status == "handed_over", outcome.detail
    assert outcome.detail.startswith("pilot took control in POSCTL at t=")
    assert link.sent_after == []
    assert sim.state.mode is FlightMode.POSCTL


class _SaidLink:
    """What failsafe_said reads of a Link: its clock and the texts it heard."""

    def __init__(self, now_s: float, texts: list[tuple[float, str]]) -> None:
        self.clock = ManualClock()
        self.clock.sleep_until(now_s)
        self.texts = [StatusText(t, text) for t, text in texts]

    def status_texts(self) -> list[StatusText]:
        return self.texts


@pytest.mark.parametrize(
    ("texts", "said"),
    [
        ([(9.0, "Failsafe: battery critical, returning")], "Failsafe: battery critical, returning"),
        ([(9.0, "failsafe activated"), (9.5, "Takeoff detected")], "failsafe activated"),
        ([(9.5, "Failsafe activated\t")], "Failsafe activated"),  # PX4's own, with its tab
        ([(9.5, "Failsafe enabled: no datalink\t")], "Failsafe enabled: no datalink"),  # v1.13
        ([(10.0 - FAILSAFE_TEXT_RECENT_S - 0.1, "Failsafe: data link lost, returning")], ""),
        ([(9.9, "Offboard control lost")], ""),
        ([], ""),
    ],
)
def test_only_a_recent_text_naming_a_failsafe_explains_a_mode_change(
    texts: list[tuple[float, str]], said: str
) -> None:
    assert failsafe_said(_SaidLink(10.0, texts)) == said


class _WallLikeClock(ManualClock):
    """A ManualClock that says it runs on the wall clock (sleeping still only moves it)."""

    real_time = True


class _LateTextLink:
    """A link whose failsafe text reaches the companion ``delay_s`` after the mode change was
    seen (at t = 0), as MAVSDK's separate streams can deliver it on a loaded computer."""

    def __init__(self, clock: ManualClock, delay_s: float) -> None:
        self.clock = clock
        self._text = StatusText(delay_s, "Failsafe activated\t")

    def status_texts(self) -> list[StatusText]:
        return [self._text] if self.clock.now_s() >= self._text.t_s else []


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_failsafe_text_arriving_after_the_mode_change_still_names_it(seed: int) -> None:
    delay_s = float(np.random.default_rng(seed).uniform(0.05, 0.95) * FAILSAFE_TEXT_WAIT_S)
    detail = handover_detail(_LateTextLink(_WallLikeClock(), delay_s), "RTL", 5.0)
    assert detail.startswith("a PX4 failsafe took the vehicle out of OFFBOARD into RTL"), detail
    late = _LateTextLink(_WallLikeClock(), FAILSAFE_TEXT_WAIT_S + delay_s)
    detail = handover_detail(late, "RTL", 5.0)  # waits a bounded time, then names no one
    assert detail.startswith("the vehicle left OFFBOARD for RTL"), detail
    assert late.clock.now_s() == pytest.approx(FAILSAFE_TEXT_WAIT_S)
    pilot = _LateTextLink(_WallLikeClock(), delay_s)  # a manual mode: reported at once
    assert handover_detail(pilot, "POSCTL", 5.0).startswith("pilot took control in POSCTL")
    assert pilot.clock.now_s() == 0.0
    lockstep = _LateTextLink(ManualClock(), delay_s)  # in order by construction: no wait
    assert handover_detail(lockstep, "RTL", 5.0).startswith("the vehicle left OFFBOARD")
    assert lockstep.clock.now_s() == 0.0
