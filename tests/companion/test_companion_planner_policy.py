"""The planner guard: whatever the planner does, the loop gets a finite, saturated command."""

from __future__ import annotations

import math

import numpy as np
import pytest

from companion.decision import CommandLimits, HoverPolicy
from companion.link import LandedPhase, LinkState, VelocityCommand
from companion.planner_policy import PlannerPolicy
from planners.plan_result import PlanResult

LIMITS = CommandLimits(horizontal_mps=2.0, up_mps=1.5, down_mps=1.0, yaw_rate_radps=0.5)


class LineReference:
    """x_ref moves north at 1 m/s from the origin at 2 m altitude."""

    duration_s = 10.0

    def x_ref(self, t_s: float) -> np.ndarray:
        return np.array([float(t_s), 0.0, -2.0, 0.0])


class ScriptedPlanner:
    """Returns whatever ``answer(state, t_s)`` gives (or raises what it raises)."""

    def __init__(self, answer) -> None:
        self.answer = answer
        self.seen: list[tuple[np.ndarray, float]] = []

    def plan(self, state, reference, t_s: float) -> PlanResult:
        self.seen.append((state.pos_ned_m, t_s))
        return self.answer(state, t_s)


def state(pos=(1.0, 0.0, -2.0), vel=(0.5, 0.0, 0.0)) -> LinkState:
    return LinkState(
        t_s=0.0,
        pos_ned_m=np.array(pos, dtype=float),
        vel_ned_mps=np.array(vel, dtype=float),
        q_wxyz=np.array([1.0, 0.0, 0.0, 0.0]),
        rates_frd_radps=np.zeros(3),
        armed=True,
        mode="OFFBOARD",
        landed=LandedPhase.IN_AIR,
    )


def ok_result(command, trajectory=None) -> PlanResult:
    trajectory = np.zeros((0, 4)) if trajectory is None else trajectory
    return PlanResult(np.asarray(command, float), trajectory, True, "", 0.004)


def policy(planner) -> PlannerPolicy:
    return PlannerPolicy(planner, LineReference(), 100.0, LIMITS)


def test_good_command_is_sent_saturated_with_reference_time_and_ref_pos() -> None:
    planner = ScriptedPlanner(lambda s, t: ok_result([3.0, 4.0, -5.0, 2.0]))
    d = policy(planner).decide(state(), 103.0)
    assert d.ok and d.reason == ""
    assert planner.seen[0][1] == pytest.approx(3.0)
    n, e, down = d.command.vel_ned_mps
    assert math.hypot(n, e) == pytest.approx(2.0)
    assert n / e == pytest.approx(3.0 / 4.0)
    assert down == -1.5
    assert d.command.yaw_rate_radps == 0.5
    np.testing.assert_allclose(d.ref_pos_ned_m, [3.0, 0.0, -2.0])
    assert d.solve_time_s == 0.004
    assert d.pred_vel_ned_mps is None


def test_a_command_within_the_limits_is_sent_unchanged_and_a_descent_is_held_to_down_mps():
    """0.5 m/s horizontal is under 2 m/s: not scaled up to the limit; 2 m/s down is cut to
    1 m/s (down_mps), a -3 rad/s yaw rate to -0.5 rad/s."""
    sent = LIMITS.apply(np.array([0.3, -0.4, 2.0]), -3.0)
    assert sent == VelocityCommand((0.3, -0.4, 1.0), -0.5)
    assert LIMITS.apply(np.zeros(3), 0.2) == VelocityCommand((0.0, 0.0, 0.0), 0.2)


@pytest.mark.parametrize(
    ("answer", "reason"),
    [
        (lambda s, t: 1 / 0, "planner raised ZeroDivisionError"),
        (lambda s, t: ok_result([np.nan, 0.0, 0.0, 0.0]), "unusable command"),
        (lambda s, t: ok_result([1.0, 0.0]), "unusable command"),
        (
            lambda s, t: PlanResult(np.ones(4), np.zeros((0, 4)), False, "solver diverged", 0.1),
            "planner failed: solver diverged",
        ),
    ],
)
def test_planner_failures_give_zero_velocity_and_a_reason(answer, reason: str) -> None:
    d = policy(ScriptedPlanner(answer)).decide(state(), 101.0)
    assert not d.ok
    assert reason in d.reason
    assert d.command == VelocityCommand((0.0, 0.0, 0.0), 0.0)
    np.testing.assert_allclose(d.ref_pos_ned_m, [1.0, 0.0, -2.0])


def test_non_finite_telemetry_never_reaches_the_planner() -> None:
    planner = ScriptedPlanner(lambda s, t: ok_result([1.0, 0.0, 0.0, 0.0]))
    d = policy(planner).decide(state(pos=(np.nan, 0.0, -2.0)), 101.0)
    assert not d.ok and d.reason == "non-finite telemetry"
    assert planner.seen == []
    assert d.command.vel_ned_mps == (0.0, 0.0, 0.0)


def test_prediction_row_one_kinematic() -> None:
    traj = np.array([[1.0, 0.0, -2.0, 0.0], [1.02, 0.0, -2.0, 0.0]])
    kin = policy(ScriptedPlanner(lambda s, t: ok_result([1.0, 0.0, 0.0, 0.0], traj)))
    np.testing.assert_allclose(kin.decide(state(), 101.0).pred_pos_ned_m, [1.02, 0.0, -2.0])
    np.testing.assert_allclose(kin.decide(state(), 101.0).pred_vel_ned_mps, [1.0, 0.0, 0.0])


def test_velocity_command_rejects_non_finite_values() -> None:
    with pytest.raises(ValueError, match="finite"):
        VelocityCommand((0.0, math.inf, 0.0))


def test_hover_policy_streams_zero_velocity_with_its_hold_point() -> None:
    d = HoverPolicy(np.array([1.0, 2.0, -3.0])).decide(state(), 0.0)
    assert d.ok and d.command.vel_ned_mps == (0.0, 0.0, 0.0)
    np.testing.assert_allclose(d.ref_pos_ned_m, [1.0, 2.0, -3.0])
