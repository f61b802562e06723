import numpy as np
import pytest

from planners.bspline import BSplineReference
from planners.pd_regulator import PdGains, PdRegulator
from planners.reference import PlannerState

REF = BSplineReference(np.array([[0.0, 0.0, -2.0], [0.0, 0.0, -2.0 + 1e-9]]), yaw_rad=0.5)


def test_known_gains():
    state = PlannerState(np.array([-0.5, 0.2, -1.0]), np.array([0.4, 0.0, -0.2]), 0.3)
    res = PdRegulator().plan(state, REF, 0.0)
    assert res.ok and res.reason == ""
    expected = [1.2 * 0.5 - 0.25 * 0.4, 1.2 * -0.2, 0.9 * -1.0 - 0.25 * -0.2, 1.0 * 0.2]
    np.testing.assert_allclose(res.command, expected, atol=1e-9)


def test_speed_and_yaw_rate_saturate():
    state = PlannerState(np.array([20.0, -20.0, 5.0]), np.zeros(3), 0.5 + 4.0)
    res = PdRegulator(PdGains(max_speed_mps=1.5, max_yaw_rate_radps=0.4)).plan(state, REF, 0.0)
    assert np.linalg.norm(res.command[:3]) == pytest.approx(1.5)
    assert res.command[0] < 0 and res.command[1] > 0  # still points at the reference
    assert res.command[3] == pytest.approx(0.4)  # yaw error -4 rad wraps to +2.28 rad


def test_nan_state_gives_safe_command():
    state = PlannerState(np.array([np.nan, 0.0, 0.0]), np.zeros(3), 0.0)
    res = PdRegulator().plan(state, REF, 0.0)
    assert not res.ok and "non-finite" in res.reason
    np.testing.assert_array_equal(res.command, np.zeros(4))


def test_closed_loop_converges_to_a_fixed_point():
    reg, pos, vel = PdRegulator(), np.array([3.0, -2.0, -4.0]), np.zeros(3)
    for k in range(400):
        cmd = reg.plan(PlannerState(pos, vel, 0.5), REF, 0.05 * k).command
        vel = cmd[:3]
        pos = pos + 0.05 * vel
    np.testing.assert_allclose(pos, [0.0, 0.0, -2.0], atol=1e-3)
