"""Latency compensation: the NMPC plans from the state predicted over the known latency."""

import numpy as np
import pytest

from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from planners.reference import PlannerState


def test_the_state_is_predicted_forward_under_the_last_command_with_the_planner_model():
    rng = np.random.default_rng(5)
    latency_s, tau_s = rng.uniform(0.02, 0.15), rng.uniform(0.2, 0.6)
    settings = NmpcSettings(
        speed_limit_mps=3.0,
        nominal_model="first_order_lag",
        nominal_params=(("tau_d_s", tau_s), ("tau_s", tau_s)),
        latency_s=latency_s,
        max_iterations=1,
    )
    planner = CompanionNmpc(settings)
    state = PlannerState(np.array([1.0, 2.0, -3.0]), np.array([0.5, 0.0, 0.0]), 0.3)
    command = np.array([2.0, -1.0, 0.0, 0.0])
    ahead = planner._predicted(state, command)
    # the exact first-order lag: v(t) = u + (v0 - u) e^(-t/tau)
    decay = np.exp(-latency_s / tau_s)
    vel = command[:3] + (state.vel_ned_mps - command[:3]) * decay
    pos = (
        state.pos_ned_m
        + command[:3] * latency_s
        + (state.vel_ned_mps - command[:3]) * tau_s * (1 - decay)
    )
    np.testing.assert_allclose(ahead.vel_ned_mps, vel, atol=1e-4)  # one RK4 step
    np.testing.assert_allclose(ahead.pos_ned_m, pos, atol=1e-4)  # one RK4 step
    assert ahead.yaw_rad == pytest.approx(0.3)


def test_a_latency_beyond_the_horizon_is_refused_in_one_line():
    with pytest.raises(ValueError, match="latency_s must be in"):
        NmpcSettings(speed_limit_mps=3.0, latency_s=5.0)


class _Line:
    """Fly north at 1 m/s from (0, 0, -3)."""

    duration_s = 10.0

    def sample(self, t_s):
        from planners.reference import ReferenceSample

        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        pos = np.column_stack([t, np.zeros_like(t), np.full_like(t, -3.0)])
        vel = np.tile([1.0, 0.0, 0.0], (t.size, 1))
        return ReferenceSample(pos, vel, np.zeros_like(vel), np.zeros(t.size), np.zeros(t.size))


def test_a_late_plan_flies_on_the_previous_plan_instead_of_braking():
    from planners.plan_result import safe_result

    planner = CompanionNmpc(NmpcSettings(speed_limit_mps=3.0, time_budget_s=10.0))
    state = PlannerState(np.array([0.0, 0.0, -3.0]), np.zeros(3), 0.0)
    first = planner.plan(state, _Line(), 1.0)
    assert first.ok
    late = safe_result(4, planner.model.nx, "late: solve took 0.05 s > budget 0.02 s", 0.05)
    planner._planner.plan = lambda *args: late  # the next solve comes back late
    second = planner.plan(state, _Line(), 1.13)
    assert second.ok
    np.testing.assert_allclose(second.command, first.predicted_inputs[1])
    stale = planner.plan(state, _Line(), 1.5)  # older than LATE_FALLBACK_S: brake
    assert not stale.ok
