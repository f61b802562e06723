"""Each named effect against a hand calculation, open loop (velocity loop frozen: fixed motor
commands) and closed loop under the flight control."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.vehicle_sim.sim_flying import fly, hovering
from vehicle_sim import load_sim_config
from vehicle_sim import physics as ph
from vehicle_sim.builtin_plant import BuiltinPlant
from vehicle_sim.config import GRAVITY_MPS2 as G

DT = 0.002
IRIS = load_sim_config("iris").vehicle
M = IRIS.mass_kg
N_HOVER = math.sqrt(IRIS.hover_thrust_norm)  # normalised rotor speed that carries the weight


def in_air(effects, alt_m=50.0, vel=(0.0, 0.0, 0.0), yaw_rad=0.0) -> BuiltinPlant:
    """A plant flying level at ``alt_m`` with its rotors at nominal hover speed."""
    p = BuiltinPlant(load_sim_config("iris", effects))
    p.x[ph.POS + 2] = -alt_m
    p.x[ph.VEL : ph.VEL + 3] = vel
    p.x[ph.QUAT : ph.QUAT + 4] = (math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2))
    p.x[ph.MOTORS : ph.MOTORS + 4] = N_HOVER
    return p


def accel(p: BuiltinPlant) -> np.ndarray:
    """Instantaneous acceleration NED of the plant's state, rotors commanded at hover."""
    dx = np.zeros(ph.N_DYN)
    cmd = np.full(4, N_HOVER)
    ph.derivatives(
        p.x,
        cmd,
        p.pp,
        p.rp,
        p.spin,
        p.ep,
        p.x[ph.GUST : ph.GUST + 3],
        ph.thrust_factor(p.x, p.ep),
        dx,
    )
    return dx[ph.VEL : ph.VEL + 3]


def coast(p: BuiltinPlant, seconds: float, noise=None, n_cmd=N_HOVER) -> None:
    noise = np.zeros((0, 3)) if noise is None else noise
    ph.run_plant(
        round(seconds / DT), DT, p.x, np.full(4, n_cmd), p.pp, p.rp, p.spin, p.ep, noise, p.aux
    )


def test_no_effect_hover_is_force_free():
    np.testing.assert_allclose(accel(in_air(None, vel=(3.0, -2.0, 1.0))), 0.0, atol=1e-12)


def test_rotor_drag_decelerates_by_k_v_over_m_in_body_axes():
    k = (0.4, 0.3, 0.2)
    p = in_air({"rotor_drag": {"k_n_per_mps": k}}, vel=(3.0, -2.0, 1.0))
    np.testing.assert_allclose(accel(p), (-0.4 * 3 / M, 0.3 * 2 / M, -0.2 * 1 / M), rtol=1e-12)
    # heading east, flying north: the velocity is along the body's -y axis, so k_y acts
    p = in_air(
        {"rotor_drag": {"k_n_per_mps": (0.5, 0.1, 0.0)}}, vel=(2.0, 0.0, 0.0), yaw_rad=math.pi / 2
    )
    np.testing.assert_allclose(accel(p), (-0.1 * 2 / M, 0.0, 0.0), atol=1e-12)
    # coasting with the velocity loop frozen: v(t) = v0 exp(-k t / m)
    p = in_air({"rotor_drag": {"k_n_per_mps": k}}, vel=(3.0, 0.0, 0.0))
    coast(p, 2.0)
    assert p.x[ph.VEL] == pytest.approx(3.0 * math.exp(-0.4 * 2.0 / M), rel=1e-6)


def test_body_drag_is_quadratic():
    c = (0.05, 0.04, 0.1)
    p = in_air({"body_drag": {"c_n_per_mps2": c}}, vel=(4.0, -3.0, 0.0))
    np.testing.assert_allclose(accel(p), (-0.05 * 16 / M, 0.04 * 9 / M, 0.0), rtol=1e-12)


def test_wind_acts_through_drag_on_the_air_relative_velocity():
    effects = {"rotor_drag": {"k_n_per_mps": (0.4, 0.4, 0.1)}, "wind": {"vel_ned_mps": (3, 0, 0)}}
    np.testing.assert_allclose(accel(in_air(effects)), (0.4 * 3 / M, 0, 0), atol=1e-12)
    np.testing.assert_allclose(accel(in_air(effects, vel=(3.0, 0.0, 0.0))), 0.0, atol=1e-12)
    # closed loop: holds zero velocity, leaning into the wind by atan(k w / (m g))
    sim = hovering(effects, settle_s=15.0)
    s = fly(sim, (0.0, 0.0, 0.0), 1.0)[-1]
    assert np.linalg.norm(s.vel_ned_mps) < 0.01
    w, x, y, z = s.q_wxyz
    pitch = math.asin(2 * (w * y - z * x))
    assert pitch == pytest.approx(math.atan(0.4 * 3 / (M * G)), rel=0.02)  # wind from behind


def test_gusts_are_seeded_zero_mean_with_the_configured_intensity():
    sigma, length = 1.5, 2.0  # ~2 s correlation time at hover (speed floor 1 m/s)
    samples = []
    p = BuiltinPlant(
        load_sim_config(
            "iris", {"rotor_drag": {}, "gusts": {"intensity_mps": sigma, "length_scale_m": length}}
        )
    )
    noise = np.random.default_rng(3).standard_normal((1_000_000, 3))
    for i in range(20_000):  # 2000 s on the ground, sampled every 0.1 s
        coast(p, 0.1, noise[i * 50 : (i + 1) * 50], n_cmd=0.0)
        samples.append(p.x[ph.GUST : ph.GUST + 3].copy())
    g = np.array(samples)
    np.testing.assert_allclose(g.std(axis=0), sigma, rtol=0.08)
    assert np.all(np.abs(g.mean(axis=0)) < 0.15 * sigma)
    lag1 = np.mean(g[1:] * g[:-1], axis=0) / g.var(axis=0)  # a = exp(-0.1 s * 1 m/s / L)
    np.testing.assert_allclose(lag1, math.exp(-0.1 / length), atol=0.03)


def test_gusts_move_a_hovering_vehicle_reproducibly_per_seed():
    effects = {"rotor_drag": {}, "gusts": {"intensity_mps": 2.0}}
    runs = {}
    for seed in (1, 1, 2):
        sim = hovering(effects, seed=seed, settle_s=1.0)
        runs.setdefault(seed, []).append(np.array([s.vel_ned_mps for s in fly(sim, (0, 0, 0), 5)]))
    np.testing.assert_array_equal(runs[1][0], runs[1][1])
    assert not np.allclose(runs[1][0], runs[2][0])
    assert np.abs(runs[1][0][:, :2]).max() > 0.02  # pushed around
    calm = hovering(settle_s=1.0)
    assert np.abs([s.vel_ned_mps for s in fly(calm, (0, 0, 0), 5)]).max() < 1e-3


def test_payload_scales_mass():
    ratio = 1.3
    p = in_air({"payload": {"mass_ratio": ratio}})
    np.testing.assert_allclose(accel(p), (0.0, 0.0, G * (1 - 1 / ratio)), rtol=1e-12)
    nominal = hovering(settle_s=8.0).state.thrust_n
    heavy = hovering({"payload": {"mass_ratio": ratio}}, settle_s=8.0).state.thrust_n
    assert nominal == pytest.approx(M * G, rel=1e-3)
    assert heavy == pytest.approx(ratio * nominal, rel=1e-3)


def test_battery_sag_loses_thrust_with_discharge():
    effects = {"battery_sag": {"full_flight_time_s": 100.0, "max_thrust_loss": 0.3}}
    p = in_air(effects)
    p.x[ph.DISCHARGE] = 0.5
    np.testing.assert_allclose(accel(p), (0.0, 0.0, G * 0.3 * 0.5), rtol=1e-12)
    p = in_air(effects)
    coast(p, 10.0)  # at nominal hover thrust the discharge grows at 1 / full_flight_time_s
    assert p.x[ph.DISCHARGE] == pytest.approx(0.1, rel=1e-9)
    # closed loop: holds altitude with ever more rotor speed while the voltage falls
    sim = hovering(effects, settle_s=2.0)
    s0 = sim.state
    s1 = fly(sim, (0.0, 0.0, 0.0), 20.0)[-1]
    d0, d1 = (
        (IRIS.battery_full_v - s.battery_v) / (IRIS.battery_full_v - IRIS.battery_empty_v)
        for s in (s0, s1)
    )
    for s, d in ((s0, d0), (s1, d1)):
        assert s.thrust_n == pytest.approx(M * G / (1 - 0.3 * d), rel=2e-3)
    assert d1 > d0 + 0.15 and s1.thrust_n > s0.thrust_n
    assert hovering(settle_s=1.0).state.battery_v == IRIS.battery_full_v  # ideal without it


def test_ground_effect_raises_thrust_below_two_rotor_radii_only():
    gain, radius, height = 0.25, 0.127, 0.1
    effects = {
        "ground_effect": {"max_gain": gain, "rotor_radius_m": radius, "rotor_height_m": height}
    }
    for alt in (0.0, 0.05, 0.12, 2 * radius - height - 1e-3):
        h = alt + height
        expected = -G * gain * (1 - h / (2 * radius)) ** 2
        p = in_air(effects, alt_m=alt if alt > 0 else 1e-9)
        assert accel(p)[2] == pytest.approx(expected, rel=1e-6, abs=1e-12)
        assert accel(p)[2] < 0.0
    for alt in (2 * radius - height, 0.5, 3.0):
        assert accel(in_air(effects, alt_m=alt))[2] == pytest.approx(0.0, abs=1e-12)
    # closed loop: hovering low needs less rotor thrust than hovering high
    effects = {"ground_effect": {"max_gain": 0.5, "rotor_radius_m": 0.25, "rotor_height_m": 0.0}}
    low = hovering(effects, settle_s=6.0, alt_m=0.25)
    assert 0.1 < -low.state.pos_ned_m[2] < 0.4  # well inside the ground-effect zone
    f = 1 + 0.5 * (1 - -low.state.pos_ned_m[2] / 0.5) ** 2
    assert low.state.thrust_n == pytest.approx(M * G / f, rel=2e-3)
    assert hovering(effects, settle_s=6.0).state.thrust_n == pytest.approx(M * G, rel=1e-3)


def test_motor_lag_sets_the_motor_time_constant():
    cases = ((None, IRIS.motor_time_constant_s), ({"motor_lag": {"tau_s": 0.08}}, 0.08))
    for effects, tau in cases:
        p = in_air(effects)
        coast(p, tau, n_cmd=0.9)
        step = 0.9 - N_HOVER
        assert p.x[ph.MOTORS] - N_HOVER == pytest.approx(step * (1 - math.exp(-1)), rel=1e-6)


def test_thrust_curve_scales_the_thrust_change_per_command_and_keeps_hover():
    gain = 0.8
    for n_cmd in (N_HOVER, 0.85, 0.4):
        p = in_air({"thrust_curve": {"gain": gain}})
        coast(p, 20 * IRIS.motor_time_constant_s, n_cmd=n_cmd)  # settled: e^-20 of the step left
        settled_sq = N_HOVER**2 + gain * (n_cmd**2 - N_HOVER**2)
        assert p.x[ph.MOTORS] ** 2 == pytest.approx(settled_sq, rel=1e-6)
    plain = in_air(None)
    coast(plain, 20 * IRIS.motor_time_constant_s, n_cmd=0.85)
    assert plain.x[ph.MOTORS] == pytest.approx(0.85, rel=1e-6)


def test_command_delay_shifts_the_response_by_the_delay():
    delay = 0.1
    base = hovering(settle_s=3.0)
    late = hovering({"command_delay": {"delay_s": delay}}, settle_s=3.0)
    np.testing.assert_allclose(late.state.vel_ned_mps, base.state.vel_ned_mps, atol=1e-9)
    v_base = np.array([s.vel_ned_mps[0] for s in fly(base, (2.0, 0.0, 0.0), 3.0, period_s=0.02)])
    v_late = np.array([s.vel_ned_mps[0] for s in fly(late, (2.0, 0.0, 0.0), 3.0, period_s=0.02)])
    shift = round(delay / 0.02)
    np.testing.assert_allclose(v_late[:shift], 0.0, atol=1e-6)
    np.testing.assert_allclose(v_late[shift:], v_base[:-shift], atol=1e-6)
    assert v_base[shift] > 0.02  # the undelayed vehicle was already moving


def test_wind_field_pushes_only_where_the_path_crosses_it():
    """Flying north across a jet blowing east (hidden strength and width, seeded), the east
    velocity departs from zero only near the jet's centre line."""
    import numpy as np
    from sim_flying import fly, hovering

    from vehicle_sim.effects import RotorDrag, WindField

    rng = np.random.default_rng(18)
    speed, width = rng.uniform(3.0, 6.0), rng.uniform(1.5, 3.0)
    field = WindField(vel_ned_mps=(0.0, speed, 0.0), center_n_m=12.0, half_width_m=width)
    sim = hovering([RotorDrag(), field], settle_s=4.0)
    states = fly(sim, (2.0, 0.0, 0.0), 12.0)
    north = np.array([s.pos_ned_m[0] for s in states])
    east_vel = np.array([s.vel_ned_mps[1] for s in states])
    far = np.abs(north - 12.0) > 4.0 * width
    near = np.abs(north - 12.0) < width
    assert near.any() and far.any()
    assert np.max(np.abs(east_vel[near])) > 3.0 * np.max(np.abs(east_vel[far & (north < 12.0)]))
