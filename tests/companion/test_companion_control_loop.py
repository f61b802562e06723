"""The fixed-rate loop and the flight recorder, on a test-double link with a manual clock."""

from __future__ import annotations

import numpy as np
import pytest

from companion.control_loop import Tick, run_fixed_rate
from companion.decision import Decision, safe_decision
from companion.flight_recorder import FlightRecorder
from companion.link import LandedPhase, LinkState, VelocityCommand
from flightlog.schema import read_flight_log, write_flight_log


class ManualClock:
    """Time moves only when slept or when ``work`` is spent."""

    real_time = False

    def __init__(self) -> None:
        self.t_s = 0.0

    def now_s(self) -> float:
        return self.t_s

    def sleep_until(self, t_s: float) -> None:
        self.t_s = max(self.t_s, t_s)


class IntegratorLink:
    """Flies the commanded velocity exactly (a kinematic vehicle) - a loop test double."""

    name = "double"

    def __init__(self, nan_at_tick: int | None = None) -> None:
        self.clock = ManualClock()
        self.pos = np.array([0.0, 0.0, -2.0])
        self.vel = np.zeros(3)
        self.sent: list[VelocityCommand] = []
        self.nan_at_tick = nan_at_tick

    def read_state(self) -> LinkState:
        pos = self.pos.copy()
        if self.nan_at_tick is not None and len(self.sent) == self.nan_at_tick:
            pos[0] = np.nan
        return LinkState(
            t_s=self.clock.now_s(),
            pos_ned_m=pos,
            vel_ned_mps=self.vel.copy(),
            q_wxyz=np.array([1.0, 0.0, 0.0, 0.0]),
            rates_frd_radps=np.zeros(3),
            armed=True,
            mode="OFFBOARD",
            landed=LandedPhase.IN_AIR,
        )

    def send_velocity(self, command: VelocityCommand) -> None:
        self.sent.append(command)
        self.vel = np.array(command.vel_ned_mps)


class GoNorth:
    """1 m/s north; optionally spends ``work_s`` of clock time deciding."""

    def __init__(self, clock: ManualClock | None = None, work_s: float = 0.0) -> None:
        self.clock = clock
        self.work_s = work_s

    def decide(self, state: LinkState, t_s: float) -> Decision:
        if self.clock is not None:
            self.clock.t_s += self.work_s
        return Decision(VelocityCommand((1.0, 0.0, 0.0)), ref_pos_ned_m=np.array([t_s, 0, -2]))


def test_loop_ticks_at_its_rate_until_the_condition_and_sends_nothing_once_it_holds() -> None:
    link = IntegratorLink()
    ticks: list[Tick] = []
    result = run_fixed_rate(
        link,
        GoNorth(),
        rate_hz=50.0,
        until=lambda s, t: t >= 1.0,
        timeout_s=5.0,
        on_tick=ticks.append,
    )
    assert result.stop_reason == "done"
    assert result.ticks == 50 == len(link.sent) == len(ticks)
    assert ticks[-1].t_s == pytest.approx(0.98)
    assert result.deadline_misses == 0
    np.testing.assert_allclose(np.diff([t.t_s for t in ticks]), 0.02)


def test_loop_stops_at_its_timeout() -> None:
    link = IntegratorLink()
    result = run_fixed_rate(
        link,
        GoNorth(),
        rate_hz=20.0,
        until=lambda s, t: False,
        timeout_s=0.5,
        on_tick=lambda tick: None,
    )
    assert result.stop_reason == "timeout"
    assert result.ticks == 10
    assert link.clock.t_s == pytest.approx(0.5)


@pytest.mark.parametrize("work_s", [0.05, 0.03])
def test_overrunning_ticks_count_as_deadline_misses_and_do_not_burst(work_s: float) -> None:
    link = IntegratorLink()
    slow = GoNorth(link.clock, work_s=work_s)  # 50 or 30 ms of work at a 20 ms period
    ticks: list[Tick] = []
    result = run_fixed_rate(
        link,
        slow,
        rate_hz=50.0,
        until=lambda s, t: len(ticks) >= 10,
        timeout_s=5.0,
        on_tick=ticks.append,
    )
    assert result.deadline_misses == 10  # every one of the 10 ticks overran
    assert min(np.diff([t.t_s for t in ticks])) == pytest.approx(work_s)


def test_bad_rate_is_refused() -> None:
    with pytest.raises(ValueError, match="rate_hz must be positive"):
        run_fixed_rate(
            IntegratorLink(),
            GoNorth(),
            rate_hz=0.0,
            until=lambda s, t: True,
            timeout_s=1.0,
            on_tick=lambda tick: None,
        )


def test_recorded_log_validates_and_holds_the_commands_sent(tmp_path) -> None:
    link = IntegratorLink(nan_at_tick=5)
    recorder = FlightRecorder(period_s=0.02)
    policy = GoNorth()

    class SafeOnNaN:
        def decide(self, state: LinkState, t_s: float) -> Decision:
            if not state.is_finite():
                return safe_decision("non-finite telemetry")
            return policy.decide(state, t_s)

    run_fixed_rate(
        link,
        SafeOnNaN(),
        rate_hz=50.0,
        until=lambda s, t: t >= 0.4,
        timeout_s=1.0,
        on_tick=recorder.record,
    )
    path = write_flight_log(tmp_path / "f.csv", recorder.to_log({"source": "test"}))
    log = read_flight_log(path)
    assert log.n_rows == len(link.sent) - 1  # the NaN tick is not a row
    sent = np.array([c.vel_ned_mps for i, c in enumerate(link.sent) if i != 5])
    np.testing.assert_array_equal(
        log.stack("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps"), sent
    )
    assert log.has("ref_pos_n_m", "planner_ok", "solve_time_s", "mode", "armed")
    assert not log.has("acc_n_mps2", "thrust_n", "pred_vel_n_mps")
    events = log.metadata["safe_command_events"]
    assert events == [
        {"t_first_s": 0.1, "t_last_s": 0.1, "count": 1, "reason": "non-finite telemetry"}
    ]


def test_prediction_columns_are_filled_with_the_nominal_prediction_when_missing() -> None:
    recorder = FlightRecorder(period_s=0.1)
    link = IntegratorLink()
    for i in range(3):
        link.clock.t_s = 0.1 * i
        state = link.read_state()
        pred = np.array([9.0, 9.0, 9.0]) if i == 1 else None
        cmd = VelocityCommand((1.0, 2.0, 0.0))
        recorder.record(
            Tick(link.clock.t_s, state, Decision(cmd, pred_pos_ned_m=pred, pred_vel_ned_mps=pred))
        )
    log = recorder.to_log({})
    np.testing.assert_allclose(log["pred_vel_n_mps"], [1.0, 9.0, 1.0])
    np.testing.assert_allclose(log["pred_pos_e_m"], [0.2, 9.0, 0.2])
