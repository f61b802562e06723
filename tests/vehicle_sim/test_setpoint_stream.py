"""A stream of setpoint legs flies, to the last bit, as the same legs set and advanced one by
one, in one compiled call where the commander has nothing to do, and leg by leg from a
touchdown, an OFFBOARD loss or anything else the compiled call cannot fly."""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest

from tests.vehicle_sim.sim_flying import hovering
from vehicle_sim import (
    AnchorState,
    CheckedSetpoint,
    FlightMode,
    Simulator,
    StreamedLegs,
    VelocitySetpoint,
)
from vehicle_sim import physics as ph
from vehicle_sim.builtin_plant import BuiltinPlant


def legs(rng: np.random.Generator, n: int, down_mps: float = 0.0, every: int = 3):
    """n legs of random NED setpoints (every ``every``-th leg keeps the one in force; some
    with a yaw, some with a position) and durations 0-50 ms (some empty); ``down_mps`` is
    added to each setpoint's down speed."""
    setpoints = [
        None
        if i % every == every - 1
        else CheckedSetpoint(
            (*rng.uniform(-2.0, 2.0, 2), rng.uniform(-0.5, 0.5) + down_mps),
            float(rng.uniform(-0.3, 0.3)),
            yaw_rad=float(rng.uniform(-3.0, 3.0)) if i % 5 == 1 else None,
            pos_ned_m=(*rng.uniform(-1.0, 1.0, 2), -2.5) if i % 7 == 2 else None,
        )
        for i in range(n)
    ]
    durations = [
        float(rng.choice([0.0, 0.004, 0.02, 0.05, rng.uniform(0.0, 0.05)])) for _ in range(n)
    ]
    return setpoints, durations


def leg_by_leg(sim: Simulator, setpoints, durations, anchors=None) -> np.ndarray:
    """(n, 4) velocity NED and thrust after each leg, flown one by one."""
    out = []
    for i, (sp, d) in enumerate(zip(setpoints, durations, strict=True)):
        if sp is not None:
            sim.set_velocity_setpoint(sp)
        if anchors is not None and anchors[i] is not None:
            sim.anchor(anchors[i])
        sim.advance(d)
        out.append([*sim.vel_ned_mps, sim.thrust_n])
    return np.array(out).reshape(-1, 4)


def measured_anchors(
    sim: Simulator, setpoints, durations, rng: np.random.Generator, unanchored: float = 0.0
) -> tuple[list[AnchorState | None], Simulator]:
    """One anchor per leg from a copy of ``sim`` flying the legs (its velocity disturbed by
    0.05 m/s), a fraction ``unanchored`` of the legs left without one at random; and the
    copy after the legs."""
    measured = copy.deepcopy(sim)
    anchors = []
    for sp, d in zip(setpoints, durations, strict=True):
        if sp is not None:
            measured.set_velocity_setpoint(sp)
        measured.advance(d)
        s = measured.state
        anchors.append(
            None
            if rng.uniform() < unanchored
            else AnchorState(s.pos_ned_m, s.vel_ned_mps + rng.normal(0.0, 0.05, 3), s.q_wxyz,
                             s.rates_frd_radps)
        )  # fmt: skip
    return anchors, measured


def state_of(sim: Simulator) -> object:
    """Everything a later step of ``sim`` depends on, comparable with == (arrays by their
    bytes: bit for bit, NaN included)."""
    commander = sim._commander
    return plain(
        (sim._plant.x, sim._plant.aux, sim._cs, sim._sp, sim._k, list(sim._pending), sim._active,
         {k: v for k, v in vars(commander).items() if k not in ("params", "failsafes")},
         {k: v for k, v in vars(commander.failsafes).items() if k != "_params"},
         sim.params.version, [sim.params.get(n) for n in sim.params.names()])
    )  # fmt: skip


def plain(value: object) -> object:
    """``value`` with arrays as bytes and our objects as their attributes, recursively."""
    if isinstance(value, np.ndarray):
        return value.tobytes()
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return tuple(plain(v) for v in value)
    if hasattr(value, "__dict__") and type(value).__module__.startswith("vehicle_sim"):
        return (type(value).__name__, plain(vars(value)))
    return value


@pytest.fixture
def compiled_calls(monkeypatch):
    """How many streams the built-in plant flew in one compiled call (it still flies them)."""
    calls = []
    flown = BuiltinPlant.advance_scheduled

    def counted(self, *args):
        calls.append(flown(self, *args))
        return calls[-1]

    monkeypatch.setattr(BuiltinPlant, "advance_scheduled", counted)
    return calls


def check_same(sim: Simulator, setpoints, durations, anchors=None) -> StreamedLegs:
    twin = copy.deepcopy(sim)
    streamed = sim.stream_setpoints(setpoints, durations, anchors)
    expected = leg_by_leg(twin, setpoints, durations, anchors)
    assert np.array_equal(streamed.vel_ned_mps, expected[:, 0:3])
    assert np.array_equal(streamed.thrust_n, expected[:, 3])
    assert state_of(sim) == state_of(twin)
    return streamed


@pytest.mark.parametrize("delay_s", [0.0, 0.07])
def test_a_stream_in_offboard_is_one_compiled_call_with_the_same_numbers(delay_s, compiled_calls):
    effects = {"rotor_drag": {}, "command_delay": {"delay_s": delay_s}} if delay_s else None
    sim = hovering(effects, settle_s=1.0)
    hover = CheckedSetpoint((0.0, 0.0, 0.0))
    sim.stream_setpoints([hover] * 5, [0.05] * 5)  # the plain setpoints queued are released
    compiled_calls.clear()
    rng = np.random.default_rng(3)
    for n in (1, 7, 120):
        check_same(sim, *legs(rng, n))
    # a setpoint whose delay ends with the stream waits for the next stretch, after it
    check_same(sim, [CheckedSetpoint((0.5, 0.0, 0.0)), None], [delay_s, 0.0])
    check_same(sim, [None], [0.02])
    assert len(compiled_calls) == 5
    assert sim.state.mode is FlightMode.OFFBOARD


@pytest.mark.parametrize("delay_s", [0.0, 0.07])
def test_anchored_legs_are_one_compiled_call_with_the_same_numbers(delay_s, compiled_calls):
    """A replay's follower: each leg put into a measured state (here: a flight's own states,
    disturbed) before it flies; the anchors of a lead-in (thrust, acceleration) leg by leg."""
    effects = {"command_delay": {"delay_s": delay_s}} if delay_s else None
    sim = hovering(effects, settle_s=1.0)
    sim.stream_setpoints([CheckedSetpoint((0.0, 0.0, 0.0))] * 5, [0.05] * 5)
    compiled_calls.clear()
    rng = np.random.default_rng(8)
    setpoints, durations = legs(rng, 60)
    durations = [max(d, 0.004) for d in durations]  # anchored legs of at least a step
    anchors, _ = measured_anchors(sim, setpoints, durations, rng, unanchored=0.2)
    check_same(sim, setpoints, durations, anchors)
    assert len(compiled_calls) == 1
    last = next(a for a in reversed(anchors) if a is not None)
    lead = replace(last, thrust_n=9.0, acc_ned_mps2=np.zeros(3))
    check_same(sim, setpoints[:3], durations[:3], [last, lead, None])
    check_same(sim, setpoints[:2], [0.02, 0.0], [last, last])  # an empty anchored leg
    assert len(compiled_calls) == 1


def test_a_touchdown_mid_stream_is_flown_on_leg_by_leg_as_the_commander_sees_it(compiled_calls):
    sim = hovering(settle_s=1.0, alt_m=1.0)
    setpoints, durations = legs(np.random.default_rng(5), 150, down_mps=1.5, every=4)
    streamed = check_same(sim, setpoints, durations)
    assert compiled_calls and compiled_calls[0] < sum(round(d / 0.002) for d in durations)
    assert streamed.vel_ned_mps[-1] == pytest.approx(np.zeros(3))  # on the ground
    assert sim.state.landed_state.name == "ON_GROUND"


def test_an_anchored_stream_that_touches_down_flies_on_leg_by_leg_from_there(compiled_calls):
    """Anchors taken from a descending flight of the same vehicle (disturbed): the stream
    flies compiled until a step touches down, leg by leg from that step on."""
    sim = hovering(settle_s=1.0, alt_m=1.0)
    rng = np.random.default_rng(11)
    setpoints, durations = legs(rng, 150, down_mps=1.5, every=4)
    durations = [max(d, 0.004) for d in durations]
    anchors, measured = measured_anchors(sim, setpoints, durations, rng)
    assert measured.state.landed_state.name == "ON_GROUND"
    check_same(sim, setpoints, durations, anchors)
    assert compiled_calls and compiled_calls[0] < sum(round(d / 0.002) for d in durations)
    assert sim.state.landed_state.name == "ON_GROUND"


def test_setpoints_older_than_the_offboard_loss_time_fly_leg_by_leg_into_the_failsafe(
    compiled_calls,
):
    sim = hovering(settle_s=1.0)
    loss_s = sim.get_param("COM_OF_LOSS_T")
    setpoints = [CheckedSetpoint((1.0, 0.0, 0.0)), *[None] * 40]
    check_same(sim, setpoints, [loss_s / 20] * len(setpoints))
    assert compiled_calls == []
    assert sim.state.mode is not FlightMode.OFFBOARD


@pytest.mark.parametrize(
    "effects, setpoint",
    [
        ({"gusts": {"intensity_mps": 0.5}, "rotor_drag": {}}, CheckedSetpoint((1.0, 0.0, 0.0))),
        (None, CheckedSetpoint((1.0, 0.0, 0.0), frame="body")),
        (None, VelocitySetpoint((1.0, 0.0, 0.0))),
    ],
)
def test_what_the_compiled_call_cannot_fly_is_flown_leg_by_leg(effects, setpoint, compiled_calls):
    sim = hovering(effects, settle_s=1.0, seed=2)
    check_same(sim, [setpoint, None] * 20, [0.02, 0.03] * 20)
    assert compiled_calls == []


def test_a_sagging_battery_far_from_its_thresholds_streams_in_one_compiled_call(compiled_calls):
    sim = hovering({"battery_sag": {"full_flight_time_s": 60.0}}, settle_s=1.0)
    rng = np.random.default_rng(21)
    setpoints, durations = legs(rng, 120)
    durations = [max(d, 0.004) for d in durations]
    anchors, _ = measured_anchors(sim, setpoints, durations, rng, unanchored=0.2)
    check_same(sim, *legs(rng, 60))
    check_same(sim, setpoints, durations, anchors)
    assert len(compiled_calls) == 2
    assert sim._plant.x[ph.DISCHARGE] > 0.03  # it did discharge meanwhile


@pytest.mark.parametrize("threshold", ["BAT_LOW_THR", "BAT_CRIT_THR"])
def test_a_battery_that_may_reach_a_threshold_in_the_stream_flies_leg_by_leg(
    threshold, compiled_calls
):
    """Charge a few seconds of full thrust above a failsafe threshold: the commander must
    see it cross, so the legs fly one by one, with its warning."""
    sim = hovering({"battery_sag": {"full_flight_time_s": 60.0}}, settle_s=1.0)
    sim._plant.x[ph.DISCHARGE] = 1.0 - (sim.get_param(threshold) + 0.02)
    sim.stream_setpoints([None], [0.0])  # the commander sees the charge
    sim.drain_events()
    compiled_calls.clear()
    check_same(sim, [CheckedSetpoint((1.0, 0.0, 0.0)), None] * 60, [0.05] * 120)
    assert compiled_calls == []
    assert any(text.startswith("Battery ") for _severity, text in sim.drain_events())


def test_a_refused_leg_raises_after_the_legs_before_it_flew():
    sim = hovering(settle_s=1.0)
    twin = copy.deepcopy(sim)
    setpoints = [CheckedSetpoint((1.0, 0.0, 0.0))] * 3
    with pytest.raises(ValueError, match="step duration"):
        sim.stream_setpoints(setpoints, [0.02, 0.02, float("nan")])
    leg_by_leg(twin, setpoints[:2], [0.02, 0.02])
    twin.set_velocity_setpoint(setpoints[2])  # the third leg's setpoint was taken
    assert state_of(sim) == state_of(twin)
    with pytest.raises(ValueError, match="2 setpoints for 3 leg durations"):
        sim.stream_setpoints(setpoints[:2], [0.02] * 3)
