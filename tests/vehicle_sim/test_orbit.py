"""PX4's Orbit mode: the setpoint against hand-computed values, PX4's limits, and the simulator
circling at the commanded radius and speed, facing the centre."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vehicle_sim import FlightMode, Simulator, load_sim_config
from vehicle_sim.orbit import Orbit, limit_orbit, orbit_setpoint
from vehicle_sim.params import Px4Params

# PX4 defaults used below: MPC_XY_CRUISE 5 m/s, MC_YAW_P 2.8 /s, MPC_ACC_HOR 3 m/s^2,
# MPC_XY_VEL_MAX 12 m/s, MC_ORBIT_RAD_MAX 1000 m.
P = Px4Params()


def _orbit(velocity: float, behaviour: int = 0) -> Orbit:
    return Orbit((0.0, 0.0), -5.0, 10.0, velocity, behaviour, 0.3)


def _same_angle(a: float, b: float) -> bool:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi) < 1e-9


def test_setpoint_on_the_circle_by_hand() -> None:
    sp = orbit_setpoint(_orbit(3.0), (10.0, 0.0), P)  # due north of the centre
    assert sp.vel_ne_mps == pytest.approx((0.0, 3.0))  # clockwise: east
    assert sp.acc_ne_mps2 == pytest.approx((-0.9, 0.0))  # v^2/r = 0.9, inwards
    assert _same_angle(sp.yaw_rad, math.pi + 3.0 / 10.0 / 2.8)  # south, led by (v/r)/MC_YAW_P
    ccw = orbit_setpoint(_orbit(-3.0), (10.0, 0.0), P)
    assert ccw.vel_ne_mps == pytest.approx((0.0, -3.0))
    assert _same_angle(ccw.yaw_rad, math.pi - 3.0 / 10.0 / 2.8)


def test_setpoint_off_the_circle_approaches_it_at_cruise_speed_at_most() -> None:
    far = orbit_setpoint(_orbit(3.0), (0.0, 25.0), P)  # 15 m out, due east
    assert far.vel_ne_mps == pytest.approx((-3.0, -5.0))  # tangent south, in at MPC_XY_CRUISE
    near = orbit_setpoint(_orbit(3.0), (0.0, 12.0), P)
    assert near.vel_ne_mps == pytest.approx((-3.0, -2.0))  # 2 m out: in at 2 m/s


@pytest.mark.parametrize(
    ("behaviour", "yaw"),
    [(1, 0.3), (2, math.nan), (3, math.pi / 2 + 3.0 / 10.0 / 2.8), (4, math.nan)],
)
def test_yaw_behaviours(behaviour: int, yaw: float) -> None:
    sp = orbit_setpoint(_orbit(3.0, behaviour), (10.0, 0.0), P)
    assert math.isnan(sp.yaw_rad) if math.isnan(yaw) else _same_angle(sp.yaw_rad, yaw)


def test_px4s_limits() -> None:
    assert limit_orbit(10.0, 3.0, P) == (10.0, 3.0, "")
    radius, velocity, note = limit_orbit(0.5, -1.0, P)
    assert (radius, velocity) == (1.0, -1.0) and note == "Orbit: radius 0.5 m limited to 1 m"
    radius, velocity, note = limit_orbit(5.0, 5.0, P)  # v^2/r = 5 > MPC_ACC_HOR
    assert velocity == pytest.approx(0.99 * math.sqrt(15.0))
    assert note == "Orbit: speed 5 m/s limited to 3.83 m/s"
    assert limit_orbit(2000.0, -15.0, P)[:2] == (1000.0, -12.0)


def _hovering() -> Simulator:
    sim = Simulator(load_sim_config("iris"), seed=4)
    assert sim.arm().accepted and sim.takeoff(5.0).accepted
    sim.step(6.0)
    assert sim.state.mode is FlightMode.HOLD
    return sim


@pytest.mark.parametrize("radius", [10.0, -10.0])
def test_the_vehicle_circles_at_radius_and_speed_facing_the_centre(radius: float) -> None:
    sim = _hovering()
    centre = (sim.state.pos_ned_m[0] + 4.0, sim.state.pos_ned_m[1])
    alt_m = -sim.state.pos_ned_m[2]
    assert sim.orbit(radius, 3.0, 0, centre).accepted
    assert sim.state.mode is FlightMode.ORBIT
    sim.step(20.0)
    for _ in range(10):  # a few seconds of steady orbit, sampled
        sim.step(0.7)
        s = sim.state
        rel = s.pos_ned_m[:2] - centre
        assert np.hypot(*rel) == pytest.approx(10.0, abs=0.3)
        assert np.hypot(*s.vel_ned_mps[:2]) == pytest.approx(3.0, abs=0.2)
        turning = rel[0] * s.vel_ned_mps[1] - rel[1] * s.vel_ned_mps[0]  # > 0: clockwise
        assert math.copysign(1.0, turning) == math.copysign(1.0, radius)
        to_centre = math.atan2(-rel[1], -rel[0])
        assert abs((s.yaw_rad - to_centre + math.pi) % (2 * math.pi) - math.pi) < math.radians(3)
        assert -s.pos_ned_m[2] == pytest.approx(alt_m, abs=0.2)
    status = sim.orbit_status
    assert status is not None and status.radius_m == 10.0
    assert status.velocity_mps == math.copysign(3.0, radius)


def test_nan_keeps_the_orbit_flown_and_a_new_centre_moves_it() -> None:
    sim = _hovering()
    assert sim.orbit(-6.0, 2.0, 3).accepted
    here = tuple(sim.state.pos_ned_m[:2])
    assert sim.orbit_status.centre_ne_m == pytest.approx(here)  # no centre: the vehicle's
    assert sim.orbit(math.nan, 1.5, math.nan, (20.0, 0.0), -8.0).accepted
    status = sim.orbit_status
    assert (status.radius_m, status.velocity_mps, status.yaw_behaviour) == (6.0, -1.5, 3)
    assert status.centre_ne_m == (20.0, 0.0) and status.down_m == -8.0


def test_orbit_refused_on_the_ground_with_a_bad_yaw_behaviour_or_infinite_values() -> None:
    sim = Simulator(load_sim_config("iris"), seed=4)
    refused = sim.orbit(5.0, 1.0)
    assert not refused.accepted and "not flying" in refused.reason
    sim = _hovering()
    assert sim.orbit(5.0, 1.0, 7).result == "denied"
    with pytest.raises(ValueError):
        sim.orbit(math.inf, 1.0)
    with pytest.raises(ValueError):
        sim.orbit(5.0, 1.0, 0, (math.nan, 0.0))
    assert sim.state.mode is FlightMode.HOLD


def test_orbit_mode_by_set_mode_uses_px4s_defaults() -> None:
    sim = _hovering()
    assert sim.set_mode(FlightMode.ORBIT).accepted
    status = sim.orbit_status
    assert (status.radius_m, status.velocity_mps, status.yaw_behaviour) == (1.0, 1.0, 0)


def test_yaw_behaviour_unchanged_keeps_the_behaviour_flown() -> None:
    """ORBIT_YAW_BEHAVIOUR_UNCHANGED (5) is MAVLink's "keep the yaw behaviour": accepted as
    NaN is, not denied as an unknown behaviour."""
    sim = _hovering()
    assert sim.orbit(6.0, 1.0, 3).accepted
    changed = sim.orbit(8.0, math.nan, 5)
    assert changed.accepted, changed.reason
    assert (sim.orbit_status.radius_m, sim.orbit_status.yaw_behaviour) == (8.0, 3)
