"""Simulator.anchor puts the vehicle into a logged state; a replay from it continues the flight."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from tests.vehicle_sim.sim_flying import fly, hovering
from vehicle_sim import AnchorState, Simulator, VelocitySetpoint, load_sim_config

PAYLOAD = {"payload": {"mass_ratio": 1.3}}
SWEEP_NED_MPS = ((3.0, 1.0, 0.0), (-1.0, 2.5, -0.5), (0.0, 0.0, 0.5))


def anchor_from_row(row: dict, with_thrust: bool = True) -> AnchorState:
    """The anchor a replay builds from one schema-v1 log row."""
    return AnchorState(
        pos_ned_m=(row["pos_n_m"], row["pos_e_m"], row["pos_d_m"]),
        vel_ned_mps=(row["vel_n_mps"], row["vel_e_mps"], row["vel_d_mps"]),
        q_wxyz=(row["q_w"], row["q_x"], row["q_y"], row["q_z"]),
        rates_frd_radps=(row["rate_x_radps"], row["rate_y_radps"], row["rate_z_radps"]),
        thrust_n=row["thrust_n"] if with_thrust else None,
        acc_ned_mps2=(row["acc_n_mps2"], row["acc_e_mps2"], row["acc_d_mps2"]),
    )


def flying_payload_vehicle() -> Simulator:
    """A vehicle with 30 % payload (a large velocity integral) in the middle of a manoeuvre."""
    sim = hovering(PAYLOAD, settle_s=8.0)
    fly(sim, SWEEP_NED_MPS[0], 1.5)
    return sim


def fly_sweep(sim: Simulator, period_s: float = 0.05) -> np.ndarray:
    """(n, 3) velocity NED [m/s] over the sweep, one row per period."""
    vel = [s.vel_ned_mps for sp in SWEEP_NED_MPS for s in fly(sim, sp, 1.0, period_s)]
    return np.array(vel)


def test_anchoring_reproduces_the_logged_state_and_the_integral_behind_its_thrust():
    original = flying_payload_vehicle()
    original.set_velocity_setpoint(VelocitySetpoint(SWEEP_NED_MPS[0]))
    row = original.log_row(None)
    replica = hovering(PAYLOAD, seed=1, settle_s=1.0)
    replica.set_velocity_setpoint(VelocitySetpoint(SWEEP_NED_MPS[0]))
    replica.anchor(anchor_from_row(row), integral="match_thrust")
    got = replica.state
    want = original.state
    for name in ("pos_ned_m", "vel_ned_mps", "q_wxyz", "rates_frd_radps", "acc_ned_mps2"):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), atol=1e-9)
    assert got.thrust_n == pytest.approx(row["thrust_n"], rel=1e-9)
    # matched to the measured attitude, which lags the commanded one in a manoeuvre
    got_int, want_int = replica.velocity_integral_mps2, original.velocity_integral_mps2
    np.testing.assert_allclose(got_int[:2], want_int[:2], atol=0.2)
    assert got_int[2] == pytest.approx(want_int[2], abs=0.05)
    assert want_int[2] < -2.0  # the payload's share of the thrust was restored


def test_replaying_from_an_anchor_continues_the_original_flight():
    original = flying_payload_vehicle()
    original.set_velocity_setpoint(VelocitySetpoint(SWEEP_NED_MPS[0]))
    row = original.log_row(None)
    matched = hovering(PAYLOAD, seed=1, settle_s=1.0)
    matched.set_velocity_setpoint(VelocitySetpoint(SWEEP_NED_MPS[0]))
    matched.anchor(anchor_from_row(row), integral="match_thrust")
    cold = copy.deepcopy(matched)
    cold.anchor(anchor_from_row(row, with_thrust=False), integral="reset")
    truth = fly_sweep(original)
    err_matched = np.sqrt(np.mean((fly_sweep(matched) - truth) ** 2))
    err_cold = np.sqrt(np.mean((fly_sweep(cold) - truth) ** 2))
    assert err_matched < 0.05
    assert err_cold > 5 * err_matched  # without the restored integral the replay sinks


def test_reset_aligns_the_yaw_setpoint_with_the_anchored_yaw():
    sim = hovering(settle_s=1.0)
    yaw_rad = 1.2
    q = (math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2))
    pos = tuple(sim.state.pos_ned_m)
    sim.anchor(AnchorState(pos, (0.0, 0.0, 0.0), q), integral="reset")
    states = fly(sim, (0.0, 0.0, 0.0), 2.0)
    assert states[-1].yaw_rad == pytest.approx(yaw_rad, abs=0.02)


def test_a_nearly_unit_quaternion_is_normalised():
    s = AnchorState((0.0, 0.0, -1.0), (0.0, 0.0, 0.0), (1.005, 0.0, 0.0, 0.0))
    assert s.q_wxyz == (1.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"q_wxyz": (0.5, 0.0, 0.0, 0.0)}, "unit quaternion"),
        ({"vel_ned_mps": (0.0, math.nan, 0.0)}, "finite"),
        ({"pos_ned_m": (0.0, 0.0)}, "3 finite numbers"),
        ({"thrust_n": -1.0}, "thrust_n"),
        ({"acc_ned_mps2": "abc"}, "3 numbers"),
    ],
)
def test_bad_anchor_states_are_rejected(kwargs, match):
    fields = {
        "pos_ned_m": (0.0, 0.0, -1.0),
        "vel_ned_mps": (0.0, 0.0, 0.0),
        "q_wxyz": (1.0, 0.0, 0.0, 0.0),
        **kwargs,
    }
    with pytest.raises(ValueError, match=match):
        AnchorState(**fields)


def test_bad_integral_modes_are_rejected_and_leave_the_state():
    sim = hovering(settle_s=1.0)
    before = sim.state.pos_ned_m
    s = AnchorState((5.0, 0.0, -3.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="unknown; use one of"):
        sim.anchor(s, integral="zero")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="needs thrust_n and acc_ned_mps2"):
        sim.anchor(s, integral="match_thrust")
    np.testing.assert_array_equal(sim.state.pos_ned_m, before)


def test_the_jsbsim_backend_refuses_to_be_anchored():
    sim = Simulator(load_sim_config("f450"), backend="jsbsim")
    s = AnchorState((0.0, 0.0, -1.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    with pytest.raises(NotImplementedError, match="needs the builtin backend"):
        sim.anchor(s)


def test_the_velocity_integral_can_be_set_and_bad_values_are_rejected():
    sim = hovering(settle_s=1.0)
    sim.set_velocity_integral(np.array([0.1, -0.2, -0.3]))
    np.testing.assert_array_equal(sim.velocity_integral_mps2, [0.1, -0.2, -0.3])
    for bad in ((0.0, 0.0), (0.0, math.inf, 0.0)):
        with pytest.raises(ValueError, match="must be 3 finite numbers"):
            sim.set_velocity_integral(np.array(bad))
    np.testing.assert_array_equal(sim.velocity_integral_mps2, [0.1, -0.2, -0.3])
