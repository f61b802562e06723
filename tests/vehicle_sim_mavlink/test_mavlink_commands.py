"""Command table against the real simulator (no sockets): results, modes, takeoff altitude."""

from __future__ import annotations

import math

import pytest

from vehicle_sim import FlightMode, Simulator, load_sim_config
from vehicle_sim.mavlink.commands import (
    MAV_RESULT_ACCEPTED,
    MAV_RESULT_DENIED,
    MAV_RESULT_TEMPORARILY_REJECTED,
    MAV_RESULT_UNSUPPORTED,
    CommandContext,
    handle_command,
)
from vehicle_sim.mavlink.scheduler import RateScheduler
from vehicle_sim.mavlink.telemetry import DEFAULT_RATES_HZ, TelemetryContext
from vehicle_sim.mission_plan import NAV_WAYPOINT, MissionItem

NAN7 = (math.nan,) * 7


def params(*values: float) -> tuple[float, ...]:
    return tuple(values) + (0.0,) * (7 - len(values))


@pytest.fixture
def ctx() -> CommandContext:
    sim = Simulator(load_sim_config("iris"), seed=0)
    return CommandContext(sim, TelemetryContext(), RateScheduler(DEFAULT_RATES_HZ))


def test_arm_then_takeoff_with_nan_params_climbs_to_mis_takeoff_alt(ctx):
    assert handle_command(400, params(1), ctx).result == MAV_RESULT_ACCEPTED
    assert handle_command(22, NAN7, ctx).result == MAV_RESULT_ACCEPTED
    ctx.sim.step(6.0)
    assert -ctx.sim.state.pos_ned_m[2] == pytest.approx(2.5, abs=0.15)


def test_takeoff_altitude_is_amsl_and_at_least_the_minimum(ctx):
    handle_command(400, params(1), ctx)
    low = handle_command(22, params(0, 0, 0, 0, 0, 0, 2.5), ctx)  # 2.5 m AMSL: below home
    assert low.result == MAV_RESULT_ACCEPTED
    assert any("minimum takeoff altitude" in text for _, text in low.notices)
    high = handle_command(22, params(0, 0, 0, 0, 0, 0, ctx.telemetry.origin.alt_amsl_m + 4.0), ctx)
    assert high.result == MAV_RESULT_ACCEPTED and high.notices == ()
    ctx.sim.step(8.0)
    assert -ctx.sim.state.pos_ned_m[2] == pytest.approx(4.0, abs=0.15)


def test_a_takeoff_above_home_but_below_the_minimum_climbs_to_the_minimum(ctx):
    """PX4's navigator: a takeoff altitude under MIS_TAKEOFF_ALT (2.5 m) above home, here 1 m,
    is raised to it ("Using minimum takeoff altitude: 2.50 m")."""
    handle_command(400, params(1), ctx)
    low = handle_command(22, params(0, 0, 0, 0, 0, 0, ctx.telemetry.origin.alt_amsl_m + 1.0), ctx)
    assert low.result == MAV_RESULT_ACCEPTED
    assert any("minimum takeoff altitude: 2.50 m" in text for _, text in low.notices)
    ctx.sim.step(6.0)
    assert -ctx.sim.state.pos_ned_m[2] == pytest.approx(2.5, abs=0.15)


@pytest.mark.parametrize(
    ("main", "sub", "mode"),
    [(3, 0, FlightMode.POSCTL), (4, 3, FlightMode.HOLD), (4, 6, FlightMode.LAND)],
)
def test_set_mode_maps_main_and_sub_mode(ctx, main, sub, mode):
    handle_command(400, params(1), ctx)
    assert handle_command(176, params(129, main, sub), ctx).result == MAV_RESULT_ACCEPTED
    assert ctx.sim.state.mode == mode


def test_offboard_without_setpoints_is_temporarily_rejected(ctx):
    assert handle_command(176, params(1, 6, 0), ctx).result == MAV_RESULT_TEMPORARILY_REJECTED


@pytest.mark.parametrize(
    ("command", "p", "result"),
    [
        (176, params(0, 6, 0), MAV_RESULT_DENIED),  # custom-mode flag missing
        (176, params(1, 9, 9), MAV_RESULT_DENIED),  # no such PX4 mode
        (176, params(1, math.nan, 0), MAV_RESULT_DENIED),
        (400, params(0.5), MAV_RESULT_DENIED),
        (400, params(math.nan), MAV_RESULT_DENIED),
        (512, params(-1), MAV_RESULT_DENIED),
        (511, params(30, math.nan), MAV_RESULT_DENIED),
        (42424, NAN7, MAV_RESULT_UNSUPPORTED),
    ],
)
def test_bad_parameters_are_denied_never_raised(ctx, command, p, result):
    assert handle_command(command, p, ctx).result == result
    assert not ctx.sim.state.armed


def test_disarm_in_air_needs_force(ctx):
    handle_command(400, params(1), ctx)
    handle_command(22, NAN7, ctx)
    ctx.sim.step(4.0)
    assert handle_command(400, params(0), ctx).result == MAV_RESULT_DENIED
    # [MAVLink] only param2 = 21196 forces it: any other value is no force
    assert handle_command(400, params(0, 1), ctx).result == MAV_RESULT_DENIED
    assert ctx.sim.state.armed
    assert handle_command(400, params(0, 21196), ctx).result == MAV_RESULT_ACCEPTED
    assert not ctx.sim.state.armed


def test_request_message_and_message_interval(ctx):
    outcome = handle_command(512, params(148), ctx)
    assert outcome.result == MAV_RESULT_ACCEPTED
    assert outcome.replies[0].get_type() == "AUTOPILOT_VERSION"
    assert handle_command(520, params(1), ctx).replies[0].get_type() == "AUTOPILOT_VERSION"
    assert handle_command(410, NAN7, ctx).replies[0].get_type() == "HOME_POSITION"
    assert handle_command(511, params(32, 100_000), ctx).result == MAV_RESULT_ACCEPTED
    interval = handle_command(510, params(32), ctx).replies[0]
    assert (interval.message_id, interval.interval_us) == (32, 100_000)
    # [MAVLink] MESSAGE_INTERVAL: -1 for a stream switched off (SET_MESSAGE_INTERVAL -1)
    assert handle_command(511, params(32, -1), ctx).result == MAV_RESULT_ACCEPTED
    interval = handle_command(510, params(32), ctx).replies[0]
    assert (interval.message_id, interval.interval_us) == (32, -1)
    # MESSAGE_INTERVAL's message_id is a uint16: a larger id cannot be answered
    assert handle_command(510, params(70_000), ctx).result == MAV_RESULT_DENIED


@pytest.mark.parametrize("lat", [90.5, -91.0])
def test_a_reposition_off_the_earth_is_denied_and_nothing_moves(ctx, lat):
    """DO_REPOSITION to a latitude outside [-90, 90] deg is no place: denied, the vehicle
    keeps its mode and its hold."""
    handle_command(400, params(1), ctx)
    handle_command(22, NAN7, ctx)
    ctx.sim.step(4.0)
    mode = ctx.sim.state.mode
    outcome = handle_command(192, params(-1, 0, 0, math.nan, lat, 8.5, math.nan), ctx)
    assert outcome.result == MAV_RESULT_DENIED
    assert any("invalid position" in text for _, text in outcome.notices)
    ctx.sim.step(1.0)
    assert ctx.sim.state.mode == mode
    assert abs(ctx.sim.state.pos_ned_m[0]) < 0.5


def test_gps_global_origin_on_request_is_home(ctx):
    outcome = handle_command(512, params(49), ctx)  # GPS_GLOBAL_ORIGIN
    assert outcome.result == MAV_RESULT_ACCEPTED
    origin, home = outcome.replies[0], ctx.telemetry.origin
    assert origin.get_type() == "GPS_GLOBAL_ORIGIN"
    assert (origin.latitude, origin.longitude) == (
        round(home.lat_deg * 1e7),
        round(home.lon_deg * 1e7),
    )
    assert origin.altitude == round(home.alt_amsl_m * 1000.0)


def _three_waypoints(ctx) -> None:
    points = ((5.0, 0.0, -3.0), (5.0, 5.0, -3.0), (0.0, 5.0, -3.0))
    ctx.sim.set_mission(tuple(MissionItem(NAV_WAYPOINT, p) for p in points))


def test_mission_start_from_an_item_switches_to_auto_mission(ctx):
    _three_waypoints(ctx)
    handle_command(400, params(1), ctx)
    assert handle_command(300, params(1, 2), ctx).result == MAV_RESULT_ACCEPTED
    assert ctx.sim.state.mode == FlightMode.MISSION and ctx.sim.mission_current == 1
    ctx.sim.step(3.0)
    assert ctx.sim.state.mode == FlightMode.MISSION  # flying it, not refused


def test_mission_start_without_a_mission_or_with_a_bad_item_is_refused(ctx):
    handle_command(400, params(1), ctx)
    assert handle_command(300, params(math.nan), ctx).result == MAV_RESULT_DENIED
    _three_waypoints(ctx)
    bad = handle_command(300, params(7), ctx)
    assert bad.result == MAV_RESULT_DENIED
    assert any("mission item 7 does not exist" in text for _, text in bad.notices)
    assert ctx.sim.state.mode != FlightMode.MISSION


def test_do_set_mission_current_selects_keeps_resets_and_refuses(ctx):
    _three_waypoints(ctx)
    assert handle_command(224, params(2), ctx).result == MAV_RESULT_ACCEPTED
    assert ctx.sim.mission_current == 2
    assert handle_command(224, params(-1), ctx).result == MAV_RESULT_ACCEPTED
    assert ctx.sim.mission_current == 2
    assert handle_command(224, params(-1, 1), ctx).result == MAV_RESULT_ACCEPTED
    assert ctx.sim.mission_current == 0
    assert handle_command(224, params(3), ctx).result == MAV_RESULT_DENIED
    assert handle_command(224, params(0.5), ctx).result == MAV_RESULT_DENIED
    assert ctx.sim.mission_current == 0
